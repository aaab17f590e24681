"""A whole task run with the skin solved less often or less tightly: its wall time and its
accuracies, to put beside the same task run as released.

    python perf/bench_task_solve.py --task textures20-icub60-v2 [--solve-every 4]
        [--solve-tol 1e-4] [--classifiers svm-raw,svm-spike] [--quick] [--out DIR] [--json]

The task's slide set is the released one with ``solve_every`` and ``solve_tol`` set
(:class:`~sim_tactile.sim.StepOptions`), registered under a new id
(``TASK+nN+tolT``) so its slides have keys of their own and nothing of the released task's
cache or stores is read. With neither option set it runs the released task. Set
``SIM_TACTILE_CACHE`` to an empty folder to time the simulation, not the cache.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from dataclasses import replace


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", required=True)
    ap.add_argument("--solve-every", type=int, default=1)
    ap.add_argument("--solve-tol", type=float, default=None)
    ap.add_argument("--classifiers", default=None, help="as run's --classifiers")
    ap.add_argument("--quick", action="store_true", help="the task's quick run")
    ap.add_argument("--out", default=None, help="the report's folder (default: a new one)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    from sim_tactile.sim import StepOptions
    from sim_tactile.tasks import get_task
    from sim_tactile.tasks.registry import register
    from sim_tactile.tasks.runner import run_task

    spec = get_task(args.task)
    task_id = args.task
    if args.solve_every != 1 or args.solve_tol is not None:
        opts = StepOptions(solve_every=args.solve_every, solve_tol=args.solve_tol)
        data = replace(spec.get_data, options=opts)
        task_id = f"{args.task}+n{args.solve_every}+tol{args.solve_tol or 'ref'}"
        register(replace(spec, id=task_id, get_data=data))
    out = args.out or tempfile.mkdtemp(prefix="bench-task-solve-")
    t0 = time.perf_counter()
    report = run_task(task_id, out, quick=args.quick, classifiers=args.classifiers)
    wall = time.perf_counter() - t0
    rows = [
        {
            "classifier": r["classifier"],
            "accuracy_mean": r["accuracy_mean"],
            "accuracy_std": r["accuracy_std"],
        }
        for r in report["results"]
    ]
    result = {"task": task_id, "wall_s": round(wall, 1), "out": out, "rows": rows}
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print(f"{task_id}: {wall:.0f} s; report in {out}")
        for r in rows:
            print(f"  {r['classifier']:12s} {r['accuracy_mean']:.3f} ({r['accuracy_std']:.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
