"""``sim-tactile run`` (a benchmark task) and ``ablate`` (a grid sweep over its slides)."""

from __future__ import annotations

import argparse

from ..errors import ConfigError
from ..tables import text_table
from ._common import add_command, emit, log
from .data import add_sensor_config


def _task_options(args: argparse.Namespace) -> dict:
    """The options ``run`` and ``ablate`` share, as their keyword arguments."""
    return {
        "quick": args.quick,
        "data": args.data,
        "classifiers": args.classifiers,
        "repeats": args.repeats,
        "seed": 0 if args.seed is None else args.seed,
        "log": log,
        "store": args.store,
    }


def cmd_run(args: argparse.Namespace) -> int:
    """Run a benchmark task's protocol and write its report; with ``--method``, the user's
    methods beside the built-in rows; with ``--baseline``, exit 1 when a row falls below the
    saved report by more than ``--tolerance`` or is missing."""
    from ..tasks import run_task
    from ..tasks.baseline import check_tolerance, compare_baseline, load_baseline, save_baseline
    from ..tasks.config_task import config_task, is_config_path
    from ..tasks.methods import import_method
    from ..tasks.report import Report

    # everything the user names is checked before anything runs or is written
    tolerance = check_tolerance(args.tolerance)
    methods = {}
    for spec in args.methods or []:
        m = import_method(spec)
        if m.name in methods:
            raise ConfigError(f"--method names {m.name!r} twice")
        methods[m.name] = m
    base = None
    if args.baseline is not None:
        task_id = args.task
        if is_config_path(task_id):
            task_id = config_task(task_id)[0].id
        base = load_baseline(args.baseline, task_id, args.quick)
    report = run_task(
        args.task,
        args.out,
        sensor_config=args.sensor_config,
        methods=methods or None,
        # a configuration file's own seed unless --seed is given (as generate takes it)
        **(_task_options(args) | {"seed": args.seed}),
    )
    if args.save_baseline is not None:
        log(f"baseline written: {save_baseline(report, args.save_baseline)}")
    check = None
    if base is not None:
        check = compare_baseline(report, base, tolerance, str(args.baseline))
        report = {**report, "baseline_check": check.to_json()}
    emit(args, report, lambda: Report.from_json(report).text())
    if check is not None:
        for line in check.table():
            log(line)
        return 1 if check.failed else 0
    return 0


def cmd_ablate(args: argparse.Namespace) -> int:
    """Sweep encoder / neuron / classifier parameters over a task's cached recordings."""
    from ..tasks.ablate import ablate, ablation_rows, parse_sets

    rep = ablate(args.task, parse_sets(args.sets), args.out, **_task_options(args))

    def table() -> str:
        head, rows = ablation_rows(rep)
        return "\n".join(text_table(head, rows) + [f"figure: {f}" for f in rep["figures"]])

    emit(args, rep, table)
    return 0


def _add_task_options(p: argparse.ArgumentParser, quick_help: str) -> None:
    p.add_argument("--quick", action="store_true", help=quick_help)
    p.add_argument("--data", default=None, help="folder of the real data set (*-real tasks)")
    p.add_argument(
        "--classifiers",
        default=None,
        help="comma-separated names (default: the task's; none: no built-in row)",
    )
    p.add_argument("--repeats", type=int, default=None, help="splits per classifier")
    p.add_argument(
        "--seed",
        type=int,
        default=None,
        help="seed of the splits and models (default 0; a configuration file's own seed)",
    )
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument(
        "--store", default=None, help="read the data from a store made by 'generate TASK'"
    )


def add_parsers(sub) -> None:
    rn = add_command(sub, "run", cmd_run, "run a benchmark task's evaluation protocol and report")
    add_sensor_config(rn)
    rn.add_argument(
        "task",
        help="task id, e.g. finger7-v1, biotac20-real-v1, or a configuration file of "
        "'generate' (.toml / .json), scored as its [evaluate] table says",
    )
    _add_task_options(rn, "the task's quick data, fewer epochs and repeats (about a minute)")
    rn.add_argument(
        "--method",
        dest="methods",
        action="append",
        metavar="NAME=module:callable",
        help="score your own method (repeatable): the callable returns an estimator, or an "
        "(encoder, estimator) pair; the module (or a .py file) is imported: this runs its code",
    )
    rn.add_argument(
        "--baseline",
        default=None,
        metavar="REPORT.json",
        help="compare the rows with a saved report; exit 1 when one falls below it by more "
        "than --tolerance or is missing",
    )
    rn.add_argument(
        "--tolerance",
        type=float,
        default=0.02,
        help="how far a row's accuracy may fall below the baseline (default 0.02)",
    )
    rn.add_argument(
        "--save-baseline",
        default=None,
        metavar="PATH",
        help="write this run's report as a baseline",
    )
    ab = add_command(
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
    _add_task_options(ab, "the task's quick data and repeats")
