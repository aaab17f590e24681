"""The half-space skin's discretisation error against an independent solver (Tamaas).

    python perf/ref_halfspace_tamaas.py [--quick] [--json]

A flat pad (grid3x3's: 12 mm with 2 mm edge fillets, E = 0.3 MPa, nu = 0.5) is pressed with
1 N on a plate at several offsets along the slide. The project's half-space contact solve on
its node grid (the active set of :class:`~sim_tactile.sim.skin.contact.ActiveSet`, the depth of
each node from the plate's height at its centre) is set against Tamaas's FFT boundary-element
solve (Polonsky-Keer) of the same gap on a 0.0625 mm grid over a 40 mm periodic cell
(:mod:`sim_tactile.bench.physics`, which ``bench speed-error`` uses for every scene). Both
read the grid3x3 taxels at the surface and at depths inside the skin (Boussinesq's stress
of each node's or cell's patch, integrated over the taxel); errors are in % of the largest
taxel load of the reference over the offsets, the worst over the offsets. The reference's
peak pressure sits on a ridge's sharp edge, where the pressure is singular: it grows as
Tamaas's grid is refined, so the peak error says how much of that singularity a grid
resolves rather than an error of a converged quantity.

Tamaas is a test extra (``pip install tamaas``), never a runtime dependency.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from sim_tactile.bench.physics import REF_SPACING_M, grid_press, tamaas_press, taxel_loads
from sim_tactile.plates import get_plate
from sim_tactile.sensors import get_sensor

FORCE_N = 1.0
DEPTHS_M = (0.0, 0.5e-3, 1e-3, 2e-3)
SCENES = {
    # plate, pad offsets along the slide [m]: spread over a period, and not multiples of a
    # node pitch (where a node's centre sits on a ridge's edge, its whole patch takes the
    # ridge's height: the error jumps as node centres cross edges while sliding)
    "finger7/ridges-4": (0.1e-3, 1.15e-3, 2.2e-3, 3.3e-3),
    "multilayer3/grating-9": (0.1e-3, 1.1e-3, 2.1e-3, 3.1e-3),
}
#: node grids compared: the default over ridges (0.5 x 2 mm) and square 0.25 mm
NODE_GRIDS = {"default 0.5 x 2 mm": (0.5e-3, 2e-3), "0.25 x 0.25 mm": (0.25e-3, None)}


def compare(plate_name: str, offsets, grids=NODE_GRIDS) -> dict:
    plate = get_plate(plate_name)
    sensor = get_sensor("grid3x3")
    finger, layout = sensor.finger, sensor.layout
    refs, ours = [], {g: [] for g in grids}
    for off in offsets:
        xy, pt, cell, _ = fine = tamaas_press(plate, finger, FORCE_N, off, REF_SPACING_M)
        refs.append(
            {
                "taxels": {d: taxel_loads(*fine, layout, d) for d in DEPTHS_M},
                "area": pt.size * cell**2,
                "peak": pt.max(),
            }
        )
        for g, (px, py) in grids.items():
            xy, p, qx, qy = grid_press(plate, finger, FORCE_N, off, "L1", px, py)
            ours[g].append(
                {
                    "taxels": {d: taxel_loads(xy, p, qx, qy, layout, d) for d in DEPTHS_M},
                    "area": np.count_nonzero(p) * qx * (qy or qx),
                    "peak": p.max(),
                }
            )
    rows = {}
    for g in grids:
        te = {}
        for d in DEPTHS_M:
            # in % of the scene's largest reference taxel load (over every offset)
            scale = max(r["taxels"][d].max() for r in refs)
            te[d] = max(
                float(np.abs(o["taxels"][d] - r["taxels"][d]).max() / scale)
                for o, r in zip(ours[g], refs, strict=True)
            )
        rows[g] = {
            "taxel_err": te,
            "area_err": [
                float(o["area"] / r["area"] - 1) for o, r in zip(ours[g], refs, strict=True)
            ],
            "peak_err": [
                float(o["peak"] / r["peak"] - 1) for o, r in zip(ours[g], refs, strict=True)
            ],
        }
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one scene, two offsets")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    scenes = {"finger7/ridges-4": (0.0, 2.25e-3)} if args.quick else SCENES
    out = {name: compare(name, offs) for name, offs in scenes.items()}
    if args.json:
        print(json.dumps(out, indent=1, default=str))
        return 0
    print(
        "scene                  nodes               taxel load error (% of the largest), worst over offsets     contact area     peak pressure"
    )
    print("                                           surface   0.5 mm    1 mm     2 mm")
    for name, rows in out.items():
        for g, r in rows.items():
            te = r["taxel_err"]
            print(
                f"{name:22s} {g:19s} "
                + " ".join(f"{100 * te[d]:7.1f}%" for d in DEPTHS_M)
                + f"   {100 * min(r['area_err']):+.0f} to {100 * max(r['area_err']):+.0f}%"
                + f"   {100 * min(r['peak_err']):+.0f} to {100 * max(r['peak_err']):+.0f}%"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
