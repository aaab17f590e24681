"""The dense contact solve against the spectral one, on whole slides, by node count.

    python perf/bench_spectral.py [--plate finger7/bumps-3x3] [--sensor grid3x3]
        [--pitches 1.0,0.8,0.6,0.5,0.4,0.3,0.25] [--repeats 3] [--dense-max 2500] [--json]

For each node pitch [mm] the same slide runs with each solver (``StepOptions.skin_solver``),
alternating A B A B, and the table gives the median wall time of the slide loop, its
real-time factor, the set-up time (scene, approach and press; the dense compliance and its
inverse are read from a cache after the first run at each pitch, as when a data set is
made), and the largest
difference between the two recordings relative to their peak. The dense solve's matrices
grow as N^2 and its factorisation as N^3, so it is skipped above ``--dense-max`` nodes.
``DENSE_MAX_NODES`` in ``sim_tactile/sim/skin/models.py`` is set from this table: the node count
above which the spectral slide is the faster.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from sim_tactile.cache import ArtefactCache
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.slide import simulate
from sim_tactile.sim.step.runner import StepOptions


def _run(plate: str, sensor: str, pitch_m: float, solver: str, cache=None):
    t = time.perf_counter()
    res = simulate(
        plate,
        sensor,
        ideal=True,
        pitch_m=pitch_m,
        options=StepOptions(skin_solver=solver),
        cache=cache,
    )
    wall = time.perf_counter() - t
    meta = res.recording.meta
    return res.recording.data.astype(float), meta["slide_wall_s"], wall, res.sim_s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plate", default="finger7/bumps-3x3")
    ap.add_argument("--sensor", default="grid3x3")
    ap.add_argument("--pitches", default="1.0,0.8,0.6,0.5,0.4,0.3,0.25", help="node pitches [mm]")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--dense-max", type=int, default=2500)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    finger = get_sensor(a.sensor).finger
    # a cache of its own, as a worker making a data set has: the dense skin's arrays are
    # computed by the first run at each pitch and read by the others
    cache = ArtefactCache(Path(tempfile.mkdtemp(prefix="bench_spectral_")))
    for s in ("dense", "spectral"):  # compile and warm both paths once
        _run(a.plate, a.sensor, 1e-3, s)
    rows = []
    for mm in (float(x) for x in a.pitches.split(",")):
        pitch = mm * 1e-3
        n = skin_grid(finger, pitch).n
        solvers = ["dense", "spectral"] if n <= a.dense_max else ["spectral"]
        loop = {s: [] for s in solvers}
        total = {s: [] for s in solvers}
        data = {}
        for _ in range(a.repeats):
            for s in solvers:
                data[s], slide_s, wall, sim_s = _run(a.plate, a.sensor, pitch, s, cache)
                loop[s].append(slide_s)
                total[s].append(wall)
        row = {"pitch_mm": mm, "nodes": n, "sim_s": sim_s}
        for s in solvers:
            med = statistics.median(loop[s])
            row[s] = {
                "slide_s": round(med, 3),
                "realtime": round(sim_s / med, 3),
                "setup_s": round(statistics.median(total[s]) - med, 3),
            }
        if len(solvers) == 2:
            peak = np.abs(data["dense"]).max()
            row["max_diff"] = float(np.abs(data["dense"] - data["spectral"]).max() / peak)
            row["ratio"] = round(row["spectral"]["slide_s"] / row["dense"]["slide_s"], 3)
        rows.append(row)
        if not a.json:
            print(_line(row), flush=True)
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
        cwd=Path(__file__).parent,
    ).stdout.strip()
    if a.json:
        print(json.dumps({"plate": a.plate, "sensor": a.sensor, "commit": commit, "rows": rows}))
    else:
        print(f"{a.plate}, {a.sensor}, medians of {a.repeats} alternating runs at {commit}")
    return 0


def _line(row: dict) -> str:
    def part(s):
        r = row.get(s)
        if r is None:
            return f"{s}: -"
        return f"{s}: slide {r['slide_s']:.2f} s ({r['realtime']:.2f}x), setup {r['setup_s']:.2f} s"

    extra = (
        f", spectral / dense {row['ratio']:.2f}, max diff {row['max_diff']:.1e}"
        if "ratio" in row
        else ""
    )
    return (
        f"{row['pitch_mm']:g} mm, {row['nodes']} nodes: {part('dense')}; {part('spectral')}{extra}"
    )


if __name__ == "__main__":
    sys.exit(main())
