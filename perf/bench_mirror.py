"""Mirrored phase tables against whole-period ones, on every plate of a task: each against
the per-step solve.

    python perf/bench_mirror.py --task textures20-icub60-v2 [--slides 1]

For every plate of the task, its first ``--slides`` slides (whole windows, the ideal loads)
three times: per step (the reference), with ``path = auto`` as it is (half a period solved
and mirrored where :func:`~sim_tactile.sim.step.mirror.mirrored_loads` offers a mirror),
and with ``path = auto`` with the mirror withheld (the whole period solved). Each side in
a fresh artefact cache with the process's memos forgotten, so no side reads another's
tables (a table's key does not say whether it was mirrored: the code is the same). Prints
per plate the relative L2 of the taxel loads over its slides and the largest one-taxel
difference over the largest load, then over all plates.
"""

from __future__ import annotations

import argparse
import tempfile

import numpy as np


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", required=True)
    ap.add_argument("--slides", type=int, default=1)
    args = ap.parse_args()
    from sim_tactile.cache import ArtefactCache, forget_process_memos
    from sim_tactile.sim import Slide, StepOptions, run
    from sim_tactile.sim.step import tabled
    from sim_tactile.tasks import get_task

    ss = get_task(args.task).get_data
    jobs = ss.jobs(seed=0, quick=False)
    offered = tabled.mirror_centre
    sides = {"per step": (StepOptions(path="per-step"), offered)}
    sides["whole period"] = (StepOptions(), lambda *a: None)
    sides["mirrored"] = (StepOptions(), offered)
    every: dict[str, list] = {k: [] for k in sides}
    try:
        for plate in ss.plates:
            picked = [j for j in jobs if j.plate.name == plate][: args.slides]
            got = {}
            for name, (opts, centre) in sides.items():
                tabled.mirror_centre = centre
                forget_process_memos()
                cache = ArtefactCache(tempfile.mkdtemp(prefix="bench-mirror-"))
                recs = [
                    run(
                        Slide(
                            j.plate,
                            j.sensor_def,
                            j.protocol,
                            j.seed,
                            j.fidelity,
                            True,
                            j.finger,
                            j.pitch_m,
                            rig=j.rig,
                            options=opts,
                        ),
                        cache,
                    ).recording
                    for j in picked
                ]
                got[name] = np.concatenate([r.data.astype(float).ravel() for r in recs])
                every[name].append(got[name])
            print(plate, *(_error(got[k], got["per step"], k) for k in list(sides)[1:]), flush=True)
    finally:
        tabled.mirror_centre = offered
    ref = np.concatenate(every["per step"])
    print("all plates", *(_error(np.concatenate(every[k]), ref, k) for k in list(sides)[1:]))
    return 0


def _error(new: np.ndarray, ref: np.ndarray, name: str) -> str:
    rel = np.linalg.norm(new - ref) / max(np.linalg.norm(ref), 1e-300)
    largest = np.abs(new - ref).max() / max(np.abs(ref).max(), 1e-300)
    return f" {name} {100 * rel:.3f}% ({100 * largest:.2f}%)"


if __name__ == "__main__":
    raise SystemExit(main())
