"""Quick runs timed as a user types them: the spiking row a newcomer tries first, and each
task's quick form (``sim-tactile tasks`` shows these times).

- default: ``sim-tactile run finger7-v1 --quick --classifiers snn,svm-spike``, the goal of
  issue 45: under 2 minutes on 2 cores, the SNN at 0.6 or more;
- ``--tasks all`` (or a comma-separated list): ``sim-tactile run TASK --quick`` with the
  task's own rows, one task at a time (a real-data task with ``--data``, from
  ``$SIM_TACTILE_DATASETS`` or ../shared/datasets).

Each command runs in a subprocess, timed by its wall time and by the CPU time it and its
workers used (user + system): on a machine shared with other jobs the wall time grows with
their load, and the CPU time bounds what the command needs of 2 cores of its own (its wall
time there is at most that, and about half of it where both workers simulate). The load
average is recorded beside. ``--cold`` gives it an empty slide cache (its slides are
simulated again; the compiled kernels are kept, as after a first run), otherwise the slides
come from the cache an earlier run left. Each is repeated ``--runs`` times.

Usage::

    python perf/bench_quick.py [--tasks all|ID,ID] [--cold] [--runs N] [--json [PATH]]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SNN_ROW = ["finger7-v1", "--classifiers", "snn,svm-spike"]
#: The goals of issue 45 for the spiking row's command.
GOAL_WALL_S = 120.0
GOAL_SNN = 0.6
#: The console script ``sim-tactile``, run with this interpreter.
CLI = "import sys; from sim_tactile.cli import main; sys.exit(main())"
#: Where the real data sets are found (the real-data tasks' --data).
DATA = {
    "biotac20-real-v1": "biotac_slide_20_50",
    "icub20-real-v1": "icub_slide_20_50",
}


def data_root() -> Path:
    """``$SIM_TACTILE_DATASETS`` (as the tests find the data), else ``shared/datasets``
    beside the checkout."""
    env = os.environ.get("SIM_TACTILE_DATASETS")
    return Path(env) if env else Path(__file__).resolve().parents[2] / "shared" / "datasets"


def run_once(args: list[str], cold: bool) -> dict:
    """``sim-tactile run ARGS --quick --json`` in a subprocess: its wall time, timings and
    each row's accuracy and repeats."""
    with tempfile.TemporaryDirectory(prefix="bench-quick-") as tmp:
        env = dict(os.environ)
        if cold:
            env["SIM_TACTILE_CACHE"] = str(Path(tmp) / "cache")
        cmd = [sys.executable, "-c", CLI, "run", *args, "--quick", "--json"]
        cmd += ["--out", str(Path(tmp) / "r")]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        out = subprocess.run(cmd, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if out.returncode != 0:
        return {"command": " ".join(args), "error": out.stderr.strip().splitlines()[-1:]}
    rep = json.loads(out.stdout)
    return {
        "command": "sim-tactile run " + " ".join(args) + " --quick",
        "wall_s": round(wall, 1),
        "cpu_s": round(cpu, 1),
        "load_before": round(load, 1),
        "load_after": round(os.getloadavg()[0], 1),
        "simulate_s": rep["timing"]["simulate_s"],
        "classify_s": rep["timing"]["classify_s"],
        "rows": {
            r["label"]: {
                "mean": r["accuracy_mean"],
                "std": r["accuracy_std"],
                "repeats": r["repeats"],
            }
            for r in rep["results"]
        },
    }


def task_args(task: str) -> list[str]:
    if task in DATA:
        return [task, "--data", str(data_root() / DATA[task])]
    return [task]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default=None, help="all, or a comma-separated list of task ids")
    ap.add_argument("--cold", action="store_true", help="An empty slide cache for each run.")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--json", nargs="?", const="-", default=None)
    args = ap.parse_args()
    if args.tasks is None:
        commands = [SNN_ROW]
    else:
        from sim_tactile.tasks import get_task, task_ids

        ids = [t for t in task_ids() if not get_task(t).parts]
        ids = ids if args.tasks == "all" else args.tasks.split(",")
        commands = [task_args(t) for t in ids]
    runs = []
    for r in (run_once(c, args.cold) for c in commands for _ in range(args.runs)):
        runs.append(r)
        if "error" in r:
            print(f"{r['command']}: failed: {r['error']}", flush=True)
            continue
        rows = "; ".join(
            f"{k} {v['mean']:.3f} ({v['std']:.3f}) x {v['repeats']}" for k, v in r["rows"].items()
        )
        print(
            f"{r['command']}: wall {r['wall_s']:.1f} s (simulate {r['simulate_s']:.1f}, "
            f"classify {r['classify_s']:.1f}), CPU {r['cpu_s']:.1f} s, load "
            f"{r['load_before']:g} -> {r['load_after']:g}; {rows}",
            flush=True,
        )
        if "snn" in r["rows"] and args.tasks is None:
            fast = min(r["wall_s"], r["cpu_s"]) < GOAL_WALL_S
            ok = fast and r["rows"]["snn"]["mean"] >= GOAL_SNN
            print(
                f"goals (wall, or CPU on a shared machine, < {GOAL_WALL_S:g} s; snn >= "
                f"{GOAL_SNN:g}): {'met' if ok else 'MISSED'}"
            )
    doc = {
        "cold_slide_cache": args.cold,
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "runs": runs,
    }
    if args.json == "-":
        print(json.dumps(doc, indent=2))
    elif args.json:
        Path(args.json).write_text(json.dumps(doc, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
