"""Fewer force levels: the line between shared tables at levels further apart, against the
table at the force between them.

    python perf/bench_force_levels.py [--plates TASK:PLATE,...] [--per-octave 4,2,1]

Slides of a set share their tables at force levels (``LEVELS_PER_OCTAVE`` an octave) and
read the line between the two levels either side of their force. For the first slide of
each named plate of a task (its route as ``auto`` takes it in the task's full set, else
``path = "phase-table"``), this solves its table at its own force and at two levels a factor
``2 ** (1 / n)`` apart with the force midway between them, reads both at 800 places over a
period (or the whole stretch of a table along the slide) and prints the relative L2 of the
line against the table at the force itself, and the largest one-taxel difference over the
largest load.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
from dataclasses import replace

import numpy as np

DEFAULT = (
    "textures20-icub60-v2:textures20-long/grating-3.0mm,"
    "textures20-biotac19-v2:textures20-long/grating-3.0mm,"
    "textures20-icub60-v1:textures20/grating-3.0mm-draft30"
)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plates", default=DEFAULT, help="comma-separated TASK:PLATE")
    ap.add_argument("--per-octave", default="4,2,1", help="levels an octave to compare")
    args = ap.parse_args()

    import sim_tactile.tasks.defs  # noqa: F401  (register the tasks)
    from sim_tactile.cache import ArtefactCache
    from sim_tactile.sim import StepOptions
    from sim_tactile.sim.step.tabled import solve_table
    from sim_tactile.tasks import get_task

    with tempfile.TemporaryDirectory() as tmp:
        cache = ArtefactCache(os.environ.get("SIM_TACTILE_CACHE") or tmp)
        for item in args.plates.split(","):
            task, plate = item.split(":", 1)
            slide = next(j for j in get_task(task).get_data.jobs(0) if j.plate.name == plate)
            plan, how = slide.route
            if plan is None:
                slide = replace(slide, options=StepOptions(path="phase-table"))
                plan, how = slide.route
            slide = replace(slide, options=how)
            proto, fid = slide.drawn(), slide.resolved
            tables = {}

            def table(f, slide=slide, proto=proto, fid=fid, plan=plan, tables=tables):
                if f not in tables:
                    tables[f] = solve_table(slide, proto, fid, plan, f, cache)
                return tables[f]

            f0 = proto.force_n
            span = plan.period_m or (plan.x_hi - plan.x_lo)
            xs = plan.x_lo + np.linspace(0.0, span, 800, endpoint=False)
            ref = table(f0).at(xs)[0]
            for per in (int(n) for n in args.per_octave.split(",")):
                r = 2 ** (1 / per)
                lo, hi = f0 / math.sqrt(r), f0 * math.sqrt(r)
                w = (f0 - lo) / (hi - lo)
                got = (1 - w) * table(lo).at(xs)[0] + w * table(hi).at(xs)[0]
                rel = np.linalg.norm(got - ref) / np.linalg.norm(ref)
                big = np.max(np.abs(got - ref)) / np.max(np.abs(ref))
                print(
                    f"{task} {plate}: {per} levels an octave ({(r - 1) * 100:.0f}% apart): "
                    f"rel L2 {rel * 100:.3f}%, largest taxel {big * 100:.3f}%"
                )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
