"""A slide's scene and the runner that steps it, built in one place (:func:`runner_for`):
the plate's MuJoCo scene with the pad at its start, the skin model of the fidelity, the
collider, the held step (:func:`~.choose.make_held_step`) and the runner over them."""

from __future__ import annotations

import math

import numpy as np

from ...plates import Plate, surface_of
from ...scene.model import build_scene, dynamics_model
from ...scene.nodes import SkinGrid, skin_grid
from ..collide.choose import make_collider
from ..plan.fidelity import Fidelity, flat_stiffness
from ..plan.protocol import APPROACH_CLEARANCE_M, Protocol
from ..plan.slide import Slide
from ..skin.models import make_skin
from .choose import make_held_step
from .runner import Runner


def scene_for(slide: Slide, proto: Protocol, fid: Fidelity, x0_m: float, cache):
    """``(scene, z0)``: the scene with the pad centred at ``x0_m`` (the slide's start; a
    phase table's reference) and ``proto.offset_y_m``, its lowest point ``z0`` [m] above the
    plate's highest point under it."""
    args, kw, z0 = _scene_args(slide, proto, fid, x0_m, cache)
    return build_scene(*args, slide.layout, **kw), z0


def dynamics_for(slide: Slide, proto: Protocol, fid: Fidelity, x0_m: float, cache):
    """``(m_dyn, jx, jz)``: the dynamics model of :func:`scene_for`'s scene, alone."""
    args, kw, _ = _scene_args(slide, proto, fid, x0_m, cache)
    return dynamics_model(*args, **kw)


def _scene_args(slide: Slide, proto: Protocol, fid: Fidelity, x0_m: float, cache):
    """The arguments of the scene of :func:`scene_for`: ``((plate, finger, grid), keywords,
    z0)``."""
    plate, finger = slide.plate, slide.pad
    grid = skin_grid(finger, fid.pitch_m, fid.pitch_y_m)
    z0 = APPROACH_CLEARANCE_M + max(
        0.0, float(np.nanmax(_plate_heights(plate, grid, x0_m, proto.offset_y_m)))
    )
    omega_guess = math.sqrt(
        flat_stiffness(finger, fid.coupled, fid.winkler_k_pa_per_m) / finger.bone_mass_kg
    )
    quasi_static = proto.force_control == "quasi-static"
    kw = dict(
        dt_s=fid.dt_s,
        x0_m=x0_m,
        y0_m=proto.offset_y_m,
        z0_m=z0,
        z_damping=2.0 * omega_guess * finger.bone_mass_kg,  # critical at the flat pad
        node_margin_m=slide.surface.margin_m if quasi_static else 0.0,
        cache=cache,
    )
    return (plate, finger, grid), kw, z0


def runner_for(slide: Slide, proto: Protocol, fid: Fidelity, x0_m: float, cache) -> Runner:
    """The scene of :func:`scene_for`, its skin model and the runner that steps it."""
    plate, layout, finger, options = slide.plate, slide.layout, slide.pad, slide.how
    scene, z0 = scene_for(slide, proto, fid, x0_m, cache)
    quasi_static = proto.force_control == "quasi-static"
    skin = make_skin(
        fid.level,
        scene.grid,
        finger,
        winkler_k_pa_per_m=fid.winkler_k_pa_per_m,
        solver=options.skin_solver,
        tol=options.solve_tol,
        cache=cache,
    )
    collider = make_collider(scene, options.primitive_collider)
    hold = make_held_step(
        scene,
        skin,
        collider,
        fid,
        plate=plate,
        layout=layout,
        finger=finger,
        quasi_static=quasi_static,
        x0_m=x0_m,
        y0_m=proto.offset_y_m,
        z0_m=z0,
        compiled=options.compiled_hold,
        reduce=options.reduce_skin,
        joint=options.held_solve == "joint",
    )
    return Runner(
        scene,
        skin,
        fid,
        finger,
        fid.dt_s,
        collider=collider,
        z0_m=z0,
        plate=plate,
        quasi_static=quasi_static,
        hold=hold,
    )


def _plate_heights(plate: Plate, grid: SkinGrid, x: float, y: float) -> np.ndarray:
    return surface_of(plate).height(grid.xy[:, 0] + x, grid.xy[:, 1] + y) - grid.z
