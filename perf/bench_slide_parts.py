"""Where a data set's slide spends its CPU in a worker: each part's process time, summed over
the slides of a configuration and divided by their number, without a profiler (whose cost
per call outweighs the parts of a small slide).

    python perf/bench_slide_parts.py CONFIG.toml [--slides 50]

The slides run as ``generate``'s worker runs them (:class:`~sim_tactile.slides.jobs.SlideWorker`,
nothing written), twice: the first pass fills the process's memos and the cache
(``SIM_TACTILE_CACHE``, else the default), the second is measured. Each part is a function
of the slide's path wrapped to add up the CPU time spent inside it; ``rest`` is what the
slide spends outside them (the recording, its metadata, the drawn protocol, ...). The parts
of a phase table's slide that are not listed (its table's reads) fall into ``rest`` too.
"""

from __future__ import annotations

import argparse
import functools
import time
from collections import defaultdict

import sim_tactile.sim.slide as slide_module
import sim_tactile.sim.step.tabled as tabled_module
import sim_tactile.slides.jobs as jobs_module
from sim_tactile.cache import default_root
from sim_tactile.slides.config import config_slide_set, load_config

#: (module, function, label): the parts measured.
PARTS = (
    (jobs_module, "slide_key", "the slide's key"),
    (jobs_module, "cached_slide", "the slide cache's look-up"),
    (slide_module, "runner_for", "the runner's set-up (scene, skin, collider, held step)"),
    (slide_module, "_held_press", "the held press"),
    (slide_module, "held_slide", "the held steps, in one compiled call"),
    (slide_module, "micro_loads", "micro-roughness"),
    (slide_module, "sensor_output", "the transducer"),
    (tabled_module, "table_for", "the phase table's key and look-up"),
    (tabled_module, "glide", "the pad's path (MuJoCo's rollout)"),
    (tabled_module, "held_steps", "a table's slide: its steps off the table"),
)


def _wrap(totals: dict, module, name: str, label: str) -> None:
    f = getattr(module, name)

    @functools.wraps(f)
    def timed(*args, **kwargs):
        t = time.process_time()
        try:
            return f(*args, **kwargs)
        finally:
            totals[label] += time.process_time() - t

    setattr(module, name, timed)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config")
    ap.add_argument("--slides", type=int, default=50)
    args = ap.parse_args()
    totals: dict[str, float] = defaultdict(float)
    for module, name, label in PARTS:
        _wrap(totals, module, name, label)
    slide_set, seed, _ = config_slide_set(load_config(args.config))
    jobs = slide_set.jobs(seed)[: args.slides]
    worker = jobs_module.SlideWorker(str(default_root()), write=False)
    for job in jobs:
        worker(job)
    totals.clear()
    t0 = time.process_time()
    for job in jobs:
        worker(job)
    whole = time.process_time() - t0
    n = len(jobs)
    print(f"{args.config}: {n} slides, CPU ms a slide")
    for label, s in totals.items():
        print(f"  {label:56s} {s / n * 1e3:7.2f}")
    print(f"  {'rest':56s} {(whole - sum(totals.values())) / n * 1e3:7.2f}")
    print(f"  {'a slide in the worker':56s} {whole / n * 1e3:7.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
