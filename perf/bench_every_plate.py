"""``solve_every`` against the per-step solve on every plate of a scene, one row a plate.

    python perf/bench_every_plate.py --scene textures20-icub60-v1 [--plates P,...]
        [--slides 0,1] [--settings 2,4] [--json]

``perf/bench_response.py`` gives one figure a scene over a few plates; a plate the choice of
plates misses can be far from it. This runs the task's own slides (``--slides``: their
indices among each plate's slides of the full task, seed 0), whole windows, the ideal
loads, on every plate of the scene whose skin is solved spectrally (the others are solved
densely, step by step, whatever ``auto`` is told; ``--plates`` names some), once per step
(the reference: ``path = per-step``) and once per setting (``solve_every = n``,
``solve_tol = 1e-4``, as ``auto`` takes them), and prints, per plate and slide, the relative
L2 of the taxel loads over the slide against the reference and the largest one-taxel
difference over the largest load, in percent.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import replace

import numpy as np


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", required=True, help="a simulated task id")
    ap.add_argument("--plates", default=None, help="comma-separated plate names (default: all)")
    ap.add_argument("--slides", default="0", help="comma-separated slide indices per plate")
    ap.add_argument("--settings", default="2,4", help="comma-separated solve_every values")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    from sim_tactile.cache import ArtefactCache
    from sim_tactile.sim import Slide, StepOptions, run
    from sim_tactile.sim.plan.options import AUTO_SOLVE_TOL
    from sim_tactile.tasks import get_task

    jobs = get_task(args.scene).get_data.jobs(seed=0, quick=False)
    names = sorted({j.plate.name for j in jobs})
    if args.plates:
        names = [p for p in args.plates.split(",") if p]
    settings = [int(n) for n in args.settings.split(",")]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cache = ArtefactCache(tmp)
        for plate in names:
            mine = [j for j in jobs if j.plate.name == plate]
            for k in (int(s) for s in args.slides.split(",")):
                job = mine[k]
                slide = Slide(
                    job.plate,
                    job.sensor_def,
                    job.protocol,
                    job.seed,
                    job.fidelity,
                    True,
                    job.finger,
                    job.pitch_m,
                    rig=job.rig,
                )
                if not slide.spectral:
                    rows.append({"plate": plate, "slide": k, "skin": "dense"})
                    continue
                ref = run(replace(slide, options=StepOptions(path="per-step")), cache)
                b = ref.recording.data.astype(float)
                row = {"plate": plate, "slide": k, "skin": "spectral"}
                for n in settings:
                    opts = StepOptions(solve_every=n, solve_tol=AUTO_SOLVE_TOL)
                    a = run(replace(slide, options=opts), cache).recording.data.astype(float)
                    row[f"every {n}"] = {
                        "rel_l2_pct": round(
                            100 * float(np.linalg.norm(a - b) / np.linalg.norm(b)), 2
                        ),
                        "largest_pct": round(100 * float(np.abs(a - b).max() / np.abs(b).max()), 2),
                    }
                rows.append(row)
                if not args.json:
                    cells = "; ".join(
                        f"{key}: {v['rel_l2_pct']}% ({v['largest_pct']}%)"
                        for key, v in row.items()
                        if key.startswith("every")
                    )
                    print(f"{plate} slide {k}: {cells}", flush=True)
    if args.json:
        print(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
