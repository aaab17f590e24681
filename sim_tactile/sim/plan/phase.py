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
from ...plates.define.spec import Plate
from ...plates.define.surface import surface_of
from .protocol import Protocol, SlideWindow

#: Reach beyond the pad's patch [m] within which the plate must repeat for the table to
#: serve: the skin nodes' collider margin (0.5 mm at most), their probes' radius (a quarter
#: of the node pitch) and the lattice's overhang past the patch (at most half a pitch), at
#: auto's coarsest 1 mm pitch.
REACH_MARGIN_M = 1.25e-3
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
#: Force levels per doubling of the force at which shared tables are solved (19% apart): a
#: slide whose force lies between two levels reads the line between their tables
#: (:func:`force_levels`). The loads are nearly linear in the force at a phase: on the iCub's
#: grating-3.0mm, three slides read between levels 4.4%, 9% and 19% apart differ from their
#: table at their own force by at most 0.001%, 0.004% and 0.007% (relative L2), against
#: 0.5-0.6% between that table and the per-step slide.
LEVELS_PER_OCTAVE = 4


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
    span: with no period, the loads are tabulated over the whole interior, a function of
        the pad's position there and not of a phase (a rough profile that does not vary
        across the slide: :func:`~.span.span_plan`); False with no period: a uniform stretch.
    """

    period_m: float | None
    x_lo: float
    x_hi: float
    x_ref: float
    y_m: float
    span: bool = False

    @property
    def uniform(self) -> bool:
        """Whether the stretch is uniform along the slide (no period and no profile): one
        phase."""
        return self.period_m is None and not self.span

    @property
    def units(self) -> tuple[str, str]:
        """What its table holds, one and many: positions along a profile, else phases."""
        return ("position", "positions") if self.span else ("phase", "phases")

    def covers(self, x: float) -> bool:
        """Whether the pad centred at ``x`` lies in the interior."""
        return self.x_lo <= x <= self.x_hi

    def describe(self) -> str:
        where = f"pad centre in [{self.x_lo * 1e3:.4g}, {self.x_hi * 1e3:.4g}] mm"
        if self.span:
            return f"a stretch tabulated along the slide, position by position ({where})"
        if self.period_m is None:
            return f"a uniform stretch ({where})"
        return f"period {self.period_m * 1e3:.4g} mm ({where})"


def force_levels(force_n: float) -> list[tuple[float, float]]:
    """``[(level force [N], weight), ...]``: the one or two shared levels
    ``2 ** (k / LEVELS_PER_OCTAVE)`` N on either side of ``force_n``, weighted by the line
    between them (one level, weight 1, where the force is one): the tables the slides of a set share
    (:mod:`~sim_tactile.sim.step.shared_tables`)."""
    t = math.log2(force_n) * LEVELS_PER_OCTAVE
    k = math.floor(t)
    lo = 2.0 ** (k / LEVELS_PER_OCTAVE)
    if lo == force_n:
        return [(lo, 1.0)]
    hi = 2.0 ** ((k + 1) / LEVELS_PER_OCTAVE)
    w = (force_n - lo) / (hi - lo)
    return [(lo, 1.0 - w), (hi, w)]


def tables_shared(plan: PhasePlan, nominal: Protocol) -> bool:
    """Whether the slides of a set drawn from ``nominal`` share their tables at force levels
    (:func:`force_levels`): their force varies from slide
    to slide, and the table does not depend on their offset (it does not, or the offset does
    not vary); else each slide's table is solved at its own force, as on a uniform stretch,
    whose table is one solve."""
    if plan.uniform:
        return False
    offset_free = plan.y_m == 0.0 or nominal.offset_jitter_m == 0.0
    return nominal.force_jitter > 0.0 and offset_free


def table_pays(plan: PhasePlan, nominal: Protocol) -> bool:
    """Whether a table pays for a slide whose window lies on the repeating texture for part
    of its travel only, whatever its skin's step costs: the table is one solve (a uniform
    stretch), or the set's slides share it (:func:`tables_shared`: a few tables a plate, each
    some tens of solves, against hundreds of steps of every slide)."""
    return plan.uniform or tables_shared(plan, nominal)


def travel(window: SlideWindow, proto: Protocol) -> tuple[float, float]:
    """The pad centre's x range [m] over ``window`` at ``proto``'s speed (an upper bound of
    its travel: the ramp at each stroke's start only shortens it)."""
    reach = proto.speed_m_s * (window.n_samples + 1) / proto.rate_hz
    if len(window.strokes) == 1:
        sign = window.strokes[0][2]
        end = window.x_start_m + sign * min(reach, abs(window.x_limit_m - window.x_start_m))
        return min(window.x_start_m, end), max(window.x_start_m, end)
    xs = [window.x_start_m, window.x_limit_m] + [x for s in window.strokes for x in s[:2]]
    return min(xs), max(xs)


def phase_plan(
    plate: Plate, patch_m: tuple[float, float], offset_y_m: float, force_control: str
) -> tuple[PhasePlan | None, str]:
    """``(plan, why)``: where a slide of a pad of ``patch_m`` (x, y) [m] at ``offset_y_m``
    over ``plate`` is a function of its phase, or None and why not."""
    if force_control != "quasi-static":
        return None, f"the force is held by {force_control!r} control, not quasi-statically"
    rx = float(patch_m[0]) / 2 + REACH_MARGIN_M
    ry = float(patch_m[1]) / 2 + REACH_MARGIN_M
    found = _repetition(plate, rx)
    if isinstance(found, str):
        return None, found
    period, lo, hi = found
    free = period is None or abs(offset_y_m) + ry <= _y_free_half_width(plate, rx)
    return PhasePlan(period, lo, hi, lo, 0.0 if free else float(offset_y_m)), ""


@memoized("plates' repetitions", maxsize=256)
def _repetition(plate: Plate, rx: float) -> tuple[float | None, float, float] | str:
    """``(period or None, x_lo, x_hi)``: the period and the interior of a pad reaching
    ``rx`` along the slide (checked across the plate's whole width), or why there is none.
    A flat plate is uniform: no period, the whole plate its interior."""
    surf = surface_of(plate)
    if not surf.features and surf.arrays is None:  # flat: no feature, no samples
        return None, -plate.length_m / 2 + rx, plate.length_m / 2 - rx
    period = surf.period_m
    if period is None:
        return "the plate has no period along the slide"
    if surf.features:
        a, b = _repeating_span(surf.features, period)
        a, b = max(a, -plate.length_m / 2), min(b, plate.length_m / 2)
    else:
        a, b = -plate.area_length_m / 2, plate.area_length_m / 2
    lo, hi = a + rx, b - rx
    if hi - lo < MIN_PERIODS * period:
        return (
            f"the pad wholly on the texture spans {max(hi - lo, 0) * 1e3:.3g} mm of travel, "
            f"under {MIN_PERIODS:g} periods ({period * 1e3:.3g} mm)"
        )
    if surf.features:
        ok = _features_repeat(surf.features, a, b, period)
    else:
        step = _check_pitch(surf)
        ok = _repeats(surf, lo, hi, period, rx, _grid(0.0, plate.width_m / 2, step), step)
    if not ok:
        return (
            f"the plate does not repeat with its period ({period * 1e3:.4g} mm) over the "
            "pad's reach"
        )
    return period, lo, hi


def _shape(f, dx: float = 0.0) -> tuple:
    """A feature's kind, place (shifted ``dx`` along the slide) and size, to the nanometre."""
    nm = (f.x + dx, f.y, f.hx, f.hy, f.height_m, f.top_hx)
    return (f.kind, *(round(v / REPEAT_TOL_M) for v in nm))


def _repeating_span(features, period: float) -> tuple[float, float]:
    """``(a, b)``: the widest span [m] along the slide over which the features repeat: the
    end columns have no copy beyond them, so a reach must not see where one would be
    (``a >= x + hx - period`` for a feature without its copy one period back,
    ``b <= x - hx + period`` for one without its copy one period on). A missing copy inside
    the texture leaves no span (``a >= b``)."""
    have = {_shape(f) for f in features}
    a, b = -math.inf, math.inf
    for f in features:
        if _shape(f, -period) not in have:
            a = max(a, f.x + f.hx - period)
        if _shape(f, period) not in have:
            b = min(b, f.x - f.hx + period)
    return a, b


def _features_repeat(features, a: float, b: float, period: float) -> bool:
    """Whether every feature that reaches into ``(a, b - period)`` has its copy one period
    on, and every one that reaches into ``(a + period, b)`` its copy one period back: a pad
    that reaches ``(x - r, x + r)`` sees the same features at ``x`` and ``x + period`` for
    every ``x`` with ``x - r >= a`` and ``x + period + r <= b`` (to the nanometre)."""
    have = {_shape(f) for f in features}
    a, b = a + REPEAT_TOL_M, b - REPEAT_TOL_M  # a feature that only touches the reach: none
    for f in features:
        if f.x + f.hx > a and f.x - f.hx < b - period and _shape(f, period) not in have:
            return False
        if f.x + f.hx > a + period and f.x - f.hx < b and _shape(f, -period) not in have:
            return False
    return True


def depths_by_column(plate: Plate, patch_m: tuple[float, float], offset_y_m: float) -> bool:
    """Whether every node of a pad of ``patch_m`` (x, y) [m] at ``offset_y_m`` reads a depth
    that does not depend on its y: a flat plate, ridges that run past the whole pad (boxes
    or drafted prisms, by more than the smaller of their half-width and height), a 1-D
    profile wider than the pad. The dense held step then solves one node per column and
    halves the problem by its mirror (:class:`~sim_tactile.sim.step.held.CompiledHeldStep`,
    whose collider decides); this is the planner's reading of the same condition, for
    ``auto``'s choice of solver (:func:`~.solver.dense_is_dear`)."""
    ry = float(patch_m[1]) / 2 + REACH_MARGIN_M
    surf = surface_of(plate)
    if surf.features:
        return all(
            f.kind in ("box", "prism") and abs(offset_y_m - f.y) + ry < f.hy - min(f.hx, f.height_m)
            for f in surf.features
        )
    if surf.arrays is None:  # flat: no feature, no samples
        return True
    return surf.y_invariant(np.array([offset_y_m - ry, offset_y_m + ry]))


@memoized("plates' offset-free widths", maxsize=256)
def _y_free_half_width(plate: Plate, rx: float) -> float:
    """The half-width [m] about the plate's centre line within which its surface does not
    depend on y (ridges across the slide: their half-length; 0 where it depends on y, as
    on a grid of bumps or a height map)."""
    fs = surface_of(plate).features
    found = _repetition(plate, rx)
    if isinstance(found, str) or found[0] is None or not fs:
        return 0.0
    return _ridges_half_width(fs)


def _ridges_half_width(fs) -> float:
    """The half-width [m] about the centre line within which features ``fs`` do not depend
    on y: each a box or drafted prism alone at its place along the slide (a ridge across it),
    their shortest half-length about the line; 0 for bumps in rows or shapes that vary along
    y."""
    columns = {round(f.x / REPEAT_TOL_M) for f in fs}
    if len(columns) != len(fs) or any(f.kind not in ("box", "prism") for f in fs):
        return 0.0
    return max(0.0, min(f.hy - abs(f.y) for f in fs))


def _check_pitch(surf) -> float:
    scale = surf.feature_scale_m or CHECK_PITCH_M
    return min(CHECK_PITCH_M, scale / 10)


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


__all__ = [
    "MIN_PERIODS",
    "PhasePlan",
    "depths_by_column",
    "force_levels",
    "phase_plan",
    "table_pays",
    "tables_shared",
    "travel",
]


#: Slack [nm units of :data:`REPEAT_TOL_M`] within which a feature's mirror image matches a
#: feature of the plate (the positions' rounding to the nanometre on either side).
MIRROR_SLACK = 2


def mirror_centre(plate: Plate, plan: PhasePlan) -> float | None:
    """A pad centre position ``c`` [m] about which the plate's repeating texture is mirror
    symmetric along the slide (its height at ``c + u`` is its height at ``c - u`` for every
    ``u``, across the plate's whole width), or None where there is none or it cannot be told
    (a uniform stretch, a profile or a map). A pad symmetric along the slide then carries at
    ``2 c - x`` the mirror image of its answer at ``x``, and a table solves half a period
    (:func:`~sim_tactile.sim.step.phase_table.tabulate`).

    Every feature is symmetric about its own centre along the slide (boxes, drafted prisms,
    cylinders, caps), so the texture is symmetric about ``c`` when the mirror image of each
    feature of one period is a feature of the plate, to the nanometre, modulo the period.
    The candidates are the features' centres and the midpoints between neighbouring ones."""
    period = plan.period_m
    fs = surface_of(plate).features
    if period is None or not fs:
        return None
    tol = REPEAT_TOL_M
    n_p = round(period / tol)
    start = plan.x_ref - tol  # one period of columns (a column at its start is in)
    one = [f for f in fs if start <= f.x < start + period]
    if not one:
        return None

    def rest(f) -> tuple:
        return (f.kind, *(round(v / tol) for v in (f.y, f.hx, f.hy, f.height_m, f.top_hx)))

    xs = sorted({f.x for f in one})
    cands = xs + [0.5 * (a + b) for a, b in zip(xs, [*xs[1:], xs[0] + period], strict=True)]
    for c in cands:
        have: dict[tuple, list[int]] = {}
        for f in one:
            have.setdefault(rest(f), []).append(round((f.x - c) / tol) % n_p)
        if all(
            any(min((k + m) % n_p, (-(k + m)) % n_p) <= MIRROR_SLACK for m in have[rest(f)])
            for f in one
            for k in [round((f.x - c) / tol) % n_p]
        ):
            return float(c)
    return None
