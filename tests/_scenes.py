"""The scenes and slides tests build by hand: the default finger on the grid3x3 layout over a
plate, through the session's artefact cache; a task's first slide of a plate (one
definition of each)."""

from __future__ import annotations

from dataclasses import replace

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


def task_slide(task: str, plate: str, duration_s: float | None, **proto):
    """The first slide of ``plate`` in ``task`` (its seed, sensor, fidelity and protocol),
    recording the ideal loads, its window shortened to ``duration_s`` where given."""
    from sim_tactile.sim import Slide
    from sim_tactile.tasks import get_task

    jobs = get_task(task).get_data.jobs(seed=0, quick=False)
    job = next(j for j in jobs if j.plate.name == plate)
    if duration_s is not None:
        proto = {"duration_s": duration_s, **proto}
    return Slide(
        job.plate,
        job.sensor_def,
        replace(job.protocol, **proto),
        job.seed,
        job.fidelity,
        True,
        job.finger,
        job.pitch_m,
        rig=job.rig,
    )


def ridges_on_shared_tables():
    """An L0 slide of grid3x3 over finger7's ridges, one of 25 of its plate: read off tables
    shared by force level, crossed from flat ground (its runner solves the steps off them)."""
    from sim_tactile.sim import Slide
    from sim_tactile.sim.plan.protocol import Protocol

    proto = Protocol(speed_m_s=0.06, force_jitter=0.1, duration_s=0.94)
    return Slide(get_plate("finger7/ridges-4"), "grid3x3", proto, 4, "L0", True, plate_slides=25)
