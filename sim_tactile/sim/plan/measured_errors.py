"""The measured error against physics of a node grid on a task scene: what ``auto`` expects.

``perf/physics_per_plate.py --write-table`` presses each simulated task's sensor on each
of its plates, at ``auto``'s node grid and at half its pitch, and sets the taxel loads
against an independent boundary-element half-space (Tamaas on a 0.0625 mm grid). It stores
each result in ``measured_errors.json`` beside this module, with the commit it was measured
at. :func:`expected_error` finds the row for a scene, so that :func:`choose_fidelity
<sim_tactile.sim.plan.fidelity.choose_fidelity>` can say how far its choice is from the physics
and what a finer grid would give.

A row is found only for the scene it was measured on: its key is the content hash of the
plate's parameters, the sensor's layout and finger (its skin and stack included), the level
and the node grid. Any change to these (a user's own sensor, an edited preset, another
pitch) finds no row, and the reason says the error was not measured. It is never another
scene's figure but in one case, which the reason names: a ``textures20-long`` preset that was
not measured takes the rows of its 36 mm ``textures20`` plate (:func:`stand_in`), whose
features are the same under the pad; where both were measured (the BioTac's 20 plates at
two grids, the iCub's gratings at three), the two differ by up to 1.9 points (14.8% against
16.7% on boxes-4.5mm) and mostly by a few tenths. The press force may differ from the measured one by at most
:data:`FORCE_SPAN` (a data set's drawn forces), and the reason names the measured force.
The error is that of a static press: the step, and what a slide adds (the node-crossing
tone), are not in it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path

from ...cache import memoized
from ...hashing import content_hash
from ...scene.nodes import lattice_shape

#: The table, written by ``perf/physics_per_plate.py --write-table``.
TABLE = Path(__file__).with_name("measured_errors.json")
#: Largest relative difference between a scene's force and the measured force for a row to
#: apply. It spans a data set's drawn forces (the protocols clip a drawn force to 0.2-2
#: times its nominal value), so that every slide of a plate takes the grid measured at the
#: nominal force: at 0.5, 5.2% of textures20-icub60-v1's slides (force varying by 25%) fell
#: outside it and kept the unrefined grid, 50% from the physics on boxes-4.5mm.
FORCE_SPAN = 1.0
#: Error against physics above which auto warns (the target of issue 16's defaults).
WARN_ABOVE = 0.10
#: The reference the rows are measured against, part of every row's key: Tamaas on a
#: 0.0625 mm grid whose cell faces (not centres) lie on the multiples of the spacing
#: (:func:`sim_tactile.bench.physics.reference_axis`), at pad offsets that put the walls
#: on cell faces too (:data:`sim_tactile.bench.physics.OFFSET_STEP_M`). Rows measured
#: against another reference are not found.
REFERENCE = "tamaas-0.0625mm-faces-on-grid"


@dataclass(frozen=True)
class MeasuredError:
    """One measured node grid: the relative norm of the taxel loads against the physics over
    the pad offsets, the largest taxel difference (in units of the largest reference load),
    the reference's own convergence (its change on a grid twice as coarse), the force, and
    the commit and the command that measured it."""

    error: float
    largest_taxel: float
    ref_change: float
    force_n: float
    pitch_m: float
    pitch_y_m: float | None
    commit: str
    task: str
    plate: str
    clipped: bool = False
    #: the anchored lattice's cells at the walls [m] (:mod:`~sim_tactile.sim.skin.anchored`; its
    #: cells up to pitch_m by pitch_y_m); None: the pad's own node lattice
    wall_m: float | None = None
    #: the plate this row stands in for (:func:`stand_in`); None: measured on it
    stands_in_for: str | None = None

    @property
    def grid(self) -> str:
        x = self.pitch_m * 1e3
        g = f"{x:.3g} mm" if self.pitch_y_m is None else f"{x:.3g} x {self.pitch_y_m * 1e3:.3g} mm"
        if self.wall_m is not None:
            return f"lattice anchored to the walls ({self.wall_m * 1e3:.3g} mm at the walls, up to {g})"
        return g + (", clipped" if self.clipped else "")

    def describe(self) -> str:
        return (
            f"{100 * self.error:.1f}% against physics (largest taxel {100 * self.largest_taxel:.1f}%; "
            f"static press at {self.force_n:g} N on {self.plate}, measured at {self.commit}"
            + (
                ""
                if self.stands_in_for is None
                else f"; {self.stands_in_for} not measured: the same features on a shorter plate"
            )
            + ")"
        )


def grid_key(
    plate,
    layout,
    finger,
    level: str,
    pitch_m: float,
    pitch_y_m: float | None,
    clipped: bool = False,
    wall_m: float | None = None,
) -> str:
    """The key of a node grid on a scene: everything the static press's error depends on but
    the force (node pitches rounded to 0.1 um), whether its patches are clipped at the walls
    and taxel edges (:mod:`~sim_tactile.sim.skin.clipped`), the anchored lattice's cells at the
    walls (:mod:`~sim_tactile.sim.skin.anchored`), and the reference."""
    d = {
        "plate": plate.hash,
        "layout": layout.to_json(),
        "finger": finger.to_json(),
        "level": level,
        "pitch_um": round(pitch_m * 1e6, 1),
        "pitch_y_um": None if pitch_y_m is None else round(pitch_y_m * 1e6, 1),
        "reference": REFERENCE,
    }
    if clipped:
        d["clipped"] = True
    if wall_m is not None:
        d["anchored_wall_um"] = round(wall_m * 1e6, 1)
    return content_hash(d)


@memoized("measured-errors table", maxsize=1)
def _table() -> dict[str, list[dict]]:
    if not TABLE.is_file():
        return {}
    rows = json.loads(TABLE.read_text())["rows"]
    out: dict[str, list[dict]] = {}
    for r in rows:
        out.setdefault(r["key"], []).append(r)
    return out


def _row(r: dict) -> MeasuredError:
    return MeasuredError(
        float(r["error_vs_physics"]),
        float(r["largest_taxel"]),
        float(r["ref_change"]),
        float(r["force_n"]),
        float(r["pitch_m"]),
        None if r["pitch_y_m"] is None else float(r["pitch_y_m"]),
        str(r["commit"]),
        str(r["task"]),
        str(r["plate"]),
        bool(r.get("clipped", False)),
        None if r.get("wall_m") is None else float(r["wall_m"]),
    )


def expected_error(
    plate,
    layout,
    finger,
    force_n: float,
    level: str,
    pitch_m: float,
    pitch_y_m: float | None,
    clipped: bool = False,
    wall_m: float | None = None,
) -> MeasuredError | None:
    """The measured error of this node grid (``clipped``: its patches clipped at the walls
    and taxel edges; ``wall_m``: the lattice anchored to the walls) on this scene, or None if
    it was not measured (or only at a force more than :data:`FORCE_SPAN` away)."""
    key = grid_key(plate, layout, finger, level, pitch_m, pitch_y_m, clipped, wall_m)
    rows = _table().get(key, [])
    near = [r for r in rows if abs(force_n / r["force_n"] - 1) <= FORCE_SPAN]
    if not near:
        short = stand_in(plate)
        if short is None:
            return None
        m = expected_error(
            short, layout, finger, force_n, level, pitch_m, pitch_y_m, clipped, wall_m
        )
        return None if m is None else replace(m, stands_in_for=plate.name)
    return _row(min(near, key=lambda r: abs(force_n / r["force_n"] - 1)))


def stand_in(plate):
    """The plate whose measured rows stand in for ``plate``'s: the 36 mm ``textures20`` plate
    of a ``textures20-long`` preset (the same features under the pad, on a longer strip), or
    None. Only the preset itself is matched (by its content, not its name alone)."""
    from ...errors import UnknownNameError
    from ...plates.read.presets import LONG_FAMILY, get_plate

    name = plate.name or ""
    if not name.startswith(LONG_FAMILY):
        return None
    try:
        if get_plate(name).hash != plate.hash:
            return None
        return get_plate("textures20/" + name[len(LONG_FAMILY) :])
    except UnknownNameError:
        return None


#: The refinements ``perf/physics_per_plate.py --refine`` measures: the grids at 1/f of
#: auto's pitch in both directions.
REFINEMENTS = (2, 3, 4, 5, 6, 8)


def finer_grids(plate, layout, finger, force_n: float, level: str, pitch_m: float, pitch_y_m):
    """The measured grids at 1/f of this one's pitch in both directions (f in
    :data:`REFINEMENTS`), coarsest first."""
    out = []
    for f in REFINEMENTS:
        m = expected_error(
            plate,
            layout,
            finger,
            force_n,
            level,
            pitch_m / f,
            None if pitch_y_m is None else pitch_y_m / f,
        )
        if m is not None:
            out.append(m)
    return out


#: Most skin nodes auto may take when the measured error sends it to a finer grid (solved
#: spectrally above :data:`~sim_tactile.sim.plan.fidelity.DENSE_MAX_NODES`): a slide there
#: costs seconds per second of contact (finger7/bumps-6x6 at 2401 nodes 0.33x real time, the
#: BioTac's boxes at 2835 nodes 0.23x). icub60's 0.385 mm grid (6231 nodes, spectral) brings
#: its boxes and cylinders within 10% of the physics; its hemispheres-3.0mm need 0.289 mm
#: (11125 nodes: 7.2%, against 11.5% at 0.385 mm). A whole slide of that plate, the process
#: timed with its imports, took 12.2 s at 0.289 mm against 7.7 s at 0.385 mm (medians of 3,
#: A B A B, at 78bfefb: 1.60x). finger7/bumps-4x4 at 16641 nodes (0.125 mm, 4.8% from the
#: physics) runs at 0.03x and is left to the user (``pitch_m``; the warning names it).
MAX_NODES_MEASURED = 11500


def node_count(finger, pitch_m: float, pitch_y_m: float | None) -> int:
    """The skin nodes of a node grid on ``finger``'s pad."""
    nx, ny = lattice_shape(finger, pitch_m, pitch_y_m)
    return nx * ny


def refinement(plate, layout, finger, force_n, level, measured) -> MeasuredError | None:
    """The grid auto refines ``measured`` to, or None (None too when it is within
    WARN_ABOVE, or not measured): the coarsest within WARN_ABOVE (:func:`_measured_within`),
    else the measured finer grid closest to the physics under :data:`MAX_NODES_MEASURED`
    nodes, where it is closer than ``measured`` (the case of a scene measured only at grids
    all beyond 10%; auto warns with the error of the one it takes)."""
    if measured is None or measured.error <= WARN_ABOVE:
        return None
    within = _measured_within(plate, layout, finger, force_n, level, measured)
    if within is not None:
        return within
    py = measured.pitch_y_m
    grids = [
        m
        for m in finer_grids(plate, layout, finger, force_n, level, measured.pitch_m, py)
        if node_count(finger, m.pitch_m, m.pitch_y_m) <= MAX_NODES_MEASURED
        and m.error < measured.error
    ]
    return min(grids, key=lambda m: m.error) if grids else None


def _measured_within(plate, layout, finger, force_n, level, measured) -> MeasuredError | None:
    """The coarsest measured finer grid from which every finer measured grid is within
    :data:`WARN_ABOVE` of the physics (under :data:`MAX_NODES_MEASURED` nodes), or None.
    A grid within it whose finer neighbours are not is a lucky alignment of the nodes with
    the features' edges (measured: finger7/bumps-3x3 at 0.25 mm 6.1%, at 0.167 mm 12.5%),
    which a slide does not keep."""
    py = measured.pitch_y_m
    grids = finer_grids(plate, layout, finger, force_n, level, measured.pitch_m, py)
    best = None
    for m in reversed(grids):  # finest first
        if m.error > WARN_ABOVE:
            break
        if node_count(finger, m.pitch_m, m.pitch_y_m) <= MAX_NODES_MEASURED:
            best = m
    return best
