"""``solve_every`` against the per-step solve on every plate of a scene, one row a plate.

    python perf/bench_every_plate.py --scene textures20-icub60-v1 [--plates P,...]
        [--slides 0,1] [--settings 2,4] [--json]

``perf/bench_response.py`` gives one figure a scene over a few plates; a plate the choice of
plates misses can be far from it. This runs the task's own slides (``--slides``: their
indices among each plate's slides of the full task, seed 0), whole windows, the ideal
loads, on every plate of the scene whose skin is solved spectrally (with ``--dense``, the
densely solved ones too; ``--plates`` names some), once per step (the reference: ``path =
per-step``) and once per setting (``solve_every = n``, and ``solve_tol = 1e-4`` on a
spectral skin, as ``auto`` takes them), and prints, per plate and slide, the relative
L2 of the taxel loads over the slide against the reference and the largest one-taxel
difference over the largest load, in percent. The setting ``table`` is ``path =
phase-table`` instead (with auto's tolerance on a spectral skin): a rough profile's table
along its whole stretch.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import replace

import numpy as np
from _task_slides import add_arguments, task_slides


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_arguments(ap, slides="0")
    ap.add_argument(
        "--settings", default="2,4", help="comma-separated solve_every values, or table"
    )
    ap.add_argument("--dense", action="store_true", help="the densely solved plates too")
    args = ap.parse_args()

    from sim_tactile.cache import ArtefactCache
    from sim_tactile.sim import StepOptions, run
    from sim_tactile.sim.plan.options import AUTO_SOLVE_TOL

    settings = args.settings.split(",")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cache = ArtefactCache(tmp)
        for plate, k, slide in task_slides(args):
            skin = "spectral" if slide.spectral else "dense"
            if skin == "dense" and not args.dense:
                rows.append({"plate": plate, "slide": k, "skin": skin})
                continue
            ref = run(replace(slide, options=StepOptions(path="per-step")), cache)
            b = ref.recording.data.astype(float)
            row = {"plate": plate, "slide": k, "skin": skin}
            for n in settings:
                tol = {"solve_tol": AUTO_SOLVE_TOL} if skin == "spectral" else {}
                how = {"path": "phase-table"} if n == "table" else {"solve_every": int(n)}
                opts = StepOptions(**how, **tol)
                a = run(replace(slide, options=opts), cache).recording.data.astype(float)
                row[f"every {n}"] = {
                    "rel_l2_pct": round(100 * float(np.linalg.norm(a - b) / np.linalg.norm(b)), 2),
                    "largest_pct": round(100 * float(np.abs(a - b).max() / np.abs(b).max()), 2),
                }
            rows.append(row)
            if not args.json:
                cells = "; ".join(
                    f"{key}: {v['rel_l2_pct']}% ({v['largest_pct']}%)"
                    for key, v in row.items()
                    if key.startswith("every")
                )
                print(f"{plate} slide {k} ({skin}): {cells}", flush=True)
    if args.json:
        print(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
