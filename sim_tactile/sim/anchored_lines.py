"""The geometry of the node lattice anchored to the plate's walls (:mod:`.anchored`): its
lines along and across the slide, and which scenes it serves. Kept apart from the solver so
that :mod:`.fidelity` can plan a lattice without importing the contact kernels."""

from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from ..plates import Plate, features
from .clipped import _merge, skin_refusals, wall_lines

#: Lines closer than this to a wall's residue are one line [m].
RESIDUE_M = 1e-9
#: Default period [m] for a plate whose features lie in one column (no texture period).
SOLO_PERIOD_M = 4e-3
#: Shapes of the pad's surface the kernel evaluates (:meth:`Finger.surface`).
_SHAPES = {"flat": 0, "sphere": 1, "ellipsoid": 2}


def period_of(plate: Plate) -> float:
    """The period [m] along the slide over which the lattice repeats: the texture's (its
    features' smallest spacing in x), or :data:`SOLO_PERIOD_M` for a single column."""
    xs = sorted({round(f.x, 9) for f in features(plate)})
    gaps = [b - a for a, b in zip(xs, xs[1:], strict=False)]
    return min(gaps) if gaps else SOLO_PERIOD_M


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
    xs, _ = wall_lines(plate)
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
    _, ys = wall_lines(plate)
    extra = np.concatenate([pos - size / 2, pos + size / 2, ys - y0_m])
    return _merge(by, extra, by[0], by[-1])


def anchored_cells(finger, layout, plate, y0_m, pitch_m, pitch_y_m, wall_m) -> int:
    """About how many cells of the anchored lattice lie under the pad."""
    _, P, base = period_lines(plate, wall_m, pitch_m)
    rows = row_lines(finger, layout, plate, y0_m, pitch_y_m or pitch_m).size - 1
    return round(base.size / P * finger.patch_m[0] * rows)


def anchor_refusals(plate: Plate, layout, level="L1", finger=None, quasi_static=True) -> list[str]:
    """What keeps the anchored lattice from serving this scene (empty when it serves it): a
    plate that is not all boxes, taxels below the surface, a pad shape the depth kernel does
    not know, and the skin's refusals (:func:`~sim_tactile.sim.clipped.skin_refusals`)."""
    why = []
    fs = features(plate) if plate.texture.kind != "roughness" else []
    if not fs or any(f.kind != "box" for f in fs):
        why.append("a plate that is not all boxes (valid: ridges, bumps and bars of boxes)")
    if (layout.depth_m > 0).any():
        why.append(f"taxels below the surface (depth up to {layout.depth_m.max():g} m; valid: 0)")
    if finger is not None and finger.shape not in _SHAPES:
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
