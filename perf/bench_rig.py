"""The probe rig (multilayer3-v2): node-pitch convergence, the thin-layer closed form, speed.

For each of the rig's plates, the probe's contact is solved on the face at 0.5, 0.25 and
0.125 mm nodes, and the centre elements' reading lines (both layers) are compared with the
finest: the largest difference along the pass, in % of the finest line's peak. The flat
probe's centre is set against the constrained-modulus stress of the thin bonded stack (the
closed form). Then whole slides at the default pitch are timed (median of 3, each after a
warm-up slide in the process). Prints a markdown table (``docs/probe_rig.md`` quotes it).

    python perf/bench_rig.py
"""

from __future__ import annotations

import time

import numpy as np

from sim_tactile.plates import get_plate
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.plan.rig import ProbeRig
from sim_tactile.sim.rig_sim import probe_contact, probe_grid, reading_lines, simulate_rig

PLATES = ("multilayer3/flat", "multilayer3/grating-9", "multilayer3/hemispheres-6x6")
PITCHES_M = (0.5e-3, 0.25e-3, 0.125e-3)


def lines(plate, skin, layout, pitch):
    grid = probe_grid(plate, pitch)
    p, approach, _ = probe_contact(plate, skin, grid, 5.0)
    pick = [4, 13]  # the centre element of each layer
    u, R = reading_lines(
        grid, p * grid.area_m2, skin, layout.sizes[pick], layout.depth_m[pick], np.zeros(2), 0.03
    )
    return u, R, approach


def main() -> None:
    sensor = get_sensor("multilayer3x3x2")
    skin = sensor.with_paper_stack().finger
    lay = sensor.layout
    print("| plate | layer | 0.5 mm | 0.25 mm (default) |")
    print("|---|---|---|---|")
    for name in PLATES:
        plate = get_plate(name)
        res = {h: lines(plate, skin, lay, h) for h in PITCHES_M}
        u_ref, R_ref, approach = res[PITCHES_M[-1]]
        for j, layer in enumerate(("top, 0.5 mm", "bottom, 2 mm")):
            errs = []
            for h in PITCHES_M[:-1]:
                u, R, _ = res[h]
                on = np.interp(u_ref, u, R[j])
                errs.append(np.abs(on - R_ref[j]).max() / np.abs(R_ref[j]).max())
            print(f"| {name} | {layer} | {100 * errs[0]:.2f}% | {100 * errs[1]:.2f}% |")
        if name.endswith("flat"):
            comp = sum(
                la.thickness_m
                * (1 + la.poisson)
                * (1 - 2 * la.poisson)
                / (la.young_pa * (1 - la.poisson))
                for la in skin.stack.layers
            )
            for h in PITCHES_M:
                u, R, appr = res[h]
                sigma = appr / comp
                at0 = [np.interp(0.0, u, R[j]) / lay.sizes[m].prod() for j, m in enumerate((4, 13))]
                print(
                    f"flat at {h * 1e3:g} mm: centre elements {at0[0]:.1f} / {at0[1]:.1f} Pa, "
                    f"thin-layer closed form {sigma:.1f} Pa "
                    f"({100 * (at0[0] / sigma - 1):+.2f}% / {100 * (at0[1] / sigma - 1):+.2f}%)"
                )
    proto = Protocol(speed_m_s=0.065, force_n=5.0, duration_s=5.0)
    for name in PLATES:
        simulate_rig(name, sensor, rig=ProbeRig(), protocol=proto, finger=skin, seed=0)
        walls = []
        for seed in range(1, 4):
            t = time.perf_counter()
            simulate_rig(name, sensor, rig=ProbeRig(), protocol=proto, finger=skin, seed=seed)
            walls.append(time.perf_counter() - t)
        med = float(np.median(walls))
        print(f"{name}: a 5 s slide in {med:.2f} s (median of 3): {5.0 / med:.1f}x real time")


if __name__ == "__main__":
    main()
