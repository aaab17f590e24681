"""``sim-tactile run`` (a benchmark task) and ``ablate`` (a grid sweep over its slides)."""

from __future__ import annotations

import argparse

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
        "seed": args.seed,
        "log": log,
        "store": args.store,
    }


def cmd_run(args: argparse.Namespace) -> int:
    """Run a benchmark task's protocol and write its report."""
    from ..tasks import run_task
    from ..tasks.report import Report

    report = run_task(args.task, args.out, sensor_config=args.sensor_config, **_task_options(args))
    emit(args, report, lambda: Report.from_json(report).text())
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
        "--classifiers", default=None, help="comma-separated names (default: the task's)"
    )
    p.add_argument("--repeats", type=int, default=None, help="splits per classifier")
    p.add_argument("--seed", type=int, default=0, help="seed of the splits and models")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument(
        "--store", default=None, help="read the data from a store made by 'generate TASK'"
    )


def add_parsers(sub) -> None:
    rn = add_command(sub, "run", cmd_run, "run a benchmark task's evaluation protocol and report")
    add_sensor_config(rn)
    rn.add_argument("task", help="task id, e.g. finger7-v1, biotac20-real-v1")
    _add_task_options(rn, "the task's quick data, fewer epochs and repeats (about a minute)")
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
