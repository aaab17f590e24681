"""finger7-v2's node pitch: the taxel loads of one pass at 0.5 and 0.25 mm nodes against
0.14 mm (the finest the finger's 22 x 16 mm patch allows under the 20000-node cap), on the
plates with the smallest features, and the wall time of each. No independent solver serves a
layered curved finger under position control, so this is convergence against our own finer
grid. Prints a markdown table (``docs/finger7_v2.md`` quotes it); ``--figure PATH`` also draws
an outer taxel's stream on bumps-4x4 at each pitch (``docs/img/finger7_v2_pitch.png``).

    python perf/bench_finger7_v2.py [--figure PATH]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.slide import simulate
from sim_tactile.tasks.defs.finger7 import FINGER7_V2_FINGER

PLATES = ("finger7/ridges-4", "finger7/ridges-8", "finger7/bumps-4x4", "finger7/bumps-6x6")
PITCHES_M = (0.5e-3, 0.25e-3, 0.14e-3)
#: the pass (the finger crosses the texture in about 1.25 s; the rest of the 9 s is rest)
PROTO = Protocol(speed_m_s=0.06, force_n=0.05, duration_s=1.3, force_control="position")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figure", default=None, help="where to draw bumps-4x4's outer taxel")
    args = ap.parse_args()
    streams = {}
    print(
        "| plate | 0.5 mm: max / rms | 0.25 mm (default): max / rms | wall 0.5 / 0.25 / 0.14 mm |"
    )
    print("|---|---|---|---|")
    for name in PLATES:
        out, walls = {}, []
        for h in PITCHES_M:
            t = time.perf_counter()
            rec = simulate(
                name, "grid3x3", protocol=PROTO, finger=FINGER7_V2_FINGER, pitch_m=h, ideal=True
            ).recording
            walls.append(time.perf_counter() - t)
            out[h] = rec.data.astype(float)
            streams[name, h] = (rec.times, out[h][:, 0])
        ref = out[PITCHES_M[-1]]
        peak = np.abs(ref).max()
        cells = []
        for h in PITCHES_M[:-1]:
            d = out[h] - ref
            cells.append(
                f"{100 * np.abs(d).max() / peak:.1f}% / {100 * np.sqrt((d**2).mean()) / peak:.1f}%"
            )
        wall = " / ".join(f"{w:.1f} s" for w in walls)
        print(f"| {name} | {cells[0]} | {cells[1]} | {wall} |", flush=True)
    if args.figure:
        _figure(streams, "finger7/bumps-4x4", args.figure)


def _figure(streams: dict, plate: str, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.2))
    for h, ls in zip(PITCHES_M, (":", "-", "--"), strict=True):
        t, y = streams[plate, h]
        ax.plot(t, y, ls, label=f"{h * 1e3:g} mm nodes")
    ax.set_xlim(0.25, 0.9)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("load [N]")
    ax.set_title(f"{plate}: taxel 0 (an outer row), ideal loads, one pass")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=90)


if __name__ == "__main__":
    main()
