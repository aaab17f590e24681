"""``sim-tactile tasks`` (the registered tasks), ``run`` (a benchmark task) and ``ablate``
(a grid sweep over its slides)."""

from __future__ import annotations

import argparse
import re

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


#: The sensors of the tasks that read real recordings (their data are not a slide set).
REAL_SENSORS = {"biotac20-real-v1": "biotac19", "icub20-real-v1": "icub60"}
#: What each task's quick form needs [s]: the CPU time (user + system, the command and its
#: workers) of `sim-tactile run TASK --quick` with the task's own rows (a real-data task with
#: its --data), its slides simulated into an empty slide cache, the kernels compiled.
#: Measured with `python perf/bench_quick.py --tasks all --cold` on 2 cores (AMD EPYC) shared
#: with other jobs (load 6-16, so their wall times were 1.5-5 times these); on 2 free cores a
#: run takes about this, less where both workers simulate. A suite's is its parts'. None:
#: not measured (the real iCub recordings were not at hand).
QUICK_WALL_S: dict[str, float | None] = {
    "finger7-v1": 19.4,
    "finger7-v2": 132.6,
    "multilayer3-v1": 16.0,
    "multilayer3-v2": 29.6,
    "biotac20-real-v1": 80.2,
    "icub20-real-v1": None,
    "roughness8-v1": 17.4,
    "textures20-biotac19-v1": 29.3,
    "textures20-icub60-v1": 76.4,
    "textures20-biotac19-v2": 27.7,
    "textures20-icub60-v2": 51.6,
}


def paper_of(reference: str) -> tuple[str, str]:
    """A task's paper: the title in its reference, and its number among the four papers
    the benchmark reproduces (``"000"`` .. ``"003"``, the tasks' docstrings name them so)."""
    m = re.search(r"\(seed paper (\d{3})\)", reference)
    head = reference[: m.start()] if m else reference
    authors = re.match(r"^(?:[A-Z]\.(?: ?[A-Z]\.)* [\w-]+, )*[A-Z]\.(?: ?[A-Z]\.)* [\w-]+: ", head)
    title = head[authors.end() :] if authors else head
    title = title.split(":")[0].strip().rstrip(",")
    return title, (m[1] if m else "")


def task_summary(task_id: str) -> dict:
    """``{id, paper, sensor, classes, slides}`` of a registered task (a suite: its parts'
    sensors and slides), with its title, quick slides and aliases."""
    from ..datasets.real import N_MATERIALS, N_SLIDES
    from ..slides import SlideSet
    from ..tasks import get_task
    from ..tasks.needs import task_needs
    from ..tasks.registry import successor

    spec = get_task(task_id)
    paper, number = paper_of(spec.reference)
    if spec.parts:
        parts = [task_summary(p) for p in spec.parts]
        sensor = "+".join(p["sensor"] for p in parts)
        classes, slides = parts[0]["classes"], sum(p["slides"] for p in parts)
        quick = sum(p["quick_slides"] for p in parts)
    elif isinstance(spec.get_data, SlideSet):
        ss = spec.get_data
        sensor, classes = str(ss.sensor), len(ss.plates)
        slides = ss.slides * classes
        quick = ss.quick_slides * len(ss.quick_plates or ss.plates)
    else:
        sensor, classes = REAL_SENSORS.get(spec.id, "?"), N_MATERIALS
        slides = quick = N_MATERIALS * N_SLIDES
    return {
        "id": spec.id,
        "paper": paper,
        "paper_number": number,
        "sensor": sensor,
        "classes": classes,
        "slides": slides,
        "quick_slides": quick,
        "title": spec.title,
        "parts": list(spec.parts),
        "needs_data": spec.needs_data_path,
        "needs": task_needs(spec),
        "quick_s": quick_wall_s(spec),
        "aliases": spec.describe()["aliases"],
        "superseded_by": successor(spec.id),
    }


def quick_wall_s(spec) -> float | None:
    """About how long the task's quick form takes [s] (:data:`QUICK_WALL_S`; a suite: its
    parts' sum), None where it was not measured."""
    if spec.parts:
        parts = [QUICK_WALL_S.get(p) for p in spec.parts]
        return None if None in parts else float(sum(parts))
    return QUICK_WALL_S.get(spec.id)


def about(seconds: float | None) -> str:
    """``~40 s``, ``~3 min``; ``?`` where not measured."""
    if seconds is None:
        return "?"
    if seconds < 90:
        return f"~{max(10, round(seconds, -1)):.0f} s"
    return f"~{round(seconds / 60):.0f} min"


def _short(text: str, n: int) -> str:
    return text if len(text) <= n else text[: n - 3].rstrip() + "..."


def cmd_tasks(args: argparse.Namespace) -> int:
    """List the registered benchmark tasks, one line each (``--suite``: a suite's; with
    ``--json`` each says which id supersedes it, ``superseded_by``)."""
    from ..tasks import task_ids
    from ..tasks.registry import suite

    ids = suite(args.suite) if args.suite else task_ids()
    rows = [task_summary(t) for t in ids]
    head = ["id", "paper", "sensor", "classes", "slides", "needs", "quick"]
    table = [
        [
            r["id"],
            _short(r["paper"], 32),
            r["sensor"],
            str(r["classes"]),
            str(r["slides"]),
            ", ".join(r["needs"]) or "-",
            about(r["quick_s"]),
        ]
        for r in rows
    ]
    notes = [
        "",
        "needs: torch, the [learn] extra (or leave the networks out: --classifiers "
        "svm-raw,svm-spike); --data, the real data set's folder.",
        "quick: about how long 'run TASK --quick' takes on 2 free cores (the CPU time it "
        "used, its slides simulated; a first run adds 1.5-2 min of compiling).",
    ]
    emit(args, rows, lambda: "\n".join(text_table(head, table, right=(3, 4)) + notes))
    return 0


def about_arg(values: list[str] | None, methods: dict) -> dict | None:
    """``--about NAME=VERSION[,LINK]`` as ``{name: {version, link}}`` (each name a method's)."""
    if not values:
        return None
    out = {}
    for v in values:
        name, eq, rest = v.partition("=")
        version, _, link = rest.partition(",")
        if not eq or not name or not version.strip():
            raise ConfigError(
                f"--about {v!r} is not valid; valid: NAME=VERSION or NAME=VERSION,LINK"
            )
        if name not in methods:
            raise ConfigError(
                f"--about {v!r}: {name!r} is not a --method; valid: {', '.join(methods) or '(none)'}"
            )
        out[name] = {"version": version.strip(), **({"link": link.strip()} if link.strip() else {})}
    return out


def cmd_run(args: argparse.Namespace) -> int:
    """Run a benchmark task's protocol and write its report; with ``--method``, the user's
    methods beside the built-in rows; with ``--baseline``, exit 1 when a row falls below its
    saved row's 95% interval by more than ``--tolerance`` or is missing."""
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
    about = about_arg(args.about, methods)
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
        export_nir=args.export_nir,
        about=about,
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

    sets = parse_sets(args.sets)
    rep = ablate(args.task, sets, args.out, **_task_options(args))

    def table() -> str:
        head, rows = ablation_rows(rep)
        return "\n".join(text_table(head, rows) + [f"figure: {f}" for f in rep["figures"]])

    emit(args, rep, table)
    return 0


def _add_task_options(p: argparse.ArgumentParser, quick_help: str) -> None:
    p.add_argument("--quick", action="store_true", help=quick_help)
    p.add_argument(
        "--data",
        default=None,
        help="The folder of the real data set (the real-data tasks need it).",
    )
    p.add_argument(
        "--classifiers",
        default=None,
        help="Comma-separated classifier names instead of the task's own; 'none' leaves out "
        "every built-in row.",
    )
    p.add_argument(
        "--repeats", type=int, default=None, help="The number of splits for every classifier."
    )
    p.add_argument(
        "--seed",
        type=int,
        default=None,
        help="The seed of the splits and the models (default 0, or a configuration file's own).",
    )
    p.add_argument("--out", required=True, help="The folder to write the report into.")
    p.add_argument(
        "--store",
        default=None,
        help="Read the data from a store that 'sim-tactile generate TASK' wrote.",
    )


def _set_help() -> str:
    from ..tasks.ablate import PARAM_HELP

    names = "; ".join(f"{k}: {v}" for k, v in PARAM_HELP.items())
    return (
        "A swept parameter and its values; repeat --set for a grid. 'sim-tactile tasks' and "
        f"the manual's task pages say which ones each task uses. The parameters: {names}."
    )


def add_parsers(sub) -> None:
    tk = add_command(
        sub,
        "tasks",
        cmd_tasks,
        "List the registered benchmark tasks, one line each: id, paper, sensor, classes, slides.",
    )
    tk.add_argument(
        "--suite",
        default=None,
        metavar="NAME",
        help="Only the tasks of a named suite: core-v1 lists the ids a paper should report.",
    )
    rn = add_command(
        sub,
        "run",
        cmd_run,
        "Run a benchmark task's evaluation protocol and write its report, its figures and "
        "one result file per row (OUT/results/, for 'sim-tactile check').",
        compiles=True,
    )
    add_sensor_config(rn)
    rn.add_argument(
        "task",
        help="A task id (see 'sim-tactile tasks'), or a configuration file of 'generate' "
        "(.toml or .json) scored as its [evaluate] table says.",
    )
    _add_task_options(
        rn, "Use the task's quick data, with fewer epochs and repeats (about a minute)."
    )
    rn.add_argument(
        "--method",
        dest="methods",
        action="append",
        metavar="NAME=module:callable",
        help="Score your own method; repeat it for several. The callable returns an "
        "estimator or an (encoder, estimator) pair; the module (or a .py file) is imported, "
        "which runs its code.",
    )
    rn.add_argument(
        "--about",
        action="append",
        metavar="NAME=VERSION[,LINK]",
        help="The version (or commit) and a link of a --method, for its result file; repeat "
        "it for several.",
    )
    rn.add_argument(
        "--baseline",
        default=None,
        metavar="REPORT.json",
        help="Compare the rows with a saved report, and exit 1 when one falls below the "
        "lower end of its baseline row's 95%% interval by more than --tolerance, or is missing.",
    )
    rn.add_argument(
        "--tolerance",
        type=float,
        default=0.02,
        help="How far a row's accuracy may fall below its baseline's interval (default 0.02).",
    )
    rn.add_argument(
        "--save-baseline",
        default=None,
        metavar="PATH",
        help="Write this run's report as a baseline for --baseline.",
    )
    rn.add_argument(
        "--export-nir",
        default=None,
        metavar="FILE.nir",
        help="Save the spiking network the run trained (the snn row's last repeat) as a NIR "
        "graph, its outputs named by the task's classes (the nir extra).",
    )
    ab = add_command(
        sub,
        "ablate",
        cmd_ablate,
        "Sweep encoder, neuron and classifier parameters over a task's cached slides, as a grid.",
        compiles=True,
    )
    ab.add_argument("task", help="A task id, for example roughness8-v1.")
    ab.add_argument(
        "--set",
        dest="sets",
        action="append",
        required=True,
        metavar="PARAM=v1,v2",
        help=_set_help,  # called when the help is printed
    )
    _add_task_options(ab, "Use the task's quick data and repeats.")
