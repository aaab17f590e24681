"""Static indentation: press a finger on a plate to a normal force and read the pressure.

The bone's height is found by root finding so that the skin's total load equals the force;
the penetration-depth map comes from MuJoCo's collider (the same scene as :func:`simulate`),
and the skin's response from the chosen contact model (half-space by default). With a
spherical pad on a flat plate this is Hertz's problem, which the tests check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from .. import _validate as v
from ..errors import PhysicsError
from ..plates import Plate, get_plate
from ..scene.model import build_scene
from ..scene.nodes import skin_grid
from ..sensors.layouts import Layout, dense_layout
from ..sensors.pad import Finger
from . import contact
from ._readout import penetration_map


@dataclass
class PressResult:
    layout: Layout
    taxel_load_n: np.ndarray  # (M,)
    pressure_pa: np.ndarray  # (M,) taxel load / taxel area
    total_force_n: float
    contact_radius_m: float  # sqrt(contact area / pi) from the skin nodes in contact
    peak_pressure_pa: float  # largest node pressure
    approach_m: float

    def to_json(self) -> dict:
        return {
            "taxels": self.layout.positions[:, :2].tolist(),
            "pressure_pa": self.pressure_pa.tolist(),
            "total_force_n": self.total_force_n,
            "contact_radius_m": self.contact_radius_m,
            "peak_pressure_pa": self.peak_pressure_pa,
            "approach_m": self.approach_m,
            "n_taxels": self.layout.n,
        }


def hertz(radius_m: float, e_star_pa: float, force_n: float) -> dict:
    """Hertz's sphere-on-flat solution: contact radius a, peak pressure p0, approach d."""
    a = (3 * force_n * radius_m / (4 * e_star_pa)) ** (1 / 3)
    return {
        "contact_radius_m": a,
        "peak_pressure_pa": 3 * force_n / (2 * math.pi * a * a),
        "approach_m": a * a / radius_m,
    }


def press(
    finger: Finger,
    force_n: float,
    *,
    pitch_m: float = 0.25e-3,
    node_pitch_m: float | None = None,
    plate: Plate | str = "finger7/flat",
    coupled: bool = True,
    cache=None,
) -> PressResult:
    """Press ``finger`` with ``force_n`` on ``plate`` (at its centre) and read a dense grid of
    surface taxels of side ``pitch_m`` covering the pad."""
    from threadpoolctl import threadpool_limits

    v.in_range("force_n", force_n, 1e-4, 100.0, unit="N")
    v.in_range("pitch_m", pitch_m, 20e-6, 5e-3, unit="m")
    plate = get_plate(plate) if isinstance(plate, str) else plate
    node_pitch = node_pitch_m or min(pitch_m, 0.2e-3)
    grid = skin_grid(finger, node_pitch)
    px, py = finger.patch_m
    layout = dense_layout(pitch_m, (px / 2 - pitch_m / 2, py / 2 - pitch_m / 2))
    top = 0.02
    scene = build_scene(
        plate,
        finger,
        grid,
        layout,
        dt_s=1e-3,
        x0_m=0.0,
        z0_m=top,
        z_damping=0.0,
        coupled=coupled,
        inverse=False,
        cache=cache,
    )
    d = mujoco.MjData(scene.m_col)
    k_w = finger.e_star_pa / finger.thickness_m

    def pen_at(z: float) -> np.ndarray:
        d.qpos[:] = 0.0
        d.qpos[scene.jz] = z - top
        mujoco.mj_kinematics(scene.m_col, d)
        mujoco.mj_collision(scene.m_col, d)
        pen = np.empty(grid.n)
        if d.ncon:
            penetration_map(d.contact.geom, d.contact.dist, scene.node_of_geom, pen)
        else:
            pen[:] = -np.inf
        return pen

    state = {"active": None}

    def solve(z: float):
        pen = pen_at(z)
        if coupled:
            p, state["active"] = contact.halfspace(pen, scene.C, state["active"], scene.K)
        else:
            p = contact.winkler(pen, k_w)
        return p, pen

    with threadpool_limits(limits=1, user_api="blas"):
        # bisection on the height of the pad's lowest point: load falls as it rises
        lo, hi = -finger.thickness_m, 0.005
        f_lo = solve(lo)[0].sum() * grid.area_m2
        if f_lo < force_n:
            raise PhysicsError(
                f"skin pressed to the bottom: {force_n:g} N needs more than the skin thickness "
                f"{finger.thickness_m * 1e3:g} mm of indentation (lower the force or use a thicker skin)"
            )
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            f = solve(mid)[0].sum() * grid.area_m2
            if f > force_n:
                lo = mid
            else:
                hi = mid
            if hi - lo < 1e-10:
                break
        z = 0.5 * (lo + hi)
        p, pen = solve(z)
    loads = p * grid.area_m2
    total = float(loads.sum())
    taxel = scene.W @ loads
    area = layout.sizes.prod(axis=1)
    n_contact = int(np.count_nonzero(p > 0))
    return PressResult(
        layout,
        taxel,
        taxel / area,
        total,
        math.sqrt(n_contact * grid.area_m2 / math.pi),
        float(p.max()),
        float(-z),
    )
