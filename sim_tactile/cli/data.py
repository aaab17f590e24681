"""``sim-tactile generate`` (a data set into a store) and ``export`` (a store as files)."""

from __future__ import annotations

import argparse

from ..slides.run import BACKENDS
from ._common import add_command, emit, log


def cmd_generate(args: argparse.Namespace) -> int:
    """Simulate a task's (or a configuration file's) slides into a Zarr store."""
    from ..generate import generate

    res = generate(
        args.task,
        args.out,
        workers=args.workers,
        backend=args.backend,
        address=args.address,
        quick=args.quick,
        resume=args.resume,
        seed=args.seed,
        data=args.data,
        progress=not args.json,
        log=log,
        sensor_config=args.sensor_config,
        device=args.device,
    )
    emit(
        args,
        res,
        lambda: generate_line(res),
    )
    return 0


def generate_line(res: dict) -> str:
    """``generate``'s summary for people: where each slide came from (simulated now, the
    slide cache, recorded data, or kept in the store from before)."""
    came = [f"{res['simulated']} simulated now", f"{res['cached']} from the slide cache"]
    if res["copied"]:
        came.append(f"{res['copied']} copied from the recordings")
    came.append(f"{res['reused']} kept")
    if res["regenerated"]:
        came.append(f"{res['regenerated']} corrupt ones redone")
    if res["repaired"]:
        came.append(f"{', '.join(res['repaired'])} written again")
    overhead = f"{100 * res['store_overhead']:.2f}%" if res["store_overhead"] else "-"
    return (
        f"{res['out']}: {res['trials']} slides ({', '.join(came)}) in {res['wall_s']:.1f} s; "
        f"store overhead {overhead}"
    )


def cmd_export(args: argparse.Namespace) -> int:
    """Write a data set as plain files (``--format``: numpy, .npy files and its metadata as
    JSON; parquet, Parquet shards of the task's splits, a dataset card and Croissant
    metadata), built beside ``--out`` and renamed when whole."""
    from .._validate import one_of
    from ..datasets.export import FORMATS

    fmt = one_of("--format", args.format, (*FORMATS, "parquet"))
    if fmt == "parquet":  # it needs the task's splits: a layer above the data sets
        from ..formats.hub import export_parquet

        res = export_parquet(args.store, args.out, part=args.part, log=log)
    else:
        from ..datasets import export

        res = export(args.store, args.out, part=args.part, format=fmt, log=log)
    emit(args, res, lambda: f"{res['slides']} slides -> {res['out']}/")
    return 0


def cmd_calibrate(args: argparse.Namespace) -> int:
    """Fit a sensor model's transducer and imperfections to real recordings of the sensor."""
    from ..calibrate import calibrate

    cal = calibrate(args.sensor, args.data)
    out = cal.write(args.out)
    fit = cal.to_json()
    payload = {
        "sensor": cal.sensor,
        "channels": fit["channels"],
        "n_recordings": cal.n_recordings,
        "counts_per_n": fit["counts_per_n"],
        "noise_std": fit["noise_std"],
        "offset": fit["offset"],
        "drift_per_s": fit["drift_per_s"],
        "out": str(out),
        "quant_step": cal.quant_step,
        "r2": fit["r2"],
        "gain": fit["gain"],
        "force_n": cal.force_n,
        "notes": fit["notes"],
    }

    def text() -> str:
        lines = [f"{cal.sensor}: {cal.n_recordings} recordings, typical force {cal.force_n:g} N"]
        lines.append(
            f"{'channel':8s} {'counts/N':>9s} {'offset':>7s} {'noise':>6s} {'drift/s':>8s} {'r2':>5s}"
        )
        for k, name in enumerate(cal.channels):
            lines.append(
                f"{name:8s} {cal.counts_per_n[k]:9.2f} {cal.offset[k]:7.2f} {cal.noise_std[k]:6.2f} "
                f"{cal.drift_per_s[k]:8.2f} {cal.r2[k]:5.2f}"
            )
        lines += [f"note: {n}" for n in cal.notes] + [f"written: {out}"]
        return "\n".join(lines)

    emit(args, payload, text)
    return 0


def add_sensor_config(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--sensor-config",
        default=None,
        help="A sensor calibration (.toml, from 'sim-tactile calibrate') for the sensor.",
    )


def add_parsers(sub) -> None:
    cb = add_command(
        sub,
        "calibrate",
        cmd_calibrate,
        "Fit a sensor model's gains, offsets, noise, drift and ADC step to real recordings.",
        compiles=True,
    )
    cb.add_argument("sensor", help="The sensor to calibrate: biotac19 or icub60.")
    cb.add_argument("--data", required=True, help="The folder of the sensor's real data set.")
    cb.add_argument("--out", required=True, help="The calibration file to write (.toml).")

    gn = add_command(
        sub,
        "generate",
        cmd_generate,
        "Simulate every slide of a task or of a configuration file into a Zarr store, in "
        "parallel (local processes or Ray), resumably.",
        compiles=True,
    )
    gn.add_argument(
        "task",
        help="A task id (a suite such as textures20-v1 gets one group per part; a real-data task "
        "copies its recordings, with --data) or a configuration file (.toml or .json: plates, "
        "sensor, protocol, randomise, finger, slides_per_plate, seed).",
    )
    gn.add_argument("--out", required=True, help="The store to write, a folder (set.zarr).")
    add_sensor_config(gn)
    gn.add_argument(
        "--workers",
        type=int,
        default=None,
        help="The worker processes (default: every core), or the CPUs of a local Ray instance.",
    )
    gn.add_argument(
        "--backend",
        default="local",
        choices=BACKENDS,
        help="Simulate on local processes (the default) or on Ray.",
    )
    gn.add_argument(
        "--address",
        default=None,
        help="The Ray cluster's address (HOST:PORT, or auto), with --backend ray.",
    )
    gn.add_argument(
        "--device",
        default="cpu",
        choices=("cpu", "cuda"),
        help="Where the phase tables of slides on a spectral skin are solved: cpu (the "
        "default), or cuda, each table's phases at once on a GPU (torch with CUDA; one error "
        "and nothing written where there is none). The slides' keys say which made them.",
    )
    gn.add_argument("--quick", action="store_true", help="Simulate the task's quick slides.")
    gn.add_argument(
        "--resume",
        action="store_true",
        help="Continue an interrupted store of this configuration.",
    )
    gn.add_argument(
        "--seed",
        type=int,
        default=None,
        help="The data set's seed (default 0, or the configuration file's own).",
    )
    gn.add_argument(
        "--data",
        default=None,
        help="The folder of the real data set (the real-data tasks need it).",
    )
    ex = add_command(
        sub,
        "export",
        cmd_export,
        "Write a data set as plain numpy files (.npy and JSON), or as Parquet shards with a "
        "dataset card and Croissant metadata for data hubs.",
    )
    ex.add_argument("store", help="A store that 'sim-tactile generate' wrote.")
    ex.add_argument("--out", required=True, help="The folder to write (new or empty).")
    ex.add_argument(
        "--part", default=None, help="One part of a suite's store (default: all of them)."
    )
    ex.add_argument(
        "--format",
        default="numpy",
        help="The files to write: numpy (the default: .npy arrays and meta.json) or parquet "
        "(Parquet shards of the task's splits, a README.md dataset card and croissant.json; "
        "the [hub] extra); an unknown format writes nothing.",
    )
