"""The dense solve against the spectral one on the plates a scene solves densely, one row a
plate: what each costs a slide and how far apart their loads are.

    python perf/bench_solver.py --scene textures20-icub60-v1 [--plates P,...]
        [--slides 0,1] [--json]

A skin the pad's lattice couples is solved densely below
``sim_tactile.sim.plan.fidelity.DENSE_MAX_NODES`` nodes and spectrally above it; both solve
the same discrete problem. This runs the task's own slides (``--slides``: their indices
among each plate's slides of the full task, seed 0; the first one of each plate also warms
its set-up and is timed all the same), whole windows, the ideal loads, on every plate of the
scene whose skin is solved densely (``--plates`` names some), four ways: the dense solve
step by step (``path = per-step``, the reference), the spectral solve step by step at the
reference tolerance (``skin_solver = spectral``), at ``solve_tol`` 1e-4, and as ``auto``
loosens it (``solve_every`` 2, ``solve_tol`` 1e-4). Per plate and slide: each one's wall time [s]
(this process, one core; the slide's set-up from a warm cache counted) and the relative L2
of its taxel loads over the slide against the dense one, in percent.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import replace

import numpy as np
from _task_slides import add_arguments, task_slides


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_arguments(ap, slides="0,1")
    args = ap.parse_args()

    from sim_tactile.cache import ArtefactCache
    from sim_tactile.sim import StepOptions, run
    from sim_tactile.sim.plan.options import AUTO_SOLVE_EVERY, AUTO_SOLVE_TOL

    ways = {
        "dense": StepOptions(path="per-step", skin_solver="dense"),
        "spectral": StepOptions(path="per-step", skin_solver="spectral"),
        "spectral, 1e-4": StepOptions(skin_solver="spectral", solve_tol=AUTO_SOLVE_TOL),
        "spectral, loosened": StepOptions(
            skin_solver="spectral", solve_every=AUTO_SOLVE_EVERY, solve_tol=AUTO_SOLVE_TOL
        ),
    }
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cache = ArtefactCache(tmp)
        for plate, k, slide in task_slides(args):
            if slide.spectral or slide.rig is not None or not slide.resolved.coupled:
                continue
            row = {"plate": plate, "slide": k}
            ref = None
            for name, opts in ways.items():
                s = replace(slide, options=opts)
                t0 = time.perf_counter()
                res = run(s, cache)
                wall = time.perf_counter() - t0
                a = res.recording.data.astype(float)
                if ref is None:
                    ref = a
                    row["skin_problem"] = res.recording.meta.get("skin_problem")
                err = float(np.linalg.norm(a - ref) / max(np.linalg.norm(ref), 1e-300))
                row[name] = {"wall_s": round(wall, 3), "rel_l2_pct": round(100 * err, 3)}
            rows.append(row)
            if not args.json:
                cells = "; ".join(
                    f"{n}: {row[n]['wall_s']:.2f} s ({row[n]['rel_l2_pct']:.2f}%)" for n in ways
                )
                print(f"{plate} slide {k} [{row['skin_problem']}]: {cells}", flush=True)
    if args.json:
        print(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
