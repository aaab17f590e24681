"""Tables at offset levels: would a plate that repeats across the slide let slides at other
offsets share tables, as slides at other forces share them at force levels?

    python perf/bench_offset_levels.py [--plates textures20-long/boxes-4.5mm,...]
        [--sensor icub60] [--levels 16,32,64] [--offsets 4] [--seed 3]

On a plate whose features repeat across the slide with period ``Py`` (a grid of boxes,
cylinders or hemispheres), the table at offset ``y`` and at ``y + Py`` are the same problem
(printed: their difference). Tables at ``K`` offset levels ``j Py / K`` would then serve
every slide of a plate, each reading the line between the two levels either side of its own
offset. For ``--offsets`` offsets drawn in +-1 mm, this prints the relative L2 (and the largest
taxel difference, relative to the largest load) of that line against the table solved at the
slide's own offset, both read at 400 positions over one period, for each ``K`` in
``--levels``. A table at its own offset is what ``auto`` takes for such a slide today; its own
error against the per-step solve is measured by ``perf/bench_phase.py``.
"""

from __future__ import annotations

import argparse
import tempfile
from dataclasses import replace

import numpy as np

from sim_tactile.cache import ArtefactCache
from sim_tactile.plates import get_plate
from sim_tactile.plates.define.surface import surface_of
from sim_tactile.sim import Protocol, Slide
from sim_tactile.sim.step import tabled


def period_across(plate) -> float:
    """The features' row pitch across the slide [m] (the median spacing of their y)."""
    ys = sorted({round(f.y, 9) for f in surface_of(plate).features})
    if len(ys) < 2:
        raise SystemExit(f"{plate.name}: one row of features: no period across the slide")
    return float(np.median(np.diff(ys)))


def rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def measure(name: str, sensor: str, levels: list[int], offsets: np.ndarray, cache) -> None:
    plate = get_plate(name)
    py = period_across(plate)
    protocol = Protocol(speed_m_s=0.04, force_n=1.0, duration_s=1.5, start="texture")
    slide = Slide(plate, sensor, protocol)
    proto, fid, plan = slide.drawn(), slide.resolved, slide.table_plan()
    if plan is None or plan.period_m is None:
        raise SystemExit(f"{name}: no phase table serves this slide")
    xs = np.linspace(plan.x_ref, plan.x_ref + plan.period_m, 400, endpoint=False)
    tables: dict[float, np.ndarray] = {}

    def loads_at(y: float) -> np.ndarray:
        y = float(y)
        if y not in tables:
            at = replace(proto, offset_y_m=y)
            table = tabled.solve_table(slide, at, fid, replace(plan, y_m=y), proto.force_n, cache)
            tables[y] = table.at(xs)[0]
        return tables[y]

    same = rel(loads_at(0.3e-3 + py), loads_at(0.3e-3))
    print(f"{name} ({sensor}, node pitch {fid.pitch_m * 1e3:.3f} mm, Py {py * 1e3:.3g} mm)")
    print(f"  the table at y and at y + Py: {same:.2g} apart (relative L2)")
    print("  | offset | levels K | spacing | relative L2 | largest taxel |")
    for y in offsets:
        own = loads_at(y)
        for k in levels:
            d = py / k
            j = np.floor(y / d)
            w = y / d - j
            line = (1.0 - w) * loads_at(j * d) + w * loads_at((j + 1) * d)
            top = np.abs(line - own).max() / np.abs(own).max()
            print(
                f"  | {y * 1e3:+.3f} mm | {k} | {d * 1e3:.3f} mm | {100 * rel(line, own):.2f}% "
                f"| {100 * top:.2f}% |"
            )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--plates", default="textures20-long/boxes-4.5mm,textures20-long/cylinders-4.5mm"
    )
    ap.add_argument("--sensor", default="icub60")
    ap.add_argument("--levels", default="16,32,64")
    ap.add_argument("--offsets", type=int, default=4)
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    offsets = np.random.default_rng(args.seed).uniform(-1e-3, 1e-3, args.offsets)
    cache = ArtefactCache(tempfile.mkdtemp(prefix="bench-offset-levels-"))
    for name in args.plates.split(","):
        measure(name, args.sensor, [int(k) for k in args.levels.split(",")], offsets, cache)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
