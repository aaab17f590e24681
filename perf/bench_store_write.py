"""What a data set's store costs a slide to write: ``generate`` into a fresh store with a
fake worker (each slide's samples drawn from its seed, no physics), so that the run is the
store's own work (its creation, each slide's two chunk files, the run's record) and the
command's Python around it.

    python perf/bench_store_write.py [--slides 150] [--rounds 7] [--dir /tmp]

Each round writes the same set twice, alternately: with the samples' chunks keyed as the
store keys them (``datasets.store.SAMPLE_KEYS``: ``c.<slide>.0.0`` in the array's folder)
and keyed Zarr's default way (``c/<slide>/0/0``: two folders a slide), in one process. It
prints each layout's median CPU seconds (user + system: creating a file or a folder is
system time, and on some file systems its largest part) and the difference a slide. The
stores are made under ``--dir`` (default: the system's temporary folder), where a data set
would be written.
"""

from __future__ import annotations

import argparse
import json
import resource
import shutil
import statistics
import tempfile
from pathlib import Path

import numpy as np

from sim_tactile.datasets import store as store_mod
from sim_tactile.generate import generate
from sim_tactile.records import Recording
from sim_tactile.slides import SlideOutcome

#: Zarr's default chunk keys: ``c/<slide>/0/0``
DEFAULT_KEYS = {"name": "default", "configuration": {"separator": "/"}}


def fake_slide(job) -> SlideOutcome:
    """A slide of the job's shape, its samples drawn from its seed (no physics)."""
    taxels = job.sensor.layout.positions
    x = np.random.default_rng(job.seed).normal(size=(job.n_samples(), len(taxels)))
    times = np.arange(len(x)) / job.protocol.rate_hz
    return SlideOutcome(Recording(x.astype(np.float32), times, taxels), (), 0.0, False)


def cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--slides", type=int, default=150, help="slides a plate (two plates)")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--dir", default=None, help="where the stores are made")
    args = ap.parse_args()
    cfg = {
        "name": "store-write",
        "seed": 7,
        "plates": ["finger7/flat", "finger7/ridges-2"],
        "sensor": "grid3x3",
        "slides_per_plate": args.slides,
        "protocol": {"duration_s": 0.2},
    }
    work = Path(tempfile.mkdtemp(prefix="bench-store-", dir=args.dir))
    n = 2 * args.slides
    layouts = {"as the store keys them": store_mod.SAMPLE_KEYS, "c/<slide>/0/0": DEFAULT_KEYS}
    cpu: dict[str, list[float]] = {k: [] for k in layouts}
    try:
        config = work / "set.json"
        config.write_text(json.dumps(cfg))
        for r in range(args.rounds + 1):  # the first round warms up
            for name, keys in layouts.items():
                store_mod.SAMPLE_KEYS = keys
                out = work / "set.zarr"
                t = cpu_s()
                generate(str(config), out, workers=1, progress=False, log=lambda m: None,
                         _worker=fake_slide)  # fmt: skip
                if r:
                    cpu[name].append(cpu_s() - t)
                shutil.rmtree(out)
    finally:
        store_mod.SAMPLE_KEYS = layouts["as the store keys them"]
        shutil.rmtree(work, ignore_errors=True)
    print(f"{n} slides a store, {args.rounds} rounds, CPU seconds (user + system):")
    med = {k: statistics.median(v) for k, v in cpu.items()}
    for name, v in cpu.items():
        print(f"  {name:24s} median {med[name]:.3f} s ({min(v):.3f}-{max(v):.3f})")
    a, b = med["as the store keys them"], med["c/<slide>/0/0"]
    print(f"  difference a slide: {(b - a) / n * 1e3:.2f} ms; ratio {b / a:.2f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
