"""Static indentation: press a finger on a plate to a normal force and read the pressure.

The pad is held at the force by the same held step as a slide under quasi-static force
control (:class:`~.step.held.PlainHeldStep`: the collider's depth map, the skin's force-holding solve,
a new query wherever the pad moved beyond the collider's margin), on the scene a slide would
build, and a dense grid of taxels reads the pressure at the surface, or the vertical stress
at a depth inside the skin. With a spherical pad on a flat plate this is Hertz's problem,
which the tests check; the finger's skin may be a half-space or a stack of layers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import _validate as v
from ..errors import ConfigError, PhysicsError
from ..plates import Plate, get_plate, surface_of
from ..scene.model import build_scene
from ..scene.nodes import skin_grid
from ..sensors.layouts import Layout, dense_layout
from ..sensors.pad import Finger
from .collide.choose import make_collider
from .plan.fidelity import PRESS_LEVELS
from .plan.protocol import APPROACH_CLEARANCE_M
from .skin.models import make_skin
from .step.held import PlainHeldStep

#: Smallest side of a spherical pad's node patch [m], and how many Hertz contact radii it
#: spans at least (the pad's edge must lie beyond the contact).
SPHERE_PAD_MIN_M = 12e-3
SPHERE_PAD_CONTACT_RADII = 3.0


@dataclass
class PressResult:
    layout: Layout
    taxel_load_n: np.ndarray  # (M,)
    pressure_pa: np.ndarray  # (M,) taxel load / taxel area: the pressure, or the stress at depth
    total_force_n: float
    contact_radius_m: float  # sqrt(contact area / pi) from the skin nodes in contact
    peak_pressure_pa: float  # largest node pressure
    approach_m: float
    contact_area_m2: float = 0.0
    depth_m: float = 0.0  # of the dense grid under the surface

    def to_json(self) -> dict:
        out = {
            "taxels": self.layout.positions[:, :2].tolist(),
            "depth_m": self.depth_m,
            "stress_pa": self.pressure_pa.tolist(),
            "total_force_n": self.total_force_n,
            "contact_area_m2": self.contact_area_m2,
            "contact_radius_m": self.contact_radius_m,
            "peak_pressure_pa": self.peak_pressure_pa,
            "approach_m": self.approach_m,
            "n_taxels": self.layout.n,
        }
        if self.depth_m == 0:
            out["pressure_pa"] = out["stress_pa"]  # at the surface, the contact pressure
        return out


def hertz(radius_m: float, e_star_pa: float, force_n: float) -> dict:
    """Hertz's sphere-on-flat solution: contact radius a, peak pressure p0, approach d."""
    a = (3 * force_n * radius_m / (4 * e_star_pa)) ** (1 / 3)
    return {
        "contact_radius_m": a,
        "peak_pressure_pa": 3 * force_n / (2 * math.pi * a * a),
        "approach_m": a * a / radius_m,
    }


def sphere_pad_size_m(radius_m: float, force_n: float, e_star_pa: float) -> float:
    """The side [m] of a spherical pad's node patch for a press: at least
    :data:`SPHERE_PAD_CONTACT_RADII` Hertz contact radii and :data:`SPHERE_PAD_MIN_M`, at
    most the sphere's diameter."""
    a = hertz(radius_m, e_star_pa, force_n)["contact_radius_m"]
    return min(2 * radius_m, max(SPHERE_PAD_MIN_M, SPHERE_PAD_CONTACT_RADII * a))


def press(
    finger: Finger,
    force_n: float,
    *,
    readout_pitch_m: float = 0.25e-3,
    node_pitch_m: float | None = None,
    plate: Plate | str = "finger7/flat",
    fidelity: str = "L1",
    depth_m: float = 0.0,
    slide_dir: tuple[float, float] = (1.0, 0.0),
    cache=None,
) -> PressResult:
    """Press ``finger`` with ``force_n`` [N] on ``plate`` (at its centre) and read a dense grid
    of taxels of side ``readout_pitch_m`` covering the pad, at the surface or ``depth_m``
    under it (then the vertical stress there). The skin's nodes are ``node_pitch_m`` apart
    (default: the readout pitch, at most 0.2 mm); ``fidelity`` L1 is the coupled skin (a
    half-space, or the finger's stack), L0 the Winkler bed. A finger with ``skin_tractions``
    is read as if sliding along ``slide_dir`` (a unit vector in the pad's plane): its skin
    carries the sliding friction against it, and buried taxels read that stress."""
    from ..hashing import one_blas_thread

    v.in_range("force_n", force_n, 1e-4, 100.0, unit="N")
    v.in_range("readout_pitch_m", readout_pitch_m, 20e-6, 5e-3, unit="m")
    if node_pitch_m is not None:
        v.in_range("node_pitch_m", node_pitch_m, 20e-6, 5e-3, unit="m")
    v.one_of("fidelity", fidelity, PRESS_LEVELS)
    v.in_range("depth_m", depth_m, 0.0, finger.thickness_m, hi_open=True, unit="m")
    if not np.isclose(math.hypot(*slide_dir), 1.0):
        raise ConfigError(f"slide_dir = {slide_dir}; valid: a unit vector (x, y)")
    plate = get_plate(plate) if isinstance(plate, str) else plate
    grid = skin_grid(finger, node_pitch_m or min(readout_pitch_m, 0.2e-3))
    px, py = finger.patch_m
    half = readout_pitch_m / 2
    layout = dense_layout(readout_pitch_m, (px / 2 - half, py / 2 - half), depth_m=depth_m)
    heights = surface_of(plate).height(grid.xy[:, 0], grid.xy[:, 1]) - grid.z
    z0 = APPROACH_CLEARANCE_M + max(0.0, float(np.nanmax(heights)))
    margin = surface_of(plate).margin_m
    scene = build_scene(
        plate,
        finger,
        grid,
        layout,
        dt_s=1e-3,
        x0_m=0.0,
        z0_m=z0,
        z_damping=0.0,
        node_margin_m=margin,
        slide_dir=slide_dir,
        cache=cache,
    )
    k_w = finger.e_star_pa / finger.thickness_m
    skin = make_skin(
        fidelity, grid, finger, winkler_k_pa_per_m=k_w, inverse=False, slide_dir=slide_dir
    )
    hold = PlainHeldStep(make_collider(scene), skin, scene.W, grid.area_m2, margin)
    qpos = np.zeros(scene.m_col.nq)
    taxel = np.zeros(layout.n)
    with one_blas_thread():
        total, top = hold.step(qpos, scene.jz, force_n / grid.area_m2, taxel)
    if top > finger.thickness_m:
        raise PhysicsError(
            f"skin pressed to the bottom: {force_n:g} N needs more than the skin thickness "
            f"{finger.thickness_m * 1e3:g} mm of indentation (lower the force or use a thicker skin)"
        )
    p = hold.p
    area = layout.sizes.prod(axis=1)
    n_contact = int(np.count_nonzero(p > 0))
    return PressResult(
        layout,
        taxel,
        taxel / area,
        total,
        math.sqrt(n_contact * grid.area_m2 / math.pi),
        float(p.max()),
        float(-(z0 + qpos[scene.jz])),
        n_contact * grid.area_m2,
        float(depth_m),
    )
