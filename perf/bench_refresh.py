"""The joint held solve's rebuild schedule: a data set's slides with the dense skin's inverse
rebuilt every ``n`` block updates (and where the drift check asks), for several ``n``, in one
process, alternated round by round.

    python perf/bench_refresh.py CONFIG.toml [--plate hemispheres] [--slides 8]
        [--refresh 100,1000] [--rounds 3]

The slides run as ``generate``'s worker runs them (:class:`~sim_tactile.slides.jobs.SlideWorker`,
nothing written), after one untimed pass of every setting. For each setting: the process CPU
a slide (each round, and their median), the rebuilds a slide, and the recordings against the
first setting's (relative L2 and the largest difference over the largest value). Only held
steps solved jointly (``held_solve = "joint"``, ``auto``'s) take the setting; the reference's
Newton iteration keeps :data:`~sim_tactile.sim.skin.contact.REFRESH`.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import sim_tactile.sim.skin.contact.active_set as active_set
import sim_tactile.sim.step.held as held
import sim_tactile.slides.jobs as jobs_module
from sim_tactile.cache import default_root
from sim_tactile.slides.config import config_slide_set, load_config


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config")
    ap.add_argument("--plate", default="", help="only the plates whose name holds this")
    ap.add_argument("--slides", type=int, default=8)
    ap.add_argument("--refresh", default="100,1000", help="comma-separated update counts")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    ss, seed, _ = config_slide_set(load_config(args.config))
    jobs = [j for j in ss.jobs(seed) if args.plate in j.plate.name][: args.slides]
    settings = [int(s) for s in args.refresh.split(",")]
    now = [settings[0]]
    init = held.CompiledHeldStep.__init__

    def joint_refresh(self, *a, **k):
        init(self, *a, **k)
        if self.joint:
            self.solver.refresh = now[0]

    rebuilds = [0]
    take = active_set.ActiveSet._take

    def counted(self, M, S, updates, rb):
        rebuilds[0] += rb
        take(self, M, S, updates, rb)

    held.CompiledHeldStep.__init__ = joint_refresh
    active_set.ActiveSet._take = counted
    worker = jobs_module.SlideWorker(str(default_root()), write=False)
    for r in settings:
        now[0] = r
        for j in jobs:
            worker(j)
    cpu = {r: [] for r in settings}
    data, built = {}, {}
    for _ in range(args.rounds):
        for r in settings:
            now[0], rebuilds[0] = r, 0
            t0 = time.process_time()
            out = [worker(j) for j in jobs]
            cpu[r].append((time.process_time() - t0) / len(jobs) * 1e3)
            built[r] = rebuilds[0] / len(jobs)
            data[r] = np.concatenate([np.ravel(o.recording.data) for o in out])
    b = data[settings[0]].astype(np.float64)
    print(
        f"{args.config}: {len(jobs)} slides ({args.plate or 'every plate'}), {args.rounds} rounds"
    )
    for r in settings:
        a = data[r].astype(np.float64)
        rows = " ".join(f"{x:.1f}" for x in cpu[r])
        print(
            f"  refresh {r:6d}: {statistics.median(cpu[r]):7.1f} ms a slide ({rows}), "
            f"{built[r]:.1f} rebuilds a slide, against {settings[0]}: rel L2 "
            f"{np.linalg.norm(a - b) / np.linalg.norm(b):.1e}, largest "
            f"{np.abs(a - b).max() / np.abs(b).max():.1e}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
