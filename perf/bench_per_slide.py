"""A slide's own CPU cost in one process, every cache warm: what a slide adds to a large data
set once its plate's tables, scene artefacts and kernels exist.

    python perf/bench_per_slide.py CONFIG.toml [CONFIG.toml ...] [--rounds 2]

Each configuration's slides are simulated once untimed (tables, artefacts, compiled kernels),
then ``--rounds`` times, each slide timed alone (process CPU seconds). Printed per plate: the
median CPU a slide, the slides' simulated seconds, and the real-time factor per core a data
set of many such slides approaches (the command's start-up, a worker's set-up, the store's
writes and the tables left out: ``perf/bench_dataset.py`` counts those). For a side by side
comparison run it with ``PYTHONPATH`` set to each checkout in turn, on its own
``SIM_TACTILE_CACHE``.
"""

from __future__ import annotations

import argparse
import statistics
import time

from sim_tactile.cache import ArtefactCache
from sim_tactile.slides.config import config_slide_set, load_config


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("configs", nargs="+")
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    cache = ArtefactCache.default()
    for path in args.configs:
        slides, seed, name = config_slide_set(load_config(path))
        jobs = slides.jobs(seed)
        for job in jobs:  # untimed: tables, artefacts, kernels
            job.simulate(cache)
        cpu: dict[str, list[float]] = {}
        sim: dict[str, list[float]] = {}
        for _ in range(args.rounds):
            for job in jobs:
                t = time.process_time()
                res = job.simulate(cache)
                cpu.setdefault(job.plate.name, []).append(time.process_time() - t)
                sim.setdefault(job.plate.name, []).append(res.sim_s)
        for plate, ts in cpu.items():
            c, s = statistics.median(ts), statistics.median(sim[plate])
            print(f"{name} {plate}: {c * 1e3:.2f} ms a slide of {s:.3f} s, RTF/core {s / c:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
