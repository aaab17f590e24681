"""The ``sim-tactile`` command line: a thin layer over the package.

Every command takes ``--json``: stdout then carries one JSON document and nothing else;
progress and logs go to stderr. A failure exits non-zero with a one-line reason on stderr.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from . import __version__
from .errors import SimTactileError

EXIT_ERROR = 2


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _emit(args: argparse.Namespace, payload: object, text: Callable[[], str]) -> None:
    if args.json:
        json.dump(payload, sys.stdout, indent=2, sort_keys=False)
        sys.stdout.write("\n")
    else:
        print(text())


# ---------------------------------------------------------------- plates
def _plate_rows():
    from .plates import get_plate, preset_names

    for name in preset_names():
        yield get_plate(name)


def cmd_plates_list(args: argparse.Namespace) -> int:
    plates = list(_plate_rows())
    rows = [
        {"name": p.name, "family": p.family, "params": p.params(), "hash": p.hash} for p in plates
    ]

    def text() -> str:
        lines = [f"{'name':36s} {'family':10s} hash"]
        lines += [f"{r['name']:36s} {r['family']:10s} {r['hash']}" for r in rows]
        return "\n".join(lines)

    _emit(args, rows, text)
    return 0


def _build_table(results) -> str:
    lines = [f"{'plate':36s} {'geoms':22s} {'cached':7s} {'wall_s':>7s}  files"]
    for r in results:
        geoms = ",".join(f"{k}:{v}" for k, v in sorted(r.geoms.items()))
        cached = "yes" if all(r.cached.values()) else "no"
        lines.append(
            f"{r.plate.name:36s} {geoms:22s} {cached:7s} {r.wall_s:7.2f}  {r.files['stl'].parent}/{r.plate.slug}.*"
        )
    return "\n".join(lines)


def cmd_plates_build(args: argparse.Namespace) -> int:
    from .errors import ConfigError
    from .plates import build, preset_names

    if args.all == bool(args.name):
        raise ConfigError("plates build: give a plate NAME or --all")
    names = preset_names() if args.all else [args.name]
    results = []
    for n in names:
        r = build(n, args.out)
        _log(
            f"built {n} in {r.wall_s:.2f} s ({'cache hit' if all(r.cached.values()) else 'built'})"
        )
        results.append(r)
    if args.all:
        _emit(args, [r.to_json() for r in results], lambda: _build_table(results))
    else:
        _emit(args, results[0].to_json(), lambda: _build_table(results))
    return 0


# ---------------------------------------------------------------- simulate / press
def cmd_simulate(args: argparse.Namespace) -> int:
    from .errors import ConfigError
    from .sim.plots import plot_heatmap, plot_traces
    from .sim.protocol import Protocol
    from .sim.simulate import simulate

    out = Path(args.out)
    if out.suffix != ".npz":
        raise ConfigError(f"--out {args.out!r} must end in .npz")
    proto = Protocol(
        speed_m_s=args.speed,
        force_n=args.force,
        duration_s=args.duration,
        rate_hz=args.rate,
        force_control=args.force_control,
    )
    res = simulate(
        args.plate,
        args.sensor,
        protocol=proto,
        fidelity=args.fidelity,
        seed=args.seed,
        ideal=args.ideal,
    )
    for w in res.warnings:
        _log(f"warning: {w}")
    _log(f"fidelity: {res.fidelity.reason}")
    rec = res.recording
    _log(f"skin problem solved: {rec.meta['skin_problem']}")
    rec.save(out)
    figs = [
        str(plot_traces(rec, out.with_suffix(".traces.png"))),
        str(plot_heatmap(rec, out.with_suffix(".heatmap.png"))),
    ]
    payload = {
        "out": str(out),
        "n_taxels": rec.n_taxels,
        "n_samples": int(rec.data.shape[0]),
        "rate_hz": rec.rate_hz,
        "sim_s": res.sim_s,
        "wall_s": round(res.wall_s, 4),
        "fidelity": res.fidelity.level,
        "dt_s": res.fidelity.dt_s,
        "warnings": res.warnings,
        "node_pitch_m": res.fidelity.pitch_m,
        "skin_problem": rec.meta["skin_problem"],
        "transducer": rec.meta["transducer"],
        "figures": figs,
    }
    _emit(args, payload, lambda: "\n".join(f"{k}: {v}" for k, v in payload.items()))
    return 0


def cmd_press(args: argparse.Namespace) -> int:
    from .sensors import Finger
    from .sim.press import hertz, press, sphere_pad_size_m

    r = args.radius
    if args.finger == "sphere":
        size = sphere_pad_size_m(r, args.force, args.young / (1 - args.poisson**2))
        finger = Finger(
            shape="sphere",
            radius_m=r,
            size_m=(size, size),
            young_pa=args.young,
            poisson=args.poisson,
            thickness_m=args.thickness,
        )
    else:
        finger = Finger(
            shape="flat",
            size_m=(args.size, args.size),
            young_pa=args.young,
            poisson=args.poisson,
            thickness_m=args.thickness,
        )
    res = press(
        finger, args.force, readout_pitch_m=args.pitch, plate=args.plate, fidelity=args.fidelity
    )
    payload = res.to_json()
    if args.finger == "sphere":
        payload["hertz"] = hertz(r, finger.e_star_pa, args.force)
    _emit(
        args,
        payload,
        lambda: (
            f"total force {res.total_force_n:.4g} N, contact radius "
            f"{res.contact_radius_m * 1e3:.4g} mm, peak {res.peak_pressure_pa / 1e3:.4g} kPa"
        ),
    )
    return 0


# ---------------------------------------------------------------- demo
def cmd_demo(args: argparse.Namespace) -> int:
    """The most complete job that exists so far: build every preset plate, then press and
    slide the soft finger with the 3x3 fabric sensor over the soft-finger paper's 7 plates."""
    from .plates import build, preset_names
    from .sim.plots import plot_traces
    from .sim.simulate import simulate

    out = Path(args.out)
    _log(
        f"sim-tactile demo: building all {len(preset_names())} preset plates into {out}/ "
        "(STL, STEP, MJCF, PNG; cached after the first run)"
    )
    t0 = time.perf_counter()
    results = [build(n, out) for n in preset_names()]
    t_build = time.perf_counter() - t0
    _log("sliding the soft finger (grid3x3, 60 mm/s, 1 N) over the 7 finger7 plates")
    slides = []
    for name in [n for n in preset_names() if n.startswith("finger7/")]:
        res = simulate(name, "grid3x3", seed=0)
        rec = res.recording
        png = plot_traces(rec, out / f"{name.replace('/', '_')}.slide.png")
        slides.append(
            {
                "plate": name,
                "samples": int(rec.data.shape[0]),
                "units": rec.units,
                "mean": float(rec.data.mean()),
                "peak": float(rec.data.max()),
                "rtf": rec.meta["sim_s"] / rec.meta["slide_wall_s"],
                "fidelity": res.fidelity.level,
                "figure": str(png),
            }
        )
    wall = time.perf_counter() - t0
    payload = {
        "what": "built every preset plate; simulated one slide per finger7 plate",
        "out": str(out),
        "plates": [r.to_json() for r in results],
        "slides": slides,
        "wall_s": round(wall, 3),
    }

    def text() -> str:
        lines = [
            f"{len(results)} plates built in {t_build:.1f} s -> {out}/",
            "",
            f"{'slide over':20s} {'samples':>7s} {'mean [V]':>9s} {'peak [V]':>9s} {'RTF':>6s}  figure",
        ]
        lines += [
            f"{r['plate']:20s} {r['samples']:7d} {r['mean']:9.3f} {r['peak']:9.3f} {r['rtf']:6.1f}  {r['figure']}"
            for r in slides
        ]
        lines.append(f"\ndone in {wall:.1f} s")
        return "\n".join(lines)

    _emit(args, payload, text)
    return 0


# ---------------------------------------------------------------- run (benchmark tasks)
def _run_table(report: dict) -> str:
    from .tasks.report import paper_text

    labels = [r.get("label", r["classifier"]) for r in report["results"]]
    w = max(10, *(len(x) for x in labels))
    lines = [f"{report['task']}" + (" (quick)" if report.get("quick") else ""), ""]
    lines.append(f"{'run':{w}s} {'accuracy':>15s} {'paper':>15s}  vs paper")
    for lab, r in zip(labels, report["results"], strict=True):
        paper = paper_text(r["paper"])
        acc = f"{r['accuracy_mean']:.3f} ({r['accuracy_std']:.3f})"
        lines.append(f"{lab:{w}s} {acc:>15s} {paper:>15s}  {r['comparison']['message']}")
    t = report["timing"]
    lines.append(
        f"\nsimulate {t['simulate_s']:.1f} s, encode {t['encode_s']:.1f} s, classify "
        f"{t['classify_s']:.1f} s, wall {t.get('wall_s', 0.0):.1f} s"
    )
    lines += [f"figure: {f}" for f in report["figures"]]
    return "\n".join(lines)


def cmd_run(args: argparse.Namespace) -> int:
    """Run a benchmark task's protocol and write its report."""
    from .tasks import run_task

    report = run_task(
        args.task,
        args.out,
        quick=args.quick,
        data=args.data,
        classifiers=args.classifiers,
        repeats=args.repeats,
        seed=args.seed,
        log=_log,
        store=args.store,
    )
    _emit(args, report, lambda: _run_table(report))
    return 0


def cmd_ablate(args: argparse.Namespace) -> int:
    """Sweep encoder / neuron / classifier parameters over a task's cached recordings."""
    from .tasks.ablate import ablate, parse_sets

    sets = parse_sets(args.sets)
    rep = ablate(
        args.task,
        sets,
        args.out,
        quick=args.quick,
        data=args.data,
        classifiers=args.classifiers,
        repeats=args.repeats,
        seed=args.seed,
        log=_log,
        store=args.store,
    )

    def table() -> str:
        keys = list(rep["sets"])
        lines = [" ".join(f"{k:>8s}" for k in keys) + "  accuracy (SD)   run"]
        for r in rep["rows"]:
            vals = " ".join(f"{r['params'][k]!s:>8s}" for k in keys)
            lines.append(
                f"{vals}  {r['accuracy_mean']:.3f} ({r['accuracy_std']:.3f})  {r['label']}"
            )
        lines += [f"figure: {f}" for f in rep["figures"]]
        return "\n".join(lines)

    _emit(args, rep, table)
    return 0


# ---------------------------------------------------------------- generate / export
def cmd_generate(args: argparse.Namespace) -> int:
    """Simulate a task's (or a configuration file's) slides into a Zarr store."""
    from .generate import generate

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
        log=_log,
    )
    _emit(
        args,
        res,
        lambda: (
            f"{res['out']}: {res['trials']} slides ({res['written']} simulated now, "
            f"{res['reused']} kept, {res['regenerated']} corrupt ones redone) in "
            f"{res['wall_s']:.1f} s; store overhead "
            + (f"{100 * res['store_overhead']:.2f}%" if res["store_overhead"] else "-")
        ),
    )
    return 0


def cmd_export(args: argparse.Namespace) -> int:
    """Write a data set's arrays as plain .npy files and its metadata as JSON."""
    from .datasets import export

    res = export(args.store, args.out, part=args.part)
    _emit(args, res, lambda: f"{res['slides']} slides -> {res['out']}/")
    return 0


# ---------------------------------------------------------------- bench
def _finite_json(obj: object) -> object:
    """The document with non-finite floats as None: stdout must stay valid JSON."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite_json(v) for v in obj]
    return obj


def _names_arg(value: str | None, option: str, valid: Sequence[str]) -> list[str] | None:
    from .errors import ConfigError

    if value is None:
        return None
    names = [n.strip() for n in value.split(",") if n.strip()]
    bad = [n for n in names if n not in valid]
    if bad or not names:
        raise ConfigError(
            f"{option} {value!r}: {bad[0] if bad else 'nothing'} is not valid; valid: "
            f"a comma-separated list of {', '.join(valid)}"
        )
    return names


def cmd_bench(args: argparse.Namespace) -> int:
    from .errors import ConfigError

    raise ConfigError(
        "bench: give a benchmark: 'sim-tactile bench speed-error [--quick] --out DIR' or "
        "'sim-tactile bench stability'"
    )


def cmd_bench_speed_error(args: argparse.Namespace) -> int:
    """Speed against error of the fidelity levels on each task's scene."""
    from . import _validate as v
    from .bench.speed_error import SCENES, markdown, run_speed_error, sweep_for
    from .errors import ConfigError
    from .sim.fidelity import LEVELS

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {args.out!r} exists and is not a directory")
    if args.duration is not None:
        v.in_range("--duration", args.duration, 0.05, 60.0, unit="s")
    sweep = sweep_for(
        args.quick,
        scenes=_names_arg(args.scenes, "--scenes", list(SCENES)),
        levels=_names_arg(args.levels, "--levels", list(LEVELS)),
        duration_s=args.duration,
    )
    doc = _finite_json(run_speed_error(sweep, out, log=_log))
    _emit(
        args, doc, lambda: markdown(doc) + "\n" + "\n".join(f"figure: {f}" for f in doc["figures"])
    )
    if doc["crashes"]:
        _log(f"sim-tactile: error: bench speed-error: {doc['crashes']} configuration(s) crashed")
        return 1
    return 0


def cmd_bench_stability(args: argparse.Namespace) -> int:
    """The hard cases: each must end in a measured result or a named error."""
    from .bench.stability import case_names, run_stability, table

    doc = _finite_json(run_stability(_names_arg(args.cases, "--cases", case_names()), log=_log))
    _emit(args, doc, lambda: table(doc))
    if doc["failures"]:
        _log(
            f"sim-tactile: error: bench stability: {doc['failures']} case(s) crashed or gave a "
            f"wrong number: {', '.join(doc['failed'])}"
        )
        return 1
    return 0


# ---------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="sim-tactile", description=__doc__.splitlines()[0])
    p.add_argument("--version", action="version", version=f"sim-tactile {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    def add(parent, name: str, func, help: str) -> argparse.ArgumentParser:
        sp = parent.add_parser(name, help=help, description=help)
        sp.add_argument("--json", action="store_true", help="print one JSON document on stdout")
        sp.set_defaults(func=func)
        return sp

    plates = sub.add_parser("plates", help="list and build the textured plates")
    psub = plates.add_subparsers(dest="plates_command", required=True)
    add(psub, "list", cmd_plates_list, "list the preset plates")
    b = add(psub, "build", cmd_plates_build, "build a plate's STL, STEP, MJCF and preview PNG")
    b.add_argument("name", nargs="?", help="preset name, e.g. finger7/ridges-4")
    b.add_argument("--all", action="store_true", help="build every preset")
    b.add_argument("--out", required=True, help="output directory")

    sm = add(
        sub, "simulate", cmd_simulate, "press a finger on a plate, slide it, record the taxels"
    )
    sm.add_argument("--plate", required=True, help="preset plate name")
    sm.add_argument(
        "--sensor",
        default="grid3x3",
        help="sensor layout: grid3x3, multilayer3x3x2, biotac19, icub60, pvdf2, or dense-<pitch>mm",
    )
    sm.add_argument("--speed", type=float, default=0.06, help="slide speed [m/s]")
    sm.add_argument("--force", type=float, default=1.0, help="normal force [N]")
    sm.add_argument(
        "--duration",
        type=float,
        default=None,
        help="slide duration [s] (default: cross the texture)",
    )
    sm.add_argument(
        "--rate", type=float, default=None, help="sample rate [Hz] (default: the layout's)"
    )
    sm.add_argument("--fidelity", default="auto", choices=["auto", "L0", "L1", "L2"])
    sm.add_argument(
        "--force-control",
        default="quasi-static",
        choices=["quasi-static", "dynamic"],
        help="hold the force exactly each step (default) or a damped bone mass",
    )
    sm.add_argument("--seed", type=int, default=0)
    sm.add_argument("--ideal", action="store_true", help="record the noise-free normal load [N]")
    sm.add_argument("--out", required=True, help="output .npz")

    pr = add(
        sub, "press", cmd_press, "static indentation of a pad on a plate, read by a dense grid"
    )
    pr.add_argument("--finger", default="sphere", choices=["sphere", "flat"])
    pr.add_argument("--radius", type=float, default=8e-3, help="sphere radius [m]")
    pr.add_argument("--size", type=float, default=12e-3, help="flat pad side [m]")
    pr.add_argument("--young", type=float, default=0.3e6, help="Young's modulus [Pa]")
    pr.add_argument("--poisson", type=float, default=0.5)
    pr.add_argument("--thickness", type=float, default=5e-3, help="skin thickness [m]")
    pr.add_argument("--force", type=float, default=1.0, help="normal force [N]")
    pr.add_argument(
        "--pitch", type=float, default=0.25e-3, help="taxel pitch of the dense grid [m]"
    )
    pr.add_argument("--plate", default="finger7/flat")
    pr.add_argument("--fidelity", default="L1", choices=["L0", "L1"])

    rn = add(sub, "run", cmd_run, "run a benchmark task's evaluation protocol and report")
    rn.add_argument("task", help="task id, e.g. biotac20-real, icub20-real")
    rn.add_argument("--quick", action="store_true", help="fewer epochs and repeats (~1 min)")
    rn.add_argument("--data", default=None, help="folder of the real data set (*-real tasks)")
    rn.add_argument(
        "--classifiers", default=None, help="comma-separated names (default: the task's)"
    )
    rn.add_argument("--repeats", type=int, default=None, help="splits per classifier")
    rn.add_argument("--seed", type=int, default=0, help="seed of the splits and models")
    rn.add_argument("--out", required=True, help="output directory")
    rn.add_argument(
        "--store", default=None, help="read the data from a store made by 'generate TASK'"
    )

    ab = add(
        sub,
        "ablate",
        cmd_ablate,
        "grid sweep of encoder, neuron and classifier parameters over a task's cached slides",
    )
    ab.add_argument("task", help="task id, e.g. roughness8-v1")
    ab.add_argument(
        "--set",
        dest="sets",
        action="append",
        required=True,
        metavar="PARAM=v1,v2",
        help="a swept parameter: gain, max_rate_hz, preset, a, b, c, d, K, q, tau, k, C "
        "(repeat --set for a grid)",
    )
    ab.add_argument("--quick", action="store_true", help="the task's quick data and repeats")
    ab.add_argument("--data", default=None, help="folder of the real data set (*-real tasks)")
    ab.add_argument("--classifiers", default=None, help="comma-separated names")
    ab.add_argument("--repeats", type=int, default=None, help="splits per run")
    ab.add_argument("--seed", type=int, default=0, help="seed of the splits and models")
    ab.add_argument("--out", required=True, help="output directory")
    ab.add_argument(
        "--store", default=None, help="read the data from a store made by 'generate TASK'"
    )

    gn = add(
        sub,
        "generate",
        cmd_generate,
        "simulate every slide of a task or of a configuration file into a Zarr store, in "
        "parallel (local processes or Ray), resumably",
    )
    gn.add_argument(
        "task",
        help="a task id (a suite such as textures20-v1 gets one group per part; a *-real task "
        "copies its recordings, with --data) or a configuration file (.toml / .json: plates, "
        "sensor, protocol, randomise, finger, slides_per_plate, seed)",
    )
    gn.add_argument("--out", required=True, help="the store, a folder (e.g. set.zarr)")
    gn.add_argument(
        "--workers",
        type=int,
        default=None,
        help="worker processes (default: every core), or the CPUs of a local Ray instance",
    )
    gn.add_argument("--backend", default="local", choices=["local", "ray"])
    gn.add_argument(
        "--address", default=None, help="Ray cluster address (HOST:PORT or auto; --backend ray)"
    )
    gn.add_argument("--quick", action="store_true", help="the task's quick slides")
    gn.add_argument(
        "--resume", action="store_true", help="continue an interrupted store of this configuration"
    )
    gn.add_argument(
        "--seed", type=int, default=None, help="data set seed (default: 0, or the file's seed)"
    )
    gn.add_argument("--data", default=None, help="folder of the real data set (*-real tasks)")

    ex = add(sub, "export", cmd_export, "write a data set as plain numpy files (.npy + JSON)")
    ex.add_argument("store", help="a store written by generate")
    ex.add_argument("--out", required=True, help="output folder (new or empty)")
    ex.add_argument("--part", default=None, help="one part of a suite's store (default: all)")

    bn = sub.add_parser(
        "bench",
        help="benchmarks: speed against error, stability",
        description="benchmarks: speed against error of the fidelity levels, stability",
    )
    bn.add_argument("--json", dest="bench_json", action="store_true", help=argparse.SUPPRESS)
    bn.set_defaults(func=cmd_bench)
    bsub = bn.add_subparsers(dest="bench_command")
    se = add(
        bsub,
        "speed-error",
        cmd_bench_speed_error,
        "real-time factor against error (vs the finest level and the closed forms) of every "
        "fidelity level, time step and node pitch on each task's scene; table and Pareto figure",
    )
    se.add_argument(
        "--quick", action="store_true", help="three scenes, fewer settings, short slides (~1 min)"
    )
    se.add_argument("--out", required=True, help="output directory")
    se.add_argument(
        "--scenes",
        default=None,
        help="comma-separated scenes: finger7, multilayer3, textures20, textures20-icub, "
        "roughness8, hertz (default: all but textures20-icub; --quick: finger7, textures20, "
        "hertz)",
    )
    se.add_argument(
        "--levels", default=None, help="comma-separated levels to sweep: L0, L1, L2 (default: all)"
    )
    se.add_argument(
        "--duration",
        type=float,
        default=None,
        help="slide duration [s] (default: cross the texture; --quick: until the probe taxel "
        "has crossed 5 features)",
    )
    st = add(
        bsub,
        "stability",
        cmd_bench_stability,
        "hard cases (fast slides, high forces, coarse steps, extreme neuron inputs, dead taxels, "
        "empty spike trains): each must end in a measured result or a named error",
    )
    st.add_argument("--cases", default=None, help="comma-separated case names (default: all)")

    d = add(sub, "demo", cmd_demo, "run the main demo job")
    d.add_argument("--out", default="demo-out", help="output directory (default: demo-out)")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except SimTactileError as exc:
        _log(f"sim-tactile: error: {exc}")
        return EXIT_ERROR
    except BrokenPipeError:  # e.g. `sim-tactile plates list | head`
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        _log("sim-tactile: interrupted")
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
