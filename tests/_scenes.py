"""The scene the collider and held-step tests build by hand: the default finger on the grid3x3
layout over a plate, through the session's artefact cache (one definition of it)."""

from __future__ import annotations

from sim_tactile.plates import Plate, get_plate
from sim_tactile.scene.model import Scene, build_scene
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import Finger, get_layout


def scene_of(
    plate: Plate | str,
    margin_m: float,
    cache,
    *,
    pitch: tuple[float, ...] = (1e-3,),
    dt_s: float = 1e-3,
    x0_m: float = -0.02,
) -> Scene:
    """The scene of ``plate`` (a plate or a preset's name) with the skin nodes' collider
    margin ``margin_m`` [m], nodes at ``pitch`` (x, and y if given) [m], the bone's time step
    ``dt_s`` [s], the pad centred at ``x0_m`` on the plate and 1 mm above it."""
    f = Finger()
    return build_scene(
        get_plate(plate) if isinstance(plate, str) else plate,
        f,
        skin_grid(f, *pitch),
        get_layout("grid3x3"),
        dt_s=dt_s,
        x0_m=x0_m,
        z0_m=1e-3,
        z_damping=1.0,
        node_margin_m=margin_m,
        cache=cache,
    )
