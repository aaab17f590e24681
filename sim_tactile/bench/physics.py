"""The skin's error against physics: a solver the project did not write.

Every fidelity level is also set against an independent solution of the same contact. At a
few offsets of the pad over the plate, spread over a texture period, the pad is pressed on
the plate with the scene's force, statically. Two solutions of that press are compared:

- the configuration's own: its node grid (node pitch along and across the slide), its skin
  model (L0's Winkler bed, or the coupled half-space of L1 and L2), each node's depth from
  the plate's height at its centre, and the sensor's taxels reading each node's patch at
  their depths;
- the reference: Tamaas's FFT boundary-element solve of the elastic half-space (Polonsky and
  Keer's conjugate gradient), on a grid of :data:`REF_SPACING_M` over a periodic cell
  :data:`CELL_PADS` times the pad's larger side; each cell's pressure is read by the same
  taxels. It reproduces Hertz to 0.2% (``tests/test_ref_tamaas.py``). Its cells' *faces*,
  not their centres, sit on the multiples of the spacing (:func:`reference_axis`): the
  edges of the taxels and of the plates' features lie on round coordinates, and a row of
  cell centres on an edge would put the whole row on one side of it by the plate's ``<=``;
  where the pressure is singular at that edge (a rigid box under the skin), the row carries
  the edge's load (on ``finger7/bumps-4x4`` the taxel loads move by 7.9% between the two
  placements, see ``docs/physics.md``).

Both read the same taxels, so the difference is the skin model's discretisation against
the physics. It is a static measure: the time step's error shows in the error against L2.
The reference's own error is reported with it: the same solve on a grid twice as coarse
moves its taxel loads by ``ref_change`` (on sharp ridge edges the pressure is singular, and
the surface taxels converge slowly).

Tamaas is a test extra (``pip install tamaas``), never a runtime dependency: without it the
error against physics is left out and every row says why.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..cache import atomic_write
from ..hashing import code_version, content_hash, file_digest
from ..plates import Plate, surface_of
from ..scene.elastic import subsurface_weights
from ..scene.nodes import skin_grid
from ..sensors import Sensor
from ..sim.skin.anchored import AnchoredLattice
from ..sim.skin.clipped import ClippedPatches
from ..sim.skin.models import make_skin

#: the reference's grid spacing [m]
REF_SPACING_M = 0.0625e-3
#: the reference's periodic cell, in the pad's larger side: its images then pull on the
#: pad nearly uniformly (moving the approach, hardly the pressure: against a cell of 4 pad
#: sides the taxel loads move by 0.8% of the largest on finger7, 0.02% on biotac19 and pvdf2)
CELL_PADS = 2.5
#: Polonsky-Keer's tolerance on the relative gap
TOLERANCE = 1e-12


def tamaas_missing() -> str | None:
    """Why the error against physics cannot be computed here, or None."""
    try:
        import tamaas  # noqa: F401
    except ImportError:
        return (
            "no error against physics: Tamaas is not installed (pip install tamaas, a test extra)"
        )
    return None


#: The pad offsets are multiples of this [m] (twice the reference's spacing) plus
#: :data:`OFFSET_NUDGE_M`: walls at round coordinates then lie on the faces of the
#: reference's cells at both of its spacings, never through a column of them.
OFFSET_STEP_M = 2 * REF_SPACING_M
#: ... and off them by this [m], so that no wall lies exactly on a node centre of a
#: configuration (where the plate's ``<=`` would decide the node).
OFFSET_NUDGE_M = 1e-7


def offsets_m(plate: Plate, n: int) -> tuple[float, ...]:
    """``n`` pad offsets along the slide [m], spread over the texture's period (or 4 mm
    where it has none), each on the reference's cell faces (:data:`OFFSET_STEP_M`); every
    other one a step further, so that the walls meet a node grid's centres and its faces
    alike (a period that is a multiple of the node pitch would otherwise put every wall at
    the same place on the nodes, and a slide passes them all)."""
    period = surface_of(plate).period_m or 4e-3
    step = OFFSET_STEP_M
    return tuple(
        round((round(period * (k + 0.137) / n / step) + k % 2) * step + OFFSET_NUDGE_M, 10)
        for k in range(n)
    )


def gap_m(plate: Plate, finger, x, y, offset: float) -> np.ndarray:
    """Height of the plate above the pad's undeformed surface at pad coordinates (x, y) [m]
    with the pad ``offset`` along the slide; -1 m outside the pad (never touches)."""
    z = surface_of(plate).height(x + offset, y) - finger.surface(x, y)
    px, py = finger.patch_m
    inside = (np.abs(x) <= px / 2) & (np.abs(y) <= py / 2)
    return np.where(inside & np.isfinite(z), z, -1.0)


def reference_axis(n: int, spacing: float) -> np.ndarray:
    """The ``n`` cell centres [m] along one axis of the reference's cell: their faces on the
    multiples of ``spacing`` (the centres half a cell off), so that edges at round
    coordinates fall between cells, never through a row of centres (the reference named in
    every measured row's key, :data:`~sim_tactile.sim.plan.measured_errors.REFERENCE`)."""
    return (np.arange(n) - n // 2 + 0.5) * spacing


def tamaas_press(plate: Plate, finger, force_n: float, offset: float, spacing: float):
    """(xy, p, spacing, None): cell centres [m] and pressures [Pa] of Tamaas's solution (the
    cells that carry load), and the cells' side (as :func:`grid_press` gives its pitches)."""
    import tamaas as tm

    tm.set_log_level(tm.LogLevel.warning)
    px, py = finger.patch_m
    n = 2 * math.ceil(CELL_PADS * max(px, py) / spacing / 2)
    cell = n * spacing
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [cell, cell], [n, n])
    model.E, model.nu = finger.young_pa, finger.poisson
    x = reference_axis(n, spacing)
    X, Y = np.meshgrid(x, x, indexing="ij")
    gap = gap_m(plate, finger, X, Y, offset)
    solver = tm.PolonskyKeerRey(
        model, gap, TOLERANCE, tm.PolonskyKeerRey.pressure, tm.PolonskyKeerRey.pressure
    )
    solver.solve(force_n / cell**2)
    p = np.asarray(model.traction).reshape(n, n)
    loaded = p > 0
    return np.column_stack([X[loaded], Y[loaded]]), p[loaded], spacing, None


def grid_press(plate, finger, force_n, offset, level, pitch_m, pitch_y_m=None):
    """(xy, p, pitch, pitch_y): the node grid's pressures [Pa] of a configuration, held at
    ``force_n``."""
    grid = skin_grid(finger, pitch_m, pitch_y_m)
    gap = gap_m(plate, finger, grid.xy[:, 0], grid.xy[:, 1], offset)
    pen = np.where(gap > -1.0, gap, -np.inf)
    skin = make_skin(level, grid, finger, winkler_k_pa_per_m=finger.e_star_pa / finger.thickness_m)
    p, _ = skin.solve_force(pen, force_n / grid.area_m2)
    return grid.xy, p, grid.pitch_m, grid.pitch_y_m


def taxel_loads(xy, p, pitch, pitch_y, layout, depth_m: float | None = None) -> np.ndarray:
    """The layout's taxel loads [N] at their own depths (or all at ``depth_m``), each node or
    cell read as a uniform pressure over its patch."""
    depths = layout.depth_m if depth_m is None else np.full(layout.n, depth_m)
    W = subsurface_weights(
        xy, pitch, layout.positions[:, :2], layout.sizes, depths, pitch_y_m=pitch_y
    )
    return W @ (p * pitch * (pitch_y or pitch))


@dataclass(frozen=True)
class PhysicsReference:
    """Tamaas's taxel loads (offsets x taxels) [N] of one scene, and how far a grid twice
    as coarse moves them (relative norm)."""

    offsets_m: tuple[float, ...]
    loads: np.ndarray
    ref_change: float
    spacing_m: float

    def error(self, loads: np.ndarray) -> tuple[float, float]:
        """(relative norm over offsets x taxels, the largest taxel difference in units of
        the largest reference load) of ``loads`` against the reference."""
        d = loads - self.loads
        return (
            float(np.linalg.norm(d) / np.linalg.norm(self.loads)),
            float(np.abs(d).max() / np.abs(self.loads).max()),
        )


def reference_key(plate: Plate, sensor: Sensor, force_n: float, n_offsets: int) -> str:
    """The key of a scene's reference: the plate, the pad and its taxels, the force, the
    offsets, the reference's settings, Tamaas's version, and the code that computes it (this
    module and what the plate's heights and the taxels' weights are computed with)."""
    import tamaas as tm

    return content_hash(
        {
            "plate": plate.hash,
            "layout": sensor.layout.to_json(),
            "finger": sensor.finger.to_json(),
            "force_n": float(force_n),
            "offsets_m": list(offsets_m(plate, n_offsets)),
            "spacing_m": REF_SPACING_M,
            "cell_pads": CELL_PADS,
            "tolerance": TOLERANCE,
            "tamaas": tm.__version__,
            "this": file_digest(Path(__file__)),
            "code": code_version(
                "sim_tactile.plates", "sim_tactile.sensors", "sim_tactile.scene.elastic"
            ),
        }
    )


def reference(
    plate: Plate, sensor: Sensor, force_n: float, n_offsets: int, cache_dir: Path | None = None
) -> PhysicsReference:
    """The scene's reference taxel loads at ``n_offsets`` offsets. With ``cache_dir``, they
    are read from there when computed before (keyed by :func:`reference_key`), and stored
    there when not (an iCub plate's reference takes about 10 minutes)."""
    if cache_dir is not None:
        path = (
            Path(cache_dir) / f"physics-ref-{reference_key(plate, sensor, force_n, n_offsets)}.npz"
        )
        if path.is_file():
            with np.load(path, allow_pickle=False) as z:
                return PhysicsReference(
                    tuple(float(o) for o in z["offsets_m"]),
                    z["loads"],
                    float(z["ref_change"]),
                    float(z["spacing_m"]),
                )
        ref = reference(plate, sensor, force_n, n_offsets)
        buf = io.BytesIO()
        np.savez(
            buf,
            offsets_m=np.array(ref.offsets_m),
            loads=ref.loads,
            ref_change=ref.ref_change,
            spacing_m=ref.spacing_m,
        )
        atomic_write(path, buf.getvalue())
        return ref
    offs = offsets_m(plate, n_offsets)
    fine, coarse = [], []
    for off in offs:
        fine.append(
            taxel_loads(
                *tamaas_press(plate, sensor.finger, force_n, off, REF_SPACING_M), sensor.layout
            )
        )
        coarse.append(
            taxel_loads(
                *tamaas_press(plate, sensor.finger, force_n, off, 2 * REF_SPACING_M), sensor.layout
            )
        )
    fine_a, coarse_a = np.array(fine), np.array(coarse)
    change = float(np.linalg.norm(coarse_a - fine_a) / np.linalg.norm(fine_a))
    return PhysicsReference(offs, fine_a, change, REF_SPACING_M)


def clipped_press(cp: ClippedPatches, grid, plate, force_n, offset) -> np.ndarray:
    """The taxel loads [N] of the node grid's patches clipped at the plate's walls and the
    taxels' edges (``cp``, :mod:`~sim_tactile.sim.skin.clipped`) with the pad at ``offset``, held
    at ``force_n``."""
    z_top = float(np.nanmax(surface_of(plate).height(grid.xy[:, 0] + offset, grid.xy[:, 1])))
    (_, _, hx, hy, cell, _), cand, p, _ = cp.solve(offset, z_top + 1e-3, force_n)
    return cp.taxel_loads(cell[cand], p * 4 * hx[cand] * hy[cand])


def anchored_press(lat: AnchoredLattice, plate, force_n, offset) -> np.ndarray:
    """The taxel loads [N] of the lattice anchored to the plate's walls (``lat``,
    :mod:`~sim_tactile.sim.skin.anchored`) with the pad at ``offset``, held at ``force_n``."""
    x = np.linspace(-lat.half_x, lat.half_x, 257)
    top = float(np.nanmax(surface_of(plate).height(x[:, None] + offset, x[None, :] + lat.y0)))
    _, off = lat.solve(offset, top + 1e-3, force_n)
    return lat.taxel_loads(off, np.zeros(lat.taxel_x.size))


def configuration_loads(
    ref: PhysicsReference,
    plate,
    sensor,
    force_n,
    level,
    pitch_m,
    pitch_y_m,
    clipped=False,
    wall_m=None,
) -> np.ndarray:
    """A configuration's taxel loads at the reference's offsets (``clipped``: its patches
    clipped at the walls and taxel edges; ``wall_m``: the lattice anchored to the walls)."""
    if wall_m is not None:  # one lattice (and compliance) serves every offset
        lat = AnchoredLattice(sensor.finger, sensor.layout, plate, 0.0, pitch_m, pitch_y_m, wall_m)
        return np.array([anchored_press(lat, plate, force_n, off) for off in ref.offsets_m])
    if clipped:  # the static cells and their weights serve every offset
        grid = skin_grid(sensor.finger, pitch_m, pitch_y_m)
        cp = ClippedPatches(grid, sensor.finger, sensor.layout, plate, 0.0)
        return np.array([clipped_press(cp, grid, plate, force_n, off) for off in ref.offsets_m])
    return np.array(
        [
            taxel_loads(
                *grid_press(plate, sensor.finger, force_n, off, level, pitch_m, pitch_y_m),
                sensor.layout,
            )
            for off in ref.offsets_m
        ]
    )
