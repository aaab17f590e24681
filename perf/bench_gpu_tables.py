"""A configuration's slides made with their phase tables solved on the CPU and on a GPU
(``StepOptions(device=...)``), side by side in one run on one machine.

    python perf/bench_gpu_tables.py CONFIG.toml [--slides N] [--json]

For each device (``cpu``, then ``cuda`` where torch sees a GPU), a fresh process's state (no
table kept, a fresh cache folder for the tables and slides, the plates' artefacts made
first and untimed) simulates the first ``--slides`` slides of the configuration one after
another, as one worker of ``generate`` does; it reports the simulated seconds, the CPU and
wall seconds of those slides, the real-time factor on the wall clock, and the relative L2 of
the GPU's taxel loads against the CPU's. Only the tables of spectral skins go to the GPU;
the rest of a slide (MuJoCo, a dense skin's tables, the steps read off a table) runs on the
CPU as before. It runs without zarr or CadQuery (a GPU machine with MuJoCo, numba, scipy
and torch).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from dataclasses import replace

import numpy as np


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config")
    ap.add_argument("--slides", type=int, default=None)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    from sim_tactile.cache import ArtefactCache, forget_process_memos
    from sim_tactile.slides.config import config_slide_set, load_config
    from sim_tactile.slides.jobs import simulate_slide

    ss, seed, _ = config_slide_set(load_config(args.config))
    jobs = ss.jobs(seed)[: args.slides]
    devices = ["cpu"]
    try:
        import torch

        if torch.cuda.is_available():
            devices.append("cuda")
    except ImportError:
        pass
    base = tempfile.mkdtemp(prefix="bench-gpu-tables-")
    rows, data = [], {}
    for device in devices:
        forget_process_memos()
        cache = ArtefactCache(f"{base}/{device}")
        for name in dict.fromkeys(j.plate.name for j in jobs):  # the plates' artefacts
            first = next(j for j in jobs if j.plate.name == name)
            simulate_slide(replace(first, options=replace(first.options, path="per-step")), cache)
        forget_process_memos()
        recs, t_cpu, t_wall = [], time.process_time(), time.perf_counter()
        for j in jobs:
            opts = replace(j.options, device=device)
            recs.append(simulate_slide(replace(j, ideal=True, options=opts), cache).recording)
        cpu, wall = time.process_time() - t_cpu, time.perf_counter() - t_wall
        sim = sum(r.meta["sim_s"] for r in recs)
        data[device] = np.concatenate([r.data.astype(float).ravel() for r in recs])
        rows.append(
            {
                "device": device,
                "slides": len(recs),
                "sim_s": round(sim, 2),
                "cpu_s": round(cpu, 2),
                "wall_s": round(wall, 2),
                "rtf_wall": round(sim / wall, 2),
            }
        )
    if "cuda" in data:
        a, b = data["cuda"], data["cpu"]
        rows[-1]["rel_l2_vs_cpu"] = float(np.linalg.norm(a - b) / np.linalg.norm(b))
    print(json.dumps(rows, indent=1) if args.json else "\n".join(map(str, rows)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
