"""A table along the slide: where no period serves, the plates whose loads are a function of
the pad's position along the slide alone (:func:`span_plan`), and when such a table pays over
the slides of a set (:func:`span_pays`); and which table a slide reads (:func:`table_plan`:
a period's, :func:`~.phase.phase_plan`, or one along the slide).

A rough profile, or ridges across the whole pad that the pad never covers for two periods,
does not vary across the slide over the pad's reach: a slide's loads there are a function of
its position alone, whatever its offset, so one table of positions along it, shared by force
level, serves every slide of the plate. It holds far more positions than a period's phases,
so it pays over many slides of a plate only: ``auto`` weighs it against the set's slides.

This module loads neither MuJoCo nor numba.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import ConfigError
from ...plates.define.spec import Plate
from ...plates.define.surface import surface_of
from .phase import (
    LEVELS_PER_OCTAVE,
    MIN_PERIODS,
    REACH_MARGIN_M,
    PhasePlan,
    _ridges_half_width,
    force_levels,
    phase_plan,
    travel,
)
from .protocol import START_MARGIN_M, Protocol, SlideWindow

#: Smallest interval between two positions of a table over a stretch with no period, as a
#: share of the node pitch: a rough profile is rough below the node pitch, so its intervals
#: are halved down to this nearly everywhere, and this sets the table's cost. Measured on the
#: iCub's rough strips (slide 0 of textures20-icub60-v2, against the per-step solve, relative
#: L2): rough-ra25 0.11% at an eighth of the pitch (2441 positions), 0.24% at a quarter
#: (about half the solves), 0.89% at a half; rough-ra100 0.055% and 0.067%.
SPAN_MIN_FRACTION = 1 / 4
#: The same along ridges across the pad (a texture with walls, crossed from flat ground),
#: as a period's phases are refined: the loads jump where a node row crosses a wall, and
#: only the intervals about the walls reach it. On textures20-icub60-v1's drafted grating
#: (slide 0): 0.93% rel L2 from the per-step solve, against 1.78% at a quarter.
SPAN_RIDGES_FRACTION = 1 / 8
#: What a position of a table along the slide costs, in a per-step slide's cost a solve (its
#: whole cost over its solves), on a spectral skin and on a dense one, with a margin over
#: what was measured: 0.8-1.0 on the iCub's spectral skin (3.5 ms a position against 3.4-4.3
#: ms), 1.5 on its dense skin over a grating (3.1 ms against 2.1 ms), 2.1 on the BioTac's
#: (95 us, a position settled from its neighbour's height, against 45 us: its steps keep
#: their contact set) and 0.7 on the PVDF fingertip's (77 us against 114 us).
SPAN_SOLVE_COST = {"spectral": 1.5, "dense": 2.0}
#: The force levels a set's slides read are counted over its nominal force +- this many
#: standard deviations of its jitter (95% of its slides).
SPAN_FORCE_SDS = 2.0


def table_plan(
    plate: Plate,
    patch_m,
    proto: Protocol,
    window: SlideWindow,
    path: str,
    solve_every: int,
    span: bool = False,
) -> PhasePlan | None:
    """The plan of a slide whose loads are read off a phase table: ``path`` ``auto`` where
    the plate repeats under the pad for at least :data:`MIN_PERIODS` of the slide's travel
    (and no ``solve_every`` > 1 asks for the sampled per-step slide), or ``phase-table``
    (refused with a ConfigError that says why where it does not serve); else None, the
    per-step slide. ``proto`` is the drawn protocol, ``window`` its window."""
    if path == "per-step" or (path == "auto" and solve_every > 1):
        return None
    plan, why = phase_plan(plate, patch_m, proto.offset_y_m, proto.force_control)
    lo, hi = travel(window, proto)
    if plan is None and (path == "phase-table" or span):  # a profile's whole stretch
        found = span_plan(plate, patch_m, proto.offset_y_m, proto.force_control, (lo, hi))
        if found is not None:
            plan, why = found
    if plan is not None:
        inside = max(0.0, min(hi, plan.x_hi) - max(lo, plan.x_lo))
        if inside <= 0.0 or inside < MIN_PERIODS * (plan.period_m or 0.0):
            plan, why = (
                None,
                (
                    f"the slide travels {inside * 1e3:.3g} mm on the repeating texture, under "
                    f"{MIN_PERIODS:g} periods"
                ),
            )
    if plan is None and path == "phase-table":
        raise ConfigError(f"path = 'phase-table' does not serve this slide: {why}")
    return plan


def span_plan(
    plate: Plate,
    patch_m: tuple[float, float],
    offset_y_m: float,
    force_control: str,
    travel_m: tuple[float, float] | None = None,
) -> tuple[PhasePlan, str] | None:
    """``(plan, "")`` of a plate that does not vary across the slide over the pad's reach at
    ``offset_y_m``, where no period serves (:func:`~.phase.phase_plan`): a rough profile, or ridges
    across the whole pad that the pad crosses from flat ground. Its loads are a function of
    the pad's position along it alone, the same for every slide at the same force, whatever
    its offset, so one table along it serves them all (a table of many more positions than a
    period's phases, which pays over many slides a plate: :func:`span_pays`). The stretch is
    the textured area's interior (the pad wholly on it) where the slide's ``travel_m`` (its
    pad centre's x range [m]: :func:`~.phase.travel`) lies there, else every pad centre a slide
    window reaches on the plate (:func:`_plate_reach`), the flat ground either side of the
    texture included (the base is flat at every y: the loads are a function of the position
    there too). None where the plate is not such a plate."""
    if force_control != "quasi-static":
        return None
    surf = surface_of(plate)
    ry = float(patch_m[1]) / 2 + REACH_MARGIN_M
    if surf.features:
        if abs(offset_y_m) + ry > _ridges_half_width(surf.features):
            return None
    elif surf.arrays is None or surf.period_m is not None:
        return None  # flat, a map, or a profile that repeats: a period's plan serves
    elif not surf.y_invariant(np.array([offset_y_m - ry, offset_y_m + ry])):
        return None
    rx = float(patch_m[0]) / 2 + REACH_MARGIN_M
    lo, hi = -plate.area_length_m / 2 + rx, plate.area_length_m / 2 - rx
    if travel_m is not None and not (lo <= travel_m[0] and travel_m[1] <= hi):
        half = _plate_reach(plate, float(patch_m[0]))
        lo, hi = -half, half
    if hi <= lo:
        return None
    return PhasePlan(None, lo, hi, lo, 0.0, span=True), ""


def _plate_reach(plate: Plate, pad_length_m: float) -> float:
    """The farthest a pad centre travels from the plate's centre on any slide window
    (:meth:`~.protocol.SlideWindow.of`): its start on flat ground, or its stop with the pad
    at the plate's end, whichever is farther, and :data:`REACH_MARGIN_M` beyond (a stroke
    stops on the step that passes its limit). The pad overhangs the plate's end there; the
    loads are a function of the position all the same (the end runs straight across)."""
    start = plate.area_length_m / 2 + pad_length_m / 2 + START_MARGIN_M
    return max(start, plate.length_m / 2 - pad_length_m / 2) + REACH_MARGIN_M


def span_pays(
    plan: PhasePlan,
    plate: Plate,
    patch_m,
    nominal: Protocol,
    pitch_m: float,
    slide_solves: float,
    n_slides: int,
    spectral: bool,
) -> bool:
    """Whether a profile's table (``plan``, :func:`span_plan`) pays over the ``n_slides``
    slides of its plate that a set makes, each of which would take ``slide_solves`` solves
    step by step: the positions it is estimated to hold (every interval refined to
    :func:`span_fraction` of the node pitch ``pitch_m`` where the pad reaches the
    texture, a position a pitch on the flat ground beyond), at :data:`SPAN_SOLVE_COST`
    solves each (on a ``spectral`` skin or a dense one), once for each force level its
    slides read (:func:`levels_read`), against the solves of the slides it serves."""
    rx = float(patch_m[0]) / 2 + REACH_MARGIN_M
    reach = plate.area_length_m / 2 + rx
    rough = max(0.0, min(plan.x_hi, reach) - max(plan.x_lo, -reach))
    flat = max(0.0, plan.x_hi - plan.x_lo - rough)
    positions = rough / (pitch_m * span_fraction(plate)) + flat / pitch_m
    levels = levels_read(nominal)
    cost = SPAN_SOLVE_COST["spectral" if spectral else "dense"]
    return n_slides * slide_solves >= cost * levels * positions


def span_fraction(plate: Plate) -> float:
    """The smallest interval of ``plate``'s table along the slide, as a share of the node
    pitch: :data:`SPAN_RIDGES_FRACTION` along ridges, :data:`SPAN_MIN_FRACTION` along a
    rough profile."""
    return SPAN_RIDGES_FRACTION if surface_of(plate).features else SPAN_MIN_FRACTION


def levels_read(nominal: Protocol) -> int:
    """How many shared force levels (:func:`~.phase.force_levels`,
    :data:`~.phase.LEVELS_PER_OCTAVE` an octave) the slides drawn from ``nominal`` read: from
    the lower level of its lowest force to the upper level of its highest, its force
    +- :data:`SPAN_FORCE_SDS` of its jitter (as the draw clips it, to 0.2-2 times the
    nominal force); one where the force does not vary (every slide's table is the same)."""
    j = nominal.force_jitter
    if j == 0.0:
        return 1
    lo = force_levels(nominal.force_n * max(0.2, 1 - SPAN_FORCE_SDS * j))[0][0]
    hi = force_levels(nominal.force_n * min(2.0, 1 + SPAN_FORCE_SDS * j))[-1][0]
    return round(LEVELS_PER_OCTAVE * math.log2(hi / lo)) + 1


__all__ = [
    "levels_read",
    "span_fraction",
    "span_pays",
    "span_plan",
    "table_plan",
]
