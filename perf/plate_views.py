"""Print the agreement between the three views of every preset (analytic, STL, collider).

python perf/plate_views.py [--json]
"""

from __future__ import annotations

import argparse
import json
import sys

from sim_tactile.plates import get_plate, preset_names
from sim_tactile.plates.make.verify import compare_views


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    reports = [compare_views(get_plate(n)) for n in preset_names()]
    if args.json:
        print(json.dumps([r.to_json() for r in reports], indent=2))
        return 0
    print(
        f"{'plate':36s} {'counts a/s/c':14s} {'peak [mm]':>9s} {'stl-an':>8s} {'col-an':>8s} {'col-stl':>8s}  [um]   Ra a/s/c [um]"
    )
    for r in reports:
        c = "/".join(str(r.counts[k]) for k in ("analytic", "stl", "collider")) if r.counts else "-"
        d = r.max_diff_m
        ra = (
            ""
            if r.ra_m is None
            else "/".join(f"{r.ra_m[k] * 1e6:.3g}" for k in ("analytic", "stl", "collider"))
        )
        print(
            f"{r.name:36s} {c:14s} {r.peak_m['analytic'] * 1e3:9.4f} {d['stl_vs_analytic'] * 1e6:8.3f} "
            f"{d['collider_vs_analytic'] * 1e6:8.3f} {d.get('collider_vs_stl', float('nan')) * 1e6:8.3f}        {ra}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
