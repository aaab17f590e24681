"""Fidelity levels of the skin, and ``auto``: the cheapest setting that resolves the scene.

| level | skin model | node pitch | time step |
|---|---|---|---|
| L0 | rigid pad + penetration-depth map, local (Winkler) foundation k = E* / h | auto | auto |
| L1 | elastic half-space, exact contact set (coupled: a load deflects the neighbours) | auto | auto |
| L2 | L1 at half the node pitch and a quarter of the time step: the reference | auto/2 | auto/4 |

``auto`` (default) picks L1 with the coarsest node pitch and time step that resolve the
scene: the pitch is at most 1/2.5 of the smallest feature width or gap (the plate's
:attr:`~sim_tactile.plates.define.surface.Surface.feature_scale_m`; a height map's read off its samples) and half the smallest taxel; the time
step lets each feature take at least 20 steps to cross and stays within the skin-bone
coupling's stability limit. It warns when the taxels are coarser than the texture,
when a forced pitch or time step is too coarse, and when the plate's roughness lies below what
any node grid resolves (the micro-roughness model of the sensors handles that).

Where that grid was measured more than 10% from the physics, auto takes, in this order, the
first of these measured within 10%:

- a lattice anchored to the plate's walls (:mod:`~sim_tactile.sim.skin.anchored`:
  ``Fidelity.wall_m``; plates of boxes, taxels at the surface), the cheapest of
  :data:`ANCHORED_GRIDS`;
- the same grid with its patches clipped at the plate's walls and the taxels' edges
  (:mod:`~sim_tactile.sim.skin.clipped`: ``Fidelity.clipped``) or a finer grid; the clipped grid
  first where it has at most L1's node cap of static cells (:func:`_far_choice`), never
  above :data:`CLIPPED_MAX_CELLS`;
- where no measured grid under :data:`MAX_NODES_MEASURED` nodes is within 10%, the one
  closest to the physics (and a warning with its error).

The skin is the finger's own: its stack of layers on their backing when it has one (the cost
in the loop is the same), otherwise the elastic half-space. The reason names it and, where the
scene's node grid was measured against an independent half-space solver
(:mod:`~sim_tactile.sim.plan.measured_errors`), the expected error of the taxel loads; a warning
says when that is above 10% and what the measured finer grids give.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

from ... import _validate as v
from ...plates.define.spec import Plate
from ...plates.define.surface import surface_of
from ...scene.nodes import skin_grid
from .lattices import anchor_refusals, anchored_cells, skin_refusals, static_cells
from .measured_errors import (
    MAX_NODES_MEASURED,
    WARN_ABOVE,
    MeasuredError,
    expected_error,
    finer_grids,
    node_count,
    refinement,
)
from .options import MAX_SOLVE_EVERY, OWN_PITCH, SOLVE_TOL_RANGE  # noqa: F401  (two re-exported)

LEVELS = ("L0", "L1", "L2")
#: What a ``fidelity`` argument may be (a :class:`Fidelity` too, in Python).
FIDELITIES = ("auto", *LEVELS)
#: The levels of a static press (:func:`~sim_tactile.sim.static_press.press`): its finest node
#: pitch is its own reference, so it has no L2.
PRESS_LEVELS = ("L0", "L1")
#: Coarsest and finest node pitch auto may pick [m].
PITCH_MAX_M = 1.0e-3
PITCH_MIN_M = 0.25e-3
#: Most skin nodes auto may use per level (the dense half-space solve grows as nodes^3).
MAX_NODES = {"L0": 2500, "L1": 700, "L2": 2800}
#: Most nodes the dense solve takes; above it the skin is solved spectrally. Whole slides,
#: dense against spectral, the dense arrays read from the slide cache as when a data set is
#: made (perf/bench_spectral.py at a5d399a, medians of 3, slide loop + set-up):
#: textures20/boxes-3.0mm on the BioTac at 2835 nodes 2.3 s against 10.7 s (few contact
#: changes a step: the dense step is one product); finger7/bumps-6x6 at 2401 nodes 9.6 s
#: against 6.5 s (edges everywhere: the dense set updates cost |S|^2 each), at 1089 nodes
#: 0.9 s against 3.1 s. Without the cache, the compliance and its inverse take 4 s and
#: 3 s at 2835 nodes; the matrices grow as N^2 (two of 8 N^2 bytes) and the factorisation
#: as N^3.
DENSE_MAX_NODES = 3000
#: Most static cells of a clipped grid auto may take when no whole grid under
#: :data:`MAX_NODES_MEASURED` was measured within the target: the step assembles and factors
#: the patches along every moving wall, and the cost grows steeply with the cells (the
#: BioTac's boxes, 2009 cells: 0.55x real time; icub60's boxes-3.0mm at 1.16 mm, 4453 cells:
#: a whole slide had not finished in 10 minutes, at 6c08322).
CLIPPED_MAX_CELLS = 2500
#: Coarsest node pitch across the slide auto may pick over ridges along y [m].
PITCH_MAX_Y_M = 2.0e-3
#: Nodes across the smallest feature along the slide over ridges (x pitch = feature / this).
#: Against an independent half-space solver (Tamaas, 0.0625 mm), finger7/ridges-4's taxel
#: loads are 16% off at 5 nodes per 2.5 mm ridge (0.5 x 2 mm) and 9.6% at 10 (0.25 x 2 mm);
#: the y pitch hardly counts (0.25 x 1 mm: 7.0%). The nodes double, and the slide loop stays
#: near 40x real time.
RIDGE_NODES_PER_FEATURE = 10
#: The lattices anchored to the plate's walls auto may take ((cells at the walls, largest
#: cell along the slide, across it) [m]), cheapest first, where the pad's own lattice was
#: measured more than WARN_ABOVE from the physics: on finger7's ridges and bumps, 0.5 / 2 / 2
#: mm is 2.9-9.7% from the physics at 28-63x real time in the slide loop, 0.25 / 2 / 2 mm
#: 0.8-8.4% at 16-36x (bench_clipped at d9cbe58) (see :mod:`~sim_tactile.sim.skin.anchored`).
ANCHORED_GRIDS = ((0.5e-3, 2e-3, 2e-3), (0.25e-3, 2e-3, 2e-3), (0.25e-3, 2e-3, 1e-3))
#: Steps to cross the smallest feature, at least.
STEPS_PER_FEATURE = 20
#: Longest time step auto may pick [s].
DT_MAX_S = 2e-3
#: Largest omega * dt of the dynamic force loop's explicit skin-to-bone coupling before a run
#: is refused (the semi-implicit scheme is stable below 2: a margin of 2), and the share of it
#: that auto's time step keeps to.
MAX_OMEGA_DT = 1.0
AUTO_OMEGA_DT = 0.5 * MAX_OMEGA_DT


@dataclass(frozen=True)
class Fidelity:
    """The resolved fidelity of one slide: the skin model's level, the node pitch along
    (``pitch_m``) and across (``pitch_y_m``) the slide [m], the steps per sample and the step
    [s], the Winkler stiffness [Pa/m] of L0, why these were chosen, and the warnings."""

    level: str
    pitch_m: float
    steps_per_sample: int
    dt_s: float
    winkler_k_pa_per_m: float
    reason: str = ""
    warnings: tuple[str, ...] = field(default=())
    #: node pitch across the slide [m]; None: square nodes (``pitch_m``)
    pitch_y_m: float | None = None
    #: the taxel loads' measured error against physics at this node grid on this scene
    #: (relative norm over pad offsets x taxels; None: not measured)
    expected_error: float | None = None
    #: whether the node patches are clipped at the plate's walls and the taxels' edges
    #: (:mod:`~sim_tactile.sim.skin.clipped`; the held step of the half-space skin)
    clipped: bool = False
    #: the cells at the plate's walls [m] of a lattice anchored to the plate (its walls on
    #: the lines, cells up to ``pitch_m`` by ``pitch_y_m``; :mod:`~sim_tactile.sim.skin.anchored`);
    #: None: the pad's own node lattice
    wall_m: float | None = None

    @property
    def coupled(self) -> bool:
        """Whether a load on one node deflects its neighbours (every level but L0)."""
        return self.level != "L0"

    def to_json(self) -> dict:
        d = asdict(self)
        d["coupled"] = self.coupled
        d["warnings"] = list(self.warnings)
        if not self.clipped:
            del d["clipped"]  # whole patches keep the description they had
        if self.wall_m is None:
            del d["wall_m"]  # likewise the pad's own lattice
        return d


def choose_fidelity(
    plate: Plate,
    layout,
    finger,
    protocol,
    fidelity: str | Fidelity = "auto",
    *,
    pitch_m: float | None = None,
    dt_s: float | None = None,
    refine: bool = True,
) -> Fidelity:
    """Resolve ``fidelity`` ('auto', 'L0', 'L1', 'L2' or a Fidelity) for this scene (the
    protocol's rate defaults to the layout's). ``refine``: under ``auto``, where the grid
    that resolves the features was measured more than :data:`WARN_ABOVE` from the physics,
    take the coarsest finer grid measured within it (False: the resolving grid itself, the
    base the measurements refine)."""
    if isinstance(fidelity, Fidelity):
        return fidelity
    protocol = protocol.at_rate(layout.rate_hz)
    v.one_of("fidelity", fidelity, FIDELITIES)
    scale = surface_of(plate).feature_scale_m
    taxel = float(layout.sizes.min())
    taxel_x, taxel_y = (float(layout.sizes[:, k].min()) for k in (0, 1))
    need = min([taxel / 2] + ([scale / 2.5] if scale else []))
    auto_pitch = min(PITCH_MAX_M, max(PITCH_MIN_M, need))
    warnings = _texture_warnings(plate, layout, scale, auto_pitch)
    speed = max(protocol.speed_m_s, 1e-6)
    dt_need = DT_MAX_S if scale is None else min(DT_MAX_S, scale / (speed * STEPS_PER_FEATURE))
    level = "L1" if fidelity == "auto" else fidelity
    k_w = finger.e_star_pa / finger.thickness_m
    # the dynamic skin-bone coupling is explicit: keep omega * dt at half its limit;
    # quasi-static force control has no such coupling
    if protocol.force_control == "dynamic":
        omega = math.sqrt(flat_stiffness(finger, level != "L0", k_w) / finger.bone_mass_kg)
        dt_need = min(dt_need, AUTO_OMEGA_DT / omega)
    auto_pitch, aspect, wanted = _node_grid(
        plate, finger, level, auto_pitch, taxel_x, taxel_y, scale
    )
    pitch = pitch_m or auto_pitch
    dt_target = dt_s or dt_need
    if level == "L2":
        pitch, dt_target = (pitch_m or auto_pitch / 2), (dt_s or dt_need / 4)
    if pitch_m is None and wanted is not None and pitch > wanted * (1 + 1e-9):
        warnings.append(_raised(wanted, pitch, level))  # not where L2 halved it below
    pitch_y = pitch * aspect
    if dt_s is not None and scale is not None and dt_s > scale / (speed * 10):
        warnings.append(
            f"time step {dt_s:g} s is too coarse for {speed:g} m/s: a {scale * 1e3:.3g} mm feature "
            f"takes {scale / (speed * dt_s):.1f} steps to cross (want >= 10); pass dt_s at "
            f"most {scale / (speed * 10):.3g} s, or none (auto)"
        )
    if pitch_m is not None and scale is not None and pitch_m > scale / 2:
        warnings.append(
            f"node pitch {pitch_m * 1e3:.3g} mm is too coarse for {scale * 1e3:.3g} mm features; "
            f"pass pitch_m at most {scale / 2 * 1e3:.3g} mm, or none (auto)"
        )
    sample = 1.0 / protocol.rate_hz
    n_sub = steps_per_sample(protocol.rate_hz, dt_target)
    dt = 1.0 / (protocol.rate_hz * n_sub)  # the step simulate() takes
    shape = (
        f"{pitch * 1e3:.3g} mm"
        if aspect == 1.0
        else (f"{pitch * 1e3:.3g} x {pitch_y * 1e3:.3g} mm (x x y: ridges along y)")
    )
    py_key = None if aspect == 1.0 else float(pitch_y)
    measured = expected_error(plate, layout, finger, protocol.force_n, level, pitch, py_key)
    auto = fidelity == "auto" and refine and pitch_m is None
    far = auto and measured is not None and measured.error > WARN_ABOVE
    measured, pitch, py_key, shape, refined, clip, anch = _far_resolution(
        plate, layout, finger, protocol, level, pitch, py_key, measured, shape, far
    )
    nodes, grid_text = _grid_text(
        finger, layout, plate, protocol, pitch, py_key, shape, refined, anch
    )
    reason = (
        f"{level}: {_skin_name(finger, level)}, {grid_text}, "
        f"{'solved spectrally' if nodes > DENSE_MAX_NODES else 'dense solve'} (smallest feature "
        f"{'-' if scale is None else f'{scale * 1e3:.3g} mm'}, taxel {taxel * 1e3:.3g} mm), "
        f"dt {dt * 1e3:.3g} ms ({n_sub} steps per {sample * 1e3:.3g} ms sample); expected error: "
        + (
            measured.describe()
            if measured
            else "not measured for this scene and grid (perf/physics_per_plate.py)"
        )
    )
    if measured and measured.error > WARN_ABOVE:
        warnings.append(_far_from_physics(plate, layout, finger, protocol, level, measured, shape))
    return Fidelity(
        level,
        float(pitch),
        n_sub,
        dt,
        k_w,
        reason,
        tuple(warnings),
        py_key,
        None if measured is None else measured.error,
        clipped=clip is not None,
        wall_m=None if anch is None else anch.wall_m,
    )


def _grid_text(finger, layout, plate, protocol, pitch, py_key, shape, refined, anch):
    """``(nodes, text)``: the node (or anchored lattice's cell) count and how the reason
    names the grid."""
    if anch is None:
        nodes = node_count(finger, pitch, py_key)
        return nodes, f"node pitch {shape}{refined}, {nodes} nodes"
    cells = anchored_cells(finger, layout, plate, protocol.offset_y_m, pitch, py_key, anch.wall_m)
    return cells, f"a node {shape}{refined}, about {cells} cells under the pad"


def _far_resolution(plate, layout, finger, protocol, level, pitch, py_key, measured, shape, far):
    """``(measured, pitch, pitch_y, shape, why, clipped, anchored)``: the grid auto takes when
    its own (``pitch``, ``py_key``) was measured ``far`` from the physics: the anchored
    lattice, the clipped patches or a finer grid (see the module docstring), else its own."""
    anch = _anchored_choice(plate, layout, finger, protocol, level) if far else None
    clip, better = (
        _far_choice(plate, layout, finger, protocol, level, pitch, py_key, measured)
        if far and anch is None
        else (None, None)
    )
    if anch is not None:
        why = (
            f" (the pad's lattice {shape} measured {100 * measured.error:.0f}% from the "
            f"physics: the lattice anchored to the walls instead)"
        )
        return anch, anch.pitch_m, anch.pitch_y_m, anch.grid, why, None, anch
    if clip is not None or better is not None:
        return (*_adopt(measured, clip, better, shape), clip, None)
    return measured, pitch, py_key, shape, "", None, None


def _adopt(measured, clip, better, shape):
    """``(measured, pitch, pitch_y, shape, why)`` of the grid auto takes instead of one
    measured too far from the physics: ``clip`` (the same grid, clipped) or ``better``."""
    if clip is not None:
        why = (
            f" (whole patches measured {100 * measured.error:.0f}% from the physics: "
            "patches clipped at the walls and taxel edges instead)"
        )
        shape += ", patches clipped at the walls and taxel edges"
        return clip, clip.pitch_m, clip.pitch_y_m, shape, why
    why = f" (refined from {shape}, measured {100 * measured.error:.0f}% from the physics: " + (
        f"the coarsest measured grid from which every finer one is within {100 * WARN_ABOVE:.0f}%)"
        if better.error <= WARN_ABOVE
        else f"none measured under {MAX_NODES_MEASURED} nodes is within "
        f"{100 * WARN_ABOVE:.0f}%; the closest)"
    )
    return better, better.pitch_m, better.pitch_y_m, better.grid, why


def _far_choice(plate, layout, finger, protocol, level, pitch, py_key, measured):
    """``(clipped, finer)``: what auto takes for a grid measured more than WARN_ABOVE from
    the physics: the same grid with its patches clipped at the walls, or a finer grid,
    whichever was measured within the target (at most one is not None).

    The clipped grid first where its static cells are within L1's node cap: its step
    assembles and factors the patches along every moving wall, which pays on a small pad
    (finger7's bumps, 437 cells: 1 mm clipped 4.0-6.3x real time in the slide loop, 0.333 mm
    whole 0.2-0.4x, perf/bench_clipped.py at aa8c226) and not over a large contact,
    where a finer whole grid comes first (finger7/ridges-4 at 0.25 x 2 mm, 923 cells: 1.3x,
    against 0.125 x 1 mm whole 5.8x; the BioTac's boxes, 2009 cells: 0.55x against 0.355 mm
    whole 3.7x), and a clipped grid of more than :data:`CLIPPED_MAX_CELLS` cells is never
    taken."""
    if not _clippable(plate, finger, protocol, level):
        return None, refinement(plate, layout, finger, protocol.force_n, level, measured)
    grid = skin_grid(finger, pitch, py_key)
    cells = static_cells(grid, layout, plate, protocol.offset_y_m)
    small = cells <= MAX_NODES[level]
    clip = expected_error(plate, layout, finger, protocol.force_n, level, pitch, py_key, True)
    clip = clip if clip is not None and clip.error <= WARN_ABOVE else None
    if small and clip is not None:
        return clip, None
    better = refinement(plate, layout, finger, protocol.force_n, level, measured)
    if better is None and cells <= CLIPPED_MAX_CELLS:
        return clip, None
    return None, better


def _anchored_choice(plate, layout, finger, protocol, level) -> MeasuredError | None:
    """The first lattice of :data:`ANCHORED_GRIDS` measured within :data:`WARN_ABOVE` of the
    physics on this scene, where the anchored lattice serves it, or None."""
    if anchor_refusals(plate, layout, level, finger, protocol.force_control == "quasi-static"):
        return None
    for wall, px, py in ANCHORED_GRIDS:
        m = expected_error(plate, layout, finger, protocol.force_n, level, px, py, wall_m=wall)
        if m is not None and m.error <= WARN_ABOVE:
            return m
    return None


def _clippable(plate, finger, protocol, level) -> bool:
    """Whether clipped patches serve this scene: a plate with box walls, the held force, and
    a skin they serve (:func:`~.lattices.skin_refusals`)."""
    quasi_static = protocol.force_control == "quasi-static"
    return surface_of(plate).has_walls and not skin_refusals(level, finger, quasi_static)


def _node_grid(plate, finger, level, auto_pitch, taxel_x, taxel_y, scale):
    """auto's node pitch along the slide, the aspect of the nodes (y pitch / x pitch) and
    the pitch the features asked for before the level's node cap coarsened it (None where
    the cap left it)."""
    px, py = finger.patch_m
    # Ridges along y under a flat pad: the load varies along the slide only, so the nodes
    # go where it varies: x at 1/5 of the smallest feature, y as coarse as the taxels allow;
    # then x alone down to 1/RIDGE_NODES_PER_FEATURE where the node cap leaves room.
    ridges = _varies_along_x_only(plate, finger)
    aspect = 1.0
    cap = MAX_NODES["L1" if level == "L2" else level]
    if ridges:
        auto_pitch = min(PITCH_MAX_M, max(PITCH_MIN_M, min(taxel_x / 2, scale / 5)))
        aspect = max(1.0, min(taxel_y, PITCH_MAX_Y_M) / auto_pitch)
    floor = math.sqrt(px * py / cap / aspect)
    wanted = None
    if auto_pitch < floor:
        wanted, auto_pitch = auto_pitch, floor
    if ridges:
        y = auto_pitch * aspect
        x = max(PITCH_MIN_M, scale / RIDGE_NODES_PER_FEATURE, px * py / (cap * y))
        if x < auto_pitch:
            auto_pitch, aspect = x, y / x
    return auto_pitch, aspect, wanted


def _raised(wanted: float, pitch: float, level: str) -> str:
    """The warning for a node pitch that the level's node cap raised above what the
    features asked for (``wanted``) to ``pitch`` [m]."""
    own = f"a node pitch of your own ({OWN_PITCH}"
    finer = (
        f"{own}; slower)"
        if level == "L2"
        else f"fidelity L2 (half this pitch, about 4x the nodes and 8x the time) or {own})"
    )
    return (
        f"node pitch raised from {wanted * 1e3:.3g} to {pitch * 1e3:.3g} mm to keep the skin "
        f"under {MAX_NODES[level]} nodes: features below "
        f"{2 * pitch * 1e3:.3g} mm are smeared; for a finer grid: {finer}"
    )


def _far_from_physics(plate, layout, finger, protocol, level, measured, shape) -> str:
    """The warning for a grid measured more than WARN_ABOVE from the physics, with what the
    measured finer grids give, their node counts and how they are solved."""
    out = (
        f"the taxel loads at this node grid ({shape}) are {100 * measured.error:.0f}% from the "
        "physics on this plate"
    )
    py_m = measured.pitch_y_m
    for m in finer_grids(plate, layout, finger, protocol.force_n, level, measured.pitch_m, py_m):
        nodes = node_count(finger, m.pitch_m, m.pitch_y_m)
        how = "solved spectrally" if nodes > DENSE_MAX_NODES else "dense solve"
        over = f", over auto's {MAX_NODES_MEASURED}" if nodes > MAX_NODES_MEASURED else ""
        out += f"; {m.grid}: {100 * m.error:.1f}% ({nodes} nodes{over}, {how}; pass pitch_m)"
    return out


def _skin_name(finger, level: str) -> str:
    if level == "L0":
        return "Winkler bed"
    stack = getattr(finger, "stack", None)
    if stack is None:
        return "elastic half-space (the finger declares no stack)"
    return f"{len(stack.layers)}-layer stack ({stack.thickness_m * 1e3:.3g} mm) on a {stack.backing} backing"


def _texture_warnings(plate: Plate, layout, scale: float | None, pitch: float) -> list[str]:
    """What the node grid (``pitch``) and the taxels cannot resolve of the texture."""
    warnings = []
    taxel = float(layout.sizes.min())
    if scale is not None and pitch > scale / 2:
        warnings.append(
            f"the smallest feature ({scale * 1e3:.3g} mm) is below two node pitches "
            f"({pitch * 1e3:.3g} mm): its load is smeared over neighbouring nodes; a node "
            f"pitch of at most {scale / 2 * 1e3:.3g} mm resolves it ({OWN_PITCH}; slower)"
        )
    surf = surface_of(plate)
    if surf.ra_m is not None:
        warnings.append(
            f"micro-roughness (Ra {surf.ra_m * 1e6:.3g} um) is below the node grid: the finger simulation sees "
            "it only where its nodes sample the height map; nothing to change: the sensor's "
            "micro-roughness model adds what lies below"
        )
    period = surf.period_m
    if period is not None and layout.min_pitch_m > period / 2 and layout.n > 1:
        warnings.append(
            f"taxel pitch {layout.min_pitch_m * 1e3:.3g} mm is coarser than half the texture "
            f"period ({period * 1e3:.3g} mm): the taxel array aliases the texture; taxels at "
            f"most {period / 2 * 1e3:.3g} mm apart would sample it (a sensor file of your own)"
        )
    if period is not None and taxel > period:
        warnings.append(
            f"taxels ({taxel * 1e3:.3g} mm) are larger than the texture period "
            f"({period * 1e3:.3g} mm): each taxel averages over several features; taxels "
            f"smaller than {period * 1e3:.3g} mm would tell them apart (a sensor file of your own)"
        )
    return warnings


def steps_per_sample(rate_hz: float, dt_s: float) -> int:
    """Whole steps per sample period for a step of at most ``dt_s`` (one at least)."""
    sample = 1.0 / rate_hz
    return max(1, math.ceil(sample / dt_s - 1e-9))


def _varies_along_x_only(plate: Plate, finger) -> bool:
    """Whether the plate's features are box ridges along y across the whole textured width and
    the pad is flat: then the load under the pad varies along the slide only, but for the
    pad's own edges. Drafted ridges are left out and keep square nodes: MuJoCo's mesh
    collider, which collided them until the compiled collider took them, lost them against
    the small probe spheres of 0.4 mm wide nodes (multilayer3/grating-9 gave a flat signal),
    and their measured errors are of square grids."""
    if getattr(finger, "shape", None) != "flat":
        return False
    fs = surface_of(plate).features
    return bool(fs) and all(f.kind == "box" and 2 * f.hy >= plate.area_width_m - 1e-9 for f in fs)


def friction_coupled(finger) -> bool:
    """Whether the finger's sliding friction enters its normal problem (its compliance is
    not symmetric: a skin that carries its tractions, with friction, on a layered or
    compressible skin); such a skin is always solved dense."""
    return bool(
        finger.skin_tractions
        and finger.friction > 0
        and (finger.stack is not None or finger.poisson < 0.5)
    )


def solved_spectrally(fid: Fidelity, finger, solver: str = "auto") -> bool:
    """Whether a slide at ``fid`` solves its skin spectrally (as
    :func:`~sim_tactile.sim.skin.models.make_skin` decides): a coupled skin of the pad's own
    lattice above :data:`DENSE_MAX_NODES` nodes (or ``solver`` spectral) whose compliance is
    symmetric; a plate-anchored lattice and clipped patches are their own dense problems."""
    if not fid.coupled or fid.wall_m is not None or fid.clipped or solver == "dense":
        return False
    if friction_coupled(finger):
        return False
    return solver == "spectral" or node_count(finger, fid.pitch_m, fid.pitch_y_m) > DENSE_MAX_NODES


def flat_stiffness(finger, coupled: bool, k_w: float) -> float:
    """Stiffness of the whole pad pressed flat on a plate [N/m]: the largest contact stiffness
    the bone meets. Winkler: k_w times the area; half-space: a flat circular punch of the same
    area, 2 a E*."""
    px, py = finger.patch_m
    if not coupled:
        return k_w * px * py
    return 2 * math.sqrt(px * py / math.pi) * finger.e_star_pa
