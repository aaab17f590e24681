"""A simulated task at its own time step and at a finer one: each row's accuracy side by side,
and the simulation's CPU.

    python perf/bench_task_step.py [--task roughness8-v1] [--dt-s 1.25e-4] [--quick]
        [--repeats N] [--json]

The task's slides are simulated twice in this process (one worker) on one fresh artefact
cache, after an untimed run of them at twice ``--dt-s`` has made the plates and skins both
share: once at the step ``auto`` chooses and once with the set's ``dt_s`` (each slide's step
at most that), and each data set is scored by the task's own protocol (its
classifiers, splits and repeats; ``--repeats`` fewer). Printed per row: the accuracy's mean
and SD at each step, and their difference in SDs of the default's. For ``pvdf2`` on
roughness8, whose default step of one a 1 ms sample leaves the vibration it reports 15-81%
off (``perf/bench_vibration.py``), this says what the resolving step changes in the task.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path


def score(spec, quick: bool, repeats, out: Path, log):
    """``(rows, sim_cpu_s)``: the task's report rows on its data, simulated afresh."""
    from sim_tactile.tasks.runner import evaluate_task, load_task

    t = time.process_time()
    loaded = load_task(spec, quick=quick, data=None, classifiers=None, seed=0, log=log)
    sim = time.process_time() - t
    report = evaluate_task(
        spec,
        loaded.ds,
        out,
        quick=quick,
        runs=loaded.runs,
        repeats=repeats,
        seed=0,
        log=log,
        figures=False,
    )
    return report.results, sim


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="roughness8-v1")
    ap.add_argument("--dt-s", type=float, default=1.25e-4, help="the finer step [s]")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeats", type=int, default=None)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    import os

    from sim_tactile.tasks import get_task

    spec = get_task(args.task)
    log = lambda s: None  # noqa: E731
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["SIM_TACTILE_CACHE"] = str(Path(tmp) / "cache")
        os.environ["SIM_TACTILE_WORKERS"] = "1"  # in this process: its CPU is the slides'
        from sim_tactile.tasks.runner import load_task

        warm = replace(spec, get_data=replace(spec.get_data, dt_s=2 * args.dt_s))
        load_task(warm, quick=args.quick, data=None, classifiers=None, seed=0, log=log)
        for name, s in (
            ("default", spec),
            (f"dt {args.dt_s:g} s", replace(spec, get_data=replace(spec.get_data, dt_s=args.dt_s))),
        ):
            rows, sim = score(s, args.quick, args.repeats, Path(tmp) / "out", log)
            out[name] = {"sim_cpu_s": sim, "rows": rows}
    names = list(out)
    table = []
    for a, b in zip(out[names[0]]["rows"], out[names[1]]["rows"], strict=True):
        sd = a.accuracy_std
        table.append(
            {
                "row": f"{a.classifier} {a.label}",
                names[0]: [a.accuracy_mean, a.accuracy_std],
                names[1]: [b.accuracy_mean, b.accuracy_std],
                "delta_sd": (b.accuracy_mean - a.accuracy_mean) / sd if sd else None,
            }
        )
    if args.json:
        sims = {k: v["sim_cpu_s"] for k, v in out.items()}
        json.dump({"task": args.task, "sim_cpu_s": sims, "rows": table}, sys.stdout, indent=1)
        return 0
    for k, v in out.items():
        print(f"{args.task} at {k}: simulated in {v['sim_cpu_s']:.1f} s of CPU")
    for r in table:
        (m0, s0), (m1, s1) = r[names[0]], r[names[1]]
        d = "" if r["delta_sd"] is None else f" ({r['delta_sd']:+.2f} SD)"
        print(f"{r['row']}: {m0:.3f} +- {s0:.3f} -> {m1:.3f} +- {s1:.3f}{d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
