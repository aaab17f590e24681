"""Whole patches, patches clipped at the walls and lattices anchored to them, on finger7's box
plates: speed and error.

    python perf/bench_clipped.py [--plates finger7/bumps-4x4,...] [--rounds 3] [--json]

For each plate, a 2 s slide of the task's sensor (grid3x3, 1 N, 60 mm/s, ideal loads) at
each node grid, the grids taken in turn round after round (A B C A B C ...); medians of the
slide loop's real-time factor (simulated seconds per wall second of the loop) and of the
whole slide's (set-up included, nothing cached). The error against physics is the measured
row of ``sim_tactile/sim/plan/measured_errors.json`` for that grid (``perf/
physics_per_plate.py``), or ``-`` where it was not measured.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from dataclasses import replace

from sim_tactile.plates import get_plate
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.plan import measured_errors
from sim_tactile.sim.plan.fidelity import choose_fidelity
from sim_tactile.sim.slide import simulate
from sim_tactile.tasks import get_task

#: (x pitch [m], y pitch [m] or None, clipped, anchored lattice's wall cells [m] or None)
#: per plate kind
GRIDS = {
    "bumps": [
        (1e-3, None, False, None),
        (1e-3 / 3, None, False, None),
        (1e-3, None, True, None),
        (2e-3, 2e-3, False, 0.5e-3),
        (2e-3, 2e-3, False, 0.25e-3),
    ],
    "ridges": [
        (0.25e-3, 2e-3, False, None),
        (0.125e-3, 1e-3, False, None),
        (0.25e-3, 2e-3, True, None),
        (2e-3, 2e-3, False, 0.5e-3),
        (2e-3, 2e-3, False, 0.25e-3),
    ],
}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--plates", default="finger7/bumps-3x3,finger7/bumps-4x4,finger7/bumps-6x6,finger7/ridges-4"
    )
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    ss = get_task("finger7-v1").get_data
    sensor = get_sensor(ss.sensor)
    proto = replace(ss.protocol.at_rate(sensor.layout.rate_hz), duration_s=2.0)
    rows = []
    for name in args.plates.split(","):
        plate = get_plate(name)
        base = choose_fidelity(plate, sensor.layout, sensor.finger, proto, "L1")
        grids = GRIDS["ridges" if "ridges" in name else "bumps"]
        fids = [
            replace(base, pitch_m=px, pitch_y_m=py, clipped=c, wall_m=w) for px, py, c, w in grids
        ]
        loop = {k: [] for k in range(len(fids))}
        whole = {k: [] for k in range(len(fids))}
        for _ in range(args.rounds):
            for k, fid in enumerate(fids):
                t = time.perf_counter()
                r = simulate(plate, sensor, protocol=proto, fidelity=fid, ideal=True)
                whole[k].append(r.sim_s / (time.perf_counter() - t))
                loop[k].append(r.sim_s / r.recording.meta["slide_wall_s"])
        for k, (px, py, c, w) in enumerate(grids):
            m = measured_errors.expected_error(
                plate, sensor.layout, sensor.finger, proto.force_n, "L1", px, py, c, w
            )
            grid = f"{px * 1e3:.3g}" + ("" if py is None else f" x {py * 1e3:.3g}") + " mm"
            row = {
                "plate": name,
                "grid": grid if w is None else f"{w * 1e3:.3g}/{grid}",
                "clipped": c,
                "anchored": w is not None,
                "error_vs_physics": None if m is None else m.error,
                "loop_rtf": statistics.median(loop[k]),
                "slide_rtf": statistics.median(whole[k]),
            }
            rows.append(row)
            if not args.json:
                err = "-" if m is None else f"{100 * m.error:.1f}%"
                print(
                    f"{name:22s} {row['grid']:>16s} "
                    f"{'anchored' if w is not None else 'clipped' if c else 'whole':8s} "
                    f"{err:>7s}  loop {row['loop_rtf']:6.1f}x  slide {row['slide_rtf']:6.2f}x",
                    flush=True,
                )
    if args.json:
        print(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
