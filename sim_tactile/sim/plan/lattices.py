"""The planning geometry of the grids that follow the plate's walls (the plate's
:attr:`~sim_tactile.plates.define.surface.Surface.walls`): which lines cut the
patches of the clipped grid (:mod:`~sim_tactile.sim.skin.clipped`), which lines make the
lattice anchored to the walls (:mod:`~sim_tactile.sim.skin.anchored`), how many cells each
has, and which scenes they serve. The planner (:mod:`.fidelity`) counts cells and asks for
refusals here before a single node exists; the solvers build on the same lines. No MuJoCo
and no compiled kernel here.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import ConfigError
from ...plates.define.spec import Plate
from ...plates.define.surface import surface_of
from ...scene.nodes import SkinGrid

#: Lines closer than this to one already there are not added [m]: a patch thinner than it
#: carries nothing a taxel could tell apart.
MERGE_M = 1e-7
#: Lines closer than this to a wall's residue are one line [m].
RESIDUE_M = 1e-9
#: Default period [m] for a plate whose features lie in one column (no texture period).
SOLO_PERIOD_M = 4e-3
#: Shapes of the pad's surface the anchored lattice's depth kernel evaluates
#: (:meth:`~sim_tactile.sensors.pad.Finger.surface`), by their code in that kernel.
PAD_SHAPE_CODES = {"flat": 0, "sphere": 1, "ellipsoid": 2}


def merge_lines(base: np.ndarray, extra, lo: float, hi: float) -> np.ndarray:
    """``base`` (sorted) with the lines of ``extra`` strictly inside (lo, hi) that are not
    within :data:`MERGE_M` of a line already there."""
    out = list(base)
    for e in sorted(extra):
        if not lo + MERGE_M < e < hi - MERGE_M:
            continue
        i = np.searchsorted(out, e)
        if (i < len(out) and out[i] - e < MERGE_M) or (i > 0 and e - out[i - 1] < MERGE_M):
            continue
        out.insert(i, e)
    return np.array(out)


# ---------------------------------------------------------------- the clipped grid


def static_lines(grid: SkinGrid, layout, plate: Plate, y0_m: float):
    """The clipped grid's static column and row lines [m] in the pad's frame: the lattice's
    own, the taxels' edges, and (rows) the walls along the slide with the pad centred at
    ``y0_m`` on the plate."""
    px, py = grid.pitch_xy
    xs, ys = np.unique(grid.xy[:, 0]), np.unique(grid.xy[:, 1])
    bx = np.append(xs - px / 2, xs[-1] + px / 2)
    by = np.append(ys - py / 2, ys[-1] + py / 2)
    pos, size = layout.positions[:, :2], layout.sizes
    tx = np.concatenate([pos[:, 0] - size[:, 0] / 2, pos[:, 0] + size[:, 0] / 2])
    ty = np.concatenate([pos[:, 1] - size[:, 1] / 2, pos[:, 1] + size[:, 1] / 2])
    _, walls_y = surface_of(plate).walls
    return merge_lines(bx, tx, bx[0], bx[-1]), merge_lines(
        by, np.concatenate([ty, walls_y - y0_m]), by[0], by[-1]
    )


def static_cells(grid: SkinGrid, layout, plate: Plate, y0_m: float) -> int:
    """How many static cells the clipped grid has (:func:`static_lines`)."""
    sx, sy = static_lines(grid, layout, plate, y0_m)
    return (sx.size - 1) * (sy.size - 1)


def skin_refusals(level: str, finger=None, quasi_static: bool = True) -> list[str]:
    """What keeps a held step on the plate's own cells (clipped patches, the anchored lattice)
    from serving this skin: a level other than L1, a layered stack, friction coupled into the
    normal problem, dynamic force control. Empty when it serves it; ``finger`` None skips the
    finger's checks."""
    why = []
    if level != "L1":
        why.append(f"level {level!r} (valid: 'L1')")
    if finger is not None and finger.stack is not None:
        why.append("a layered stack")
    if finger is not None and finger.skin_tractions and finger.friction > 0:
        why.append("the skin's sliding tractions (skin_tractions)")
    if not quasi_static:
        why.append("dynamic force control (valid: 'quasi-static')")
    return why


def check_clippable(level: str, finger, quasi_static: bool = True) -> None:
    """Raise unless clipped patches serve this skin: the elastic half-space of L1, without a
    layered stack or friction coupled into the normal problem, under quasi-static force
    control (the held step)."""
    why = skin_refusals(level, finger, quasi_static)
    if why:
        raise ConfigError(
            "clipped patches serve the half-space skin of L1 under quasi-static force control; "
            "got " + ", ".join(why)
        )


# ---------------------------------------------------------------- the anchored lattice
def period_of(plate: Plate) -> float:
    """The period [m] along the slide over which the lattice repeats: the texture's
    (:attr:`~sim_tactile.plates.define.surface.Surface.period_m`), or :data:`SOLO_PERIOD_M` for a
    single column."""
    return surface_of(plate).period_m or SOLO_PERIOD_M


def graded(length: float, wall_m: float, pitch_m: float) -> list[float]:
    """Interior lines [m from its start] of a gap of ``length`` between two walls: cells of
    ``wall_m`` at each wall, doubling away from it up to ``pitch_m``, and the middle cut into
    equal cells no wider than ``pitch_m``."""
    near, x, h = [], 0.0, wall_m
    while h < pitch_m and x + h < length / 2 - 1e-12:
        x += h
        near.append(x)
        h = min(2 * h, pitch_m)
    e = near[-1] if near else 0.0
    mid = length - 2 * e
    k = max(1, math.ceil(mid / pitch_m - 1e-9))
    inner = [e + mid * i / k for i in range(1, k)]
    return near + inner + [length - v for v in reversed(near)]


def period_lines(plate: Plate, wall_m: float, pitch_m: float) -> tuple[float, float, np.ndarray]:
    """``(anchor, P, base)``: the lattice along the slide. Its lines lie at ``anchor + k P +
    base`` (plate frame) for every integer k; ``base`` (ascending, from 0, below ``P``) holds
    every wall across the slide modulo ``P`` and the graded lines between them."""
    xs, _ = surface_of(plate).walls
    if xs.size == 0:
        raise ConfigError(f"plate {plate.name or plate.hash} has no walls to anchor a lattice to")
    P = period_of(plate)
    anchor = float(xs[0])
    res = np.unique(np.round(np.mod(xs - anchor, P), 12))
    res = res[res < P - RESIDUE_M]
    ends = np.append(res, P)
    base = []
    for a, b in zip(ends[:-1], ends[1:], strict=True):
        base.append(a)
        base.extend(a + v for v in graded(b - a, wall_m, pitch_m))
    return anchor, P, np.array(base)


def row_lines(finger, layout, plate: Plate, y0_m: float, pitch_y_m: float) -> np.ndarray:
    """The lines across the slide [m, pad frame] with the pad centred at ``y0_m``: the uniform
    lattice over the pad's extent, the taxels' edges, and the walls along the slide."""
    ey = finger.patch_m[1]
    ny = 2 * math.ceil(ey / pitch_y_m / 2 - 1e-9) + 1
    by = (np.arange(ny + 1) - ny / 2) * pitch_y_m
    pos, size = layout.positions[:, 1], layout.sizes[:, 1]
    _, ys = surface_of(plate).walls
    extra = np.concatenate([pos - size / 2, pos + size / 2, ys - y0_m])
    return merge_lines(by, extra, by[0], by[-1])


def anchored_cells(finger, layout, plate, y0_m, pitch_m, pitch_y_m, wall_m) -> int:
    """About how many cells of the anchored lattice lie under the pad."""
    _, P, base = period_lines(plate, wall_m, pitch_m)
    rows = row_lines(finger, layout, plate, y0_m, pitch_y_m or pitch_m).size - 1
    return round(base.size / P * finger.patch_m[0] * rows)


def anchor_refusals(plate: Plate, layout, level="L1", finger=None, quasi_static=True) -> list[str]:
    """What keeps the anchored lattice from serving this scene (empty when it serves it): a
    plate that is not all boxes, taxels below the surface, a pad shape the depth kernel does
    not know, and the skin's refusals (:func:`skin_refusals`)."""
    why = []
    if not surface_of(plate).all_boxes:
        why.append("a plate that is not all boxes (valid: ridges, bumps and bars of boxes)")
    if (layout.depth_m > 0).any():
        why.append(f"taxels below the surface (depth up to {layout.depth_m.max():g} m; valid: 0)")
    if finger is not None and finger.shape not in PAD_SHAPE_CODES:
        why.append(f"pad shape {finger.shape!r}")
    return why + skin_refusals(level, finger, quasi_static)


def check_anchorable(plate: Plate, layout, level: str = "L1", finger=None, quasi_static=True):
    """Raise unless the anchored lattice serves this scene: a plate of boxes, taxels at the
    surface, the elastic half-space of L1 under quasi-static force control."""
    why = anchor_refusals(plate, layout, level, finger, quasi_static)
    if why:
        raise ConfigError(
            "the anchored lattice serves box plates, surface taxels and the half-space skin "
            "of L1 under quasi-static force control; got " + ", ".join(why)
        )
