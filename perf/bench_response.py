"""The skin solved at fewer steps than the dynamics (``StepOptions.solve_every``) or to a
looser tolerance (``StepOptions.solve_tol``, the spectral solve's): its error against the
per-step solve at the reference tolerance and its speed, for every task scene whose force is
held quasi-statically.

    python perf/bench_response.py [--scenes finger7-v1,...] [--slides 3]
        [--settings 1,2,4,8,1:1e-4,4:1e-4] [--json]

A setting is ``n`` (``solve_every``) or ``n:tol`` (with ``solve_tol``); the reference, ``1``,
is always measured.

For each scene, one process simulates ``--slides`` of the task's slides (the first slide of
plates spread over the task's list; the same slides for every setting), after one warm-up
slide of each plate that is not counted, with one artefact cache (a data set's steady
state). Each slide records the noise-free taxel loads (``ideal``); for each setting:

- ``rel_l2``: the relative L2 of the taxel loads over the whole slides against the per-step
  solve, ``||a - b|| / ||b||`` over every sample and taxel of all the slides;
- ``max_taxel``: the largest difference of one taxel's load at one sample, over the largest
  load of the reference;
- ``rtf``: simulated seconds over the process's CPU seconds for those slides, and ``speedup``
  against the per-step solve measured in the same process (the settings alternate, A B A B,
  ``--rounds`` times; medians).
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from dataclasses import replace

import numpy as np


def scene_ids() -> list[str]:
    from sim_tactile.slides import SlideSet
    from sim_tactile.tasks import get_task, task_ids

    out = []
    for t in task_ids():
        ss = get_task(t).get_data
        if isinstance(ss, SlideSet) and ss.rig is None:
            if ss.window_protocol().force_control == "quasi-static":
                out.append(t)
    return out


def jobs_of(task_id: str, n: int):
    """The warm-up and the measured slides (as ``perf/bench_throughput.py`` picks them)."""
    from sim_tactile.tasks import get_task

    ss = get_task(task_id).get_data
    jobs = ss.jobs(seed=0, quick=False)
    per = len(jobs) // len(ss.plates)
    picks = sorted({round(i * (len(ss.plates) - 1) / max(1, n - 1)) for i in range(n)})
    return [jobs[p * per + 1] for p in picks], [jobs[p * per] for p in picks]


def run(job, every: int, cache, tol: float | None = None) -> tuple[np.ndarray, float, float]:
    """The slide's ideal loads, its CPU seconds and its simulated seconds."""
    from sim_tactile.sim import StepOptions, simulate

    t0 = time.process_time()
    res = simulate(
        job.plate,
        job.sensor,
        protocol=job.protocol,
        finger=job.finger,
        fidelity=job.fidelity,
        seed=job.seed,
        ideal=True,
        pitch_m=job.pitch_m,
        options=StepOptions(solve_every=every, solve_tol=tol),
        cache=cache,
    )
    return np.asarray(res.recording.data, np.float64), time.process_time() - t0, res.sim_s


def parse_settings(text: str) -> list[tuple[int, float | None]]:
    """``"1,4,1:1e-4"`` -> ``[(1, None), (4, None), (1, 1e-4)]``, the reference first."""
    out = [(1, None)]
    for part in text.split(","):
        every, _, tol = part.partition(":")
        s = (int(every), float(tol) if tol else None)
        if s not in out:
            out.append(s)
    return out


def measure(task_id: str, n: int, everies: list, rounds: int) -> list[dict]:
    from sim_tactile.cache import ArtefactCache

    cache = ArtefactCache(tempfile.mkdtemp(prefix="bench-response-"))
    warm, jobs = jobs_of(task_id, n)
    for job in warm:
        run(replace(job, ideal=True), 1, cache)
    ref = {}
    cpu = {s: [] for s in everies}
    sim = 0.0
    loads = {}
    for _ in range(rounds):
        for e in everies:
            total = 0.0
            for i, job in enumerate(jobs):
                x, c, s = run(job, e[0], cache, e[1])
                total += c
                if e == (1, None):
                    ref[i] = x
                    sim += s / rounds
                loads[e, i] = x
            cpu[e].append(total)
    rows = []
    b = np.concatenate([ref[i].ravel() for i in ref])
    for e in everies:
        a = np.concatenate([loads[e, i].ravel() for i in ref])
        rows.append(
            {
                "scene": task_id,
                "solve_every": e[0],
                "solve_tol": e[1],
                "slides": len(jobs),
                "rel_l2": float(np.linalg.norm(a - b) / np.linalg.norm(b)),
                "max_taxel": float(np.abs(a - b).max() / np.abs(b).max()),
                "rtf": sim / statistics.median(cpu[e]),
                "speedup": statistics.median(
                    r / x for r, x in zip(cpu[1, None], cpu[e], strict=True)
                ),
            }
        )
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default=None, help="comma-separated task ids (default: all)")
    ap.add_argument("--slides", type=int, default=3, help="slides per scene (one per plate)")
    ap.add_argument(
        "--settings",
        "--every",
        default="1,2,4,8",
        help="solve_every values, each optionally :solve_tol",
    )
    ap.add_argument("--rounds", type=int, default=1, help="alternating runs of the settings")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    everies = parse_settings(args.settings)
    scenes = args.scenes.split(",") if args.scenes else scene_ids()
    out = []
    for scene in scenes:
        for row in measure(scene, args.slides, everies, args.rounds):
            out.append(row)
            if not args.json:
                print(
                    f"{row['scene']:28s} every {row['solve_every']:2d} tol "
                    f"{row['solve_tol'] or 1e-10:5.0e}: rel L2 "
                    f"{100 * row['rel_l2']:6.3f}%  max taxel {100 * row['max_taxel']:6.3f}%  "
                    f"RTF {row['rtf']:7.2f}  x{row['speedup']:.2f}",
                    flush=True,
                )
    if args.json:
        print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
