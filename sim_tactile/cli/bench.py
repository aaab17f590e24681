"""``sim-tactile bench speed-error`` and ``bench stability``."""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import _validate as v
from ..errors import ConfigError
from ._common import add_command, emit, finite_json, log, names_arg


def cmd_bench(args: argparse.Namespace) -> int:
    raise ConfigError(
        "bench: give a benchmark: 'sim-tactile bench speed-error [--quick] --out DIR' or "
        "'sim-tactile bench stability'"
    )


def cmd_bench_speed_error(args: argparse.Namespace) -> int:
    """Speed against error of the fidelity levels on each task's scene."""
    from ..bench.pareto import markdown
    from ..bench.speed_error import run_speed_error
    from ..bench.sweep import ALL_SCENES, sweep_for
    from ..sim.plan.fidelity import LEVELS

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {args.out!r} exists and is not a directory")
    if args.duration is not None:
        v.in_range("--duration", args.duration, 0.05, 60.0, unit="s")
    sweep = sweep_for(
        args.quick,
        scenes=names_arg(args.scenes, "--scenes", list(ALL_SCENES)),
        levels=names_arg(args.levels, "--levels", list(LEVELS)),
        duration_s=args.duration,
        physics=not args.no_physics,
    )
    doc = finite_json(run_speed_error(sweep, out, log=log))
    emit(
        args, doc, lambda: markdown(doc) + "\n" + "\n".join(f"figure: {f}" for f in doc["figures"])
    )
    if doc["crashes"]:
        log(f"sim-tactile: error: bench speed-error: {doc['crashes']} configuration(s) crashed")
        return 1
    return 0


def cmd_bench_stability(args: argparse.Namespace) -> int:
    """The hard cases: each must end in a measured result or a named error."""
    from ..bench.stability import run_stability, table
    from ..bench.stability_cases import CASES, case_names

    names = names_arg(args.cases, "--cases", case_names())
    doc = finite_json(run_stability(CASES, names, log=log))
    emit(args, doc, lambda: table(doc))
    if doc["failures"]:
        log(
            f"sim-tactile: error: bench stability: {doc['failures']} case(s) crashed or gave a "
            f"wrong number: {', '.join(doc['failed'])}"
        )
        return 1
    return 0


def cmd_bench_sim_real(args: argparse.Namespace) -> int:
    """Simulated against real streams of the sensors with real data."""
    from ..bench.sim_real import SENSORS, run_sim_real, table

    sensors = names_arg(args.sensors, "--sensors", list(SENSORS)) or list(SENSORS)
    slides = {}
    if args.slides is not None:
        n = v.integer("--slides", args.slides, 2, 50)
        slides = {s: n for s in sensors}
    doc = finite_json(
        run_sim_real(
            args.data,
            args.out,
            sensors=tuple(sensors),
            slides=slides,
            sensor_config=args.sensor_config,
            log=log,
        )
    )
    emit(args, doc, lambda: table(doc) + "\n".join(f"figure: {f}" for f in doc["figures"]))
    return 0


def add_parsers(sub) -> None:
    bn = sub.add_parser(
        "bench",
        help="Run the benchmarks of the simulator: speed against error, simulated against "
        "real streams, and stability.",
        description="Run the benchmarks of the simulator: speed against error of the fidelity "
        "levels, simulated against real streams, and stability.",
    )
    bn.add_argument("--json", dest="bench_json", action="store_true", help=argparse.SUPPRESS)
    bn.set_defaults(func=cmd_bench)
    bsub = bn.add_subparsers(dest="bench_command")
    se = add_command(
        bsub,
        "speed-error",
        cmd_bench_speed_error,
        "Measure the real-time factor against the error (against the finest level, the "
        "physics and the closed forms) of every fidelity level, time step and node pitch on "
        "each task's scene, with a table and a Pareto figure.",
        compiles=True,
    )
    se.add_argument(
        "--quick",
        action="store_true",
        help="Three scenes, fewer settings and short slides (about a minute).",
    )
    se.add_argument("--out", required=True, help="The folder to write the table and figure into.")
    se.add_argument(
        "--scenes",
        default=None,
        help="Comma-separated scenes: each task's (finger7, multilayer3, roughness8, "
        "textures20, textures20-icub) and hertz (default: all but those a task leaves out; "
        "with --quick: finger7, textures20 and hertz).",
    )
    se.add_argument(
        "--levels",
        default=None,
        help="Comma-separated levels to sweep: L0, L1, L2 (default: all).",
    )
    se.add_argument(
        "--duration",
        type=float,
        default=None,
        help="The slide's duration [s] (default: the time to cross the texture; with --quick: "
        "until the probe taxel has crossed a few features).",
    )
    se.add_argument(
        "--no-physics",
        action="store_true",
        help="Leave out the error against physics (static presses against Tamaas's "
        "half-space, a test extra; about 10 s per scene and offset).",
    )
    sr = add_command(
        bsub,
        "sim-real",
        cmd_bench_sim_real,
        "Set simulated against real streams of each sensor with real data: the distributions "
        "of mean, maximum, temporal spread, noise, spectral slope, channel correlation and "
        "class separability, with a table and a figure.",
        compiles=True,
    )
    sr.add_argument("--data", required=True, help="The folder of the real data set.")
    sr.add_argument("--out", required=True, help="The folder to write the figure into.")
    sr.add_argument(
        "--sensors",
        default=None,
        help="Comma-separated sensors: biotac19, icub60 (default: both).",
    )
    sr.add_argument(
        "--slides",
        type=int,
        default=None,
        help="The slides per class, real and simulated (default: 5 for the BioTac, 2 for the "
        "iCub).",
    )
    sr.add_argument(
        "--sensor-config",
        action="append",
        default=None,
        help="A calibration (.toml, or a shipped one by its sensor's name) for one of the "
        "sensors, shown in a column of its own; repeat it for each sensor.",
    )
    st = add_command(
        bsub,
        "stability",
        cmd_bench_stability,
        "Run the hard cases (fast slides, high forces, coarse steps, extreme neuron inputs, "
        "dead taxels, empty spike trains): each must end in a measured result or a named error.",
        compiles=True,
    )
    st.add_argument(
        "--cases", default=None, help="Comma-separated case names (default: all of them)."
    )
