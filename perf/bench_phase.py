"""``path = auto`` against the per-step reference on every task scene: the path it takes,
its error and its speed.

    python perf/bench_phase.py [--scenes textures20-icub60-v2,...] [--plates 3]
        [--slides 2] [--duration S] [--json]

For each simulated task (every ``-v1`` and ``-v2``, each sensor of ``textures20``), the
first ``--slides`` slides of ``--plates`` of its plates (spread over its list; its
repeating plates first), their whole windows (``--duration`` shortens them), with the ideal
loads, once with ``path = auto`` and once with ``path = per-step``, in one process with one
artefact cache (plates and skin matrices kept, no slide read from the slide cache; the
phase tables solved afresh for the first slide of each plate and shared by the next, as in
a data set). Per scene it prints the paths ``auto`` took, the relative L2 of the taxel loads
over the slides against the per-step solve, the largest one-taxel difference over the
largest load, and the real-time factor per core of each path (simulated seconds over the
process's CPU seconds for those slides, after an untimed per-step slide of each plate has
set up its scene, skin and kernels; the phase tables are solved within the timed slides).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from dataclasses import replace

import numpy as np


def scene_ids() -> list[str]:
    from sim_tactile.slides import SlideSet
    from sim_tactile.tasks import get_task, task_ids

    return [t for t in task_ids() if isinstance(get_task(t).get_data, SlideSet)]


def pick_plates(ss, n: int) -> list[str]:
    """``n`` plates of a set, the repeating ones first, spread over its list."""
    from sim_tactile.plates import get_plate, surface_of

    names = list(ss.plates)
    periodic = [p for p in names if surface_of(get_plate(p)).period_m is not None]
    rest = [p for p in names if p not in periodic]
    ordered = periodic[:: max(1, len(periodic) // max(1, n))] + rest
    return ordered[:n]


def run_scene(task: str, plates: int, slides: int, duration: float | None, cache) -> dict:
    from sim_tactile.sim import StepOptions
    from sim_tactile.slides.jobs import simulate_slide
    from sim_tactile.tasks import get_task

    ss = get_task(task).get_data
    jobs = ss.jobs(seed=0, quick=False)
    chosen = pick_plates(ss, plates)
    picked = [j for p in chosen for j in [j for j in jobs if j.plate.name == p][:slides]]
    if duration is not None:
        picked = [replace(j, protocol=replace(j.protocol, duration_s=duration)) for j in picked]
    picked = [replace(j, ideal=True) for j in picked]
    out = {"scene": task, "plates": chosen, "slides": len(picked)}
    for p in chosen:  # the set-up a worker pays once a plate (scene, skin, kernels): untimed
        first = next(j for j in picked if j.plate.name == p)
        simulate_slide(replace(first, options=StepOptions(path="per-step")), cache)
    data, cpu, paths, sim = {}, {}, [], 0.0
    for name, opts in (("per-step", StepOptions(path="per-step")), ("auto", StepOptions())):
        recs, t0 = [], time.process_time()
        for j in picked:
            recs.append(simulate_slide(replace(j, options=opts), cache).recording)
        cpu[name] = time.process_time() - t0
        data[name] = np.concatenate([r.data.astype(float).ravel() for r in recs])
        if name == "auto":
            paths = [r.meta["skin_problem"] for r in recs]
            sim = sum(r.meta["sim_s"] for r in recs)
    ref, new = data["per-step"], data["auto"]
    took = sorted({"phase table" if "phase table" in p else "per step" for p in paths})
    out.update(
        path=" + ".join(took),
        rel_l2=float(np.linalg.norm(new - ref) / np.linalg.norm(ref)),
        largest=float(np.abs(new - ref).max() / np.abs(ref).max()),
        sim_s=sim,
        rtf_per_step=sim / cpu["per-step"],
        rtf_auto=sim / cpu["auto"],
        speed_up=cpu["per-step"] / cpu["auto"],
        skin_problems=paths,
    )
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default=None, help="comma-separated task ids (default: all)")
    ap.add_argument("--plates", type=int, default=3)
    ap.add_argument("--slides", type=int, default=2)
    ap.add_argument("--duration", type=float, default=None)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    from sim_tactile.cache import ArtefactCache

    cache = ArtefactCache(tempfile.mkdtemp(prefix="bench-phase-"))
    scenes = args.scenes.split(",") if args.scenes else scene_ids()
    rows = []
    for task in scenes:
        row = run_scene(task, args.plates, args.slides, args.duration, cache)
        rows.append(row)
        if not args.json:
            print(
                f"{task}: {row['path']}; rel L2 {100 * row['rel_l2']:.2f}%, largest taxel "
                f"{100 * row['largest']:.2f}%; RTF per core {row['rtf_per_step']:.2f} -> "
                f"{row['rtf_auto']:.2f} ({row['speed_up']:.1f}x) over {row['slides']} slides, "
                f"{row['sim_s']:.1f} s",
                flush=True,
            )
    if args.json:
        print(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
