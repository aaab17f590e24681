"""Where a held slide's loads are a function of the pad's phase in one texture period.

Under quasi-static force control the pad's path is kinematic (the held step sets its height,
the arm its speed) and the skin is free of history under full sliding: a step's taxel loads
are a function of the pad's pose against the plate and of the force it holds. Where the
plate repeats with period ``P`` along the slide over everything the pad reaches, the pose at
``x`` and at ``x + P`` are the same problem, so the loads are a function of the phase
``(x - x_ref) mod P`` alone; a flat plate (or a flat stretch) is the limit of one phase.
:func:`phase_plan` finds that stretch of a slide (the *interior*: the pad's centre positions
whose reach lies on the repeating texture), checks the repetition on the plate's own surface
(its height at ``x`` and ``x + P`` over the pad's reach, to :data:`REPEAT_TOL_M`), and says
whether the answer depends on the slide's offset across it. The step floor tabulates the
loads over one period there (:mod:`sim_tactile.sim.step.phase_table`).

This module loads neither MuJoCo nor numba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...cache import memoized
from ...plates.spec import Plate
from ...plates.surface import surface_of

#: Reach beyond the pad's patch [m] within which the plate must repeat for the table to
#: serve: the skin nodes' collider margin (0.5 mm at most) and their radius, with room.
REACH_MARGIN_M = 2e-3
#: Largest height difference [m] between the plate at ``x`` and at ``x + P`` that still
#: counts as a repetition: far below any node's depth (1 nm; the features' positions differ
#: from an exact repetition by round-off, some 1e-18 m).
REPEAT_TOL_M = 1e-9
#: Spacing [m] of the points at which the repetition is checked, at most (finer on fine
#: textures: a tenth of the smallest feature).
CHECK_PITCH_M = 0.1e-3
#: Periods the pad must travel in the interior for a table to pay (a table costs about one
#: period of per-step solves).
MIN_PERIODS = 2.0


@dataclass(frozen=True)
class PhasePlan:
    """The repeating stretch of one slide's plate for its pad (:func:`phase_plan`).

    period_m: the period along the slide [m] (None: the surface is uniform along the slide
        there, one phase).
    x_lo, x_hi: the interior: pad centre positions [m] whose reach lies on the repetition.
    x_ref: the pad centre position of phase 0 [m] (the interior's start).
    y_m: the offset across the slide [m] the table is solved at: 0.0 where the surface under
        the pad does not depend on the offset (ridges across the whole pad, a flat plate),
        else the slide's own.
    """

    period_m: float | None
    x_lo: float
    x_hi: float
    x_ref: float
    y_m: float

    def covers(self, x: float) -> bool:
        """Whether the pad centred at ``x`` lies in the interior."""
        return self.x_lo <= x <= self.x_hi

    def describe(self) -> str:
        where = f"pad centre in [{self.x_lo * 1e3:.4g}, {self.x_hi * 1e3:.4g}] mm"
        if self.period_m is None:
            return f"a uniform stretch ({where})"
        return f"period {self.period_m * 1e3:.4g} mm ({where})"


def phase_plan(
    plate: Plate, patch_m: tuple[float, float], offset_y_m: float, force_control: str
) -> tuple[PhasePlan | None, str]:
    """``(plan, why)``: where a slide of a pad of ``patch_m`` (x, y) [m] at ``offset_y_m``
    over ``plate`` is a function of its phase, or None and why not."""
    if force_control != "quasi-static":
        return None, f"the force is held by {force_control!r} control, not quasi-statically"
    return _plan(plate, (float(patch_m[0]), float(patch_m[1])), float(offset_y_m))


@memoized("phase plans", maxsize=256)
def _plan(plate: Plate, patch: tuple[float, float], offset: float):
    surf = surface_of(plate)
    rx = patch[0] / 2 + REACH_MARGIN_M
    ry = patch[1] / 2 + REACH_MARGIN_M
    uniform = not surf.features and surf.arrays is None  # flat: no feature, no samples
    if uniform:
        lo, hi = -plate.length_m / 2 + rx, plate.length_m / 2 - rx
        period = None
    else:
        period = surf.period_m
        if period is None:
            return None, "the plate has no period along the slide"
        lo, hi = -plate.area_length_m / 2 + rx, plate.area_length_m / 2 - rx
        if hi - lo < MIN_PERIODS * period:
            return None, (
                f"the pad ({patch[0] * 1e3:.3g} mm) wholly on the texture spans "
                f"{max(hi - lo, 0) * 1e3:.3g} mm of travel, under {MIN_PERIODS:g} periods "
                f"({period * 1e3:.3g} mm)"
            )
    scale = surf.feature_scale_m or CHECK_PITCH_M
    step = min(CHECK_PITCH_M, scale / 10)
    y = _grid(offset, ry, step)
    if uniform:
        return PhasePlan(None, lo, hi, lo, 0.0), "flat under the pad"
    if not _repeats(surf, lo, hi, period, rx, y, step):
        return None, (
            f"the plate does not repeat with its period ({period * 1e3:.4g} mm) over the "
            "pad's reach"
        )
    y_free = _offset_free(surf, lo, period, rx, offset, ry, step)
    return PhasePlan(period, lo, hi, lo, 0.0 if y_free else offset), ""


def _grid(x0: float, rx: float, step: float) -> np.ndarray:
    """Points every ``step`` across ``[x0 - rx, x0 + rx]``, at the middles of their cells
    (so that none falls on the reach's end, where a feature's closed edge may sit one
    period on)."""
    n = max(1, int(np.ceil(2 * rx / step)))
    return x0 - rx + (np.arange(n) + 0.5) * (2 * rx / n)


def _repeats(surf, lo, hi, period, rx, y, step) -> bool:
    """Whether the surface over the pad's reach at the interior's start, middle and last
    whole period equals the surface one period further."""
    starts = {lo, lo + math.floor((hi - lo) / period / 2) * period, hi - period}
    for x0 in sorted(starts):
        if x0 < lo - 1e-12 or x0 + period > hi + 1e-12:
            continue
        xs = _grid(x0, rx, step)
        a = surf.height(xs[:, None], y[None, :], near=(x0, rx))
        b = surf.height(xs[:, None] + period, y[None, :], near=(x0 + period, rx))
        if not (np.isfinite(a).all() and np.isfinite(b).all()):
            return False
        if float(np.max(np.abs(a - b))) > REPEAT_TOL_M:
            return False
    return True


def _offset_free(surf, lo, period, rx, offset, ry, step) -> bool:
    """Whether the surface under the pad over one period is the same at the slide's offset
    and at none (ridges across the whole pad): then every offset shares one table."""
    xs = _grid(lo + period / 2, rx + period / 2, step)
    y = _grid(0.0, ry, step)
    a = surf.height(xs[:, None], y[None, :] + offset, near=(lo + period / 2, rx + period))
    b = surf.height(xs[:, None], y[None, :], near=(lo + period / 2, rx + period))
    same_rows = float(np.max(np.abs(a - a[:, :1]))) <= REPEAT_TOL_M
    return bool(same_rows and float(np.max(np.abs(a - b))) <= REPEAT_TOL_M)
