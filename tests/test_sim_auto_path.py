"""``path = auto`` against the per-step reference on one plate of every simulated task.

``auto`` is the default: it reads a held slide off a phase table, presses once to the
held equilibrium, or loosens a spectral skin's per-step solve (``solve_every``,
``solve_tol``), each only where its error against the per-step solve is measured within
2% (relative L2 of the taxel loads over a slide). Here every task's scene is run both
ways, on a plate whose slide touches its texture, and the default's loads must lie within
that target of the reference. The probe rig (multilayer3-v2) has its own slide, which
``auto`` leaves as it is.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from _scenes import task_slide

from sim_tactile.sim import Slide, StepOptions, run
from sim_tactile.sim.plan.options import AUTO_SOLVE_TOL, AUTO_TABLE_TOL
from sim_tactile.tasks import get_task, task_ids

#: The default's error target against the per-step solve (relative L2 over a slide).
REL_L2_TARGET = 0.02

STEP = StepOptions(path="per-step")

#: task, plate, window [s] (None: the task's), protocol changes; the path ``auto`` takes.
CASES = [
    pytest.param("finger7-v1", "finger7/bumps-4x4", 0.5, {}, "per-step", id="finger7-v1"),
    # from flat ground over ridges across the pad: the set's slides share the tables
    pytest.param("finger7-v1", "finger7/ridges-4", None, {}, "phase-table", id="finger7-v1-shared"),
    pytest.param("finger7-v2", "finger7/ridges-4", 0.3, {}, "per-step", id="finger7-v2"),
    pytest.param(
        "multilayer3-v1", "multilayer3/hemispheres-6x6", 0.4, {}, "per-step", id="multilayer3-v1"
    ),
    pytest.param("roughness8-v1", "roughness8/ra-50", 0.25, {}, "per-step", id="roughness8-v1"),
    pytest.param(
        "textures20-biotac19-v1",
        "textures20/hemispheres-4.5mm",
        None,
        {},
        "per-step",
        id="textures20-biotac19-v1",
    ),
    pytest.param(
        "textures20-icub60-v1",
        "textures20/boxes-4.5mm",
        None,
        {},
        "per-step",
        id="textures20-icub60-v1",
        marks=pytest.mark.slow,
    ),
    pytest.param(
        "textures20-icub60-v1",
        "textures20/hemispheres-6.0mm",
        0.4,
        {},
        "per-step",
        id="textures20-icub60-v1-spectral",
        marks=pytest.mark.slow,
    ),
    pytest.param(
        "textures20-biotac19-v2",
        "textures20-long/hemispheres-4.5mm",
        0.5,
        {},
        "phase-table",
        id="textures20-biotac19-v2",
    ),
    pytest.param(
        "textures20-icub60-v2",
        "textures20-long/grating-3.0mm",
        0.2,
        {},
        "phase-table",
        id="textures20-icub60-v2",
        marks=pytest.mark.slow,
    ),
]


def test_the_cases_cover_every_simulated_task():
    from sim_tactile.slides import SlideSet

    simulated = {t for t in task_ids() if isinstance(get_task(t).get_data, SlideSet)}
    covered = {p.values[0] for p in CASES} | {"multilayer3-v2"}
    assert covered == simulated


@pytest.mark.parametrize(("task", "plate", "duration", "changes", "path"), CASES)
def test_the_default_is_within_its_target_of_the_per_step_solve(
    task, plate, duration, changes, path, cache
):
    slide = task_slide(task, plate, duration, **changes)
    assert slide.how.path == path
    auto = run(slide, cache).recording
    step = run(replace(slide, options=STEP), cache).recording
    ref = step.data.astype(float)
    assert np.abs(ref).max() > 0  # the pad touched the plate
    rel = float(np.linalg.norm(auto.data.astype(float) - ref) / np.linalg.norm(ref))
    assert rel <= REL_L2_TARGET, f"{task} on {plate}: {rel:.2%} from the per-step solve"
    assert auto.meta["protocol"] == step.meta["protocol"]


def test_the_probe_rigs_slide_is_left_as_it_is():
    jobs = get_task("multilayer3-v2").get_data.jobs(seed=0, quick=True)
    slide = Slide(
        jobs[0].plate, jobs[0].sensor_def, jobs[0].protocol, jobs[0].seed, rig=jobs[0].rig
    )
    assert slide.rig is not None
    assert slide.how == replace(StepOptions(), path="per-step")
    assert not slide.held_press
    assert "path" not in slide.describe()


def test_a_flat_pads_full_dense_problem_is_solved_spectrally_and_keyed_so():
    """The iCub's flat pad on bumps: the dense solve's contact set starts as the whole face
    and pays |S|^2 for each node that leaves it, so ``auto`` solves the same problem
    spectrally, to its loosened tolerance: at every 2nd step on smooth caps, at every step
    on bumps with walls; its key says so. Problems that reduce by column (gratings), a
    curved pad (the BioTac) and the per-step reference stay dense."""
    icub = task_slide("textures20-icub60-v1", "textures20/hemispheres-6.0mm", None)
    assert not icub.spectral  # the dense solve by the node count
    how = icub.how
    assert (how.path, how.skin_solver, how.solve_every) == ("per-step", "spectral", 2)
    assert how.solve_tol == AUTO_SOLVE_TOL
    assert icub.describe()["skin_solver"] == "spectral"
    walls = task_slide("textures20-icub60-v1", "textures20/cylinders-4.5mm", None)
    assert not walls.spectral
    assert (walls.how.skin_solver, walls.how.solve_every) == ("spectral", 1)
    step = replace(icub, options=STEP)
    assert step.how.skin_solver == "auto" and step.describe() != icub.describe()
    grating = task_slide("textures20-icub60-v1", "textures20/grating-3.0mm", None)
    assert grating.how.skin_solver == "auto" and not grating.spectral
    biotac = task_slide("textures20-biotac19-v1", "textures20/hemispheres-6.0mm", None)
    assert biotac.how.skin_solver == "auto" and not biotac.spectral


def test_a_sensor_that_reports_vibration_is_solved_at_every_step(cache):
    """``pvdf2`` (piezoelectric: it reports the load's vibration) in a set of 40 slides a
    rough plate: ``auto`` would read a capacitive sensor's slide off the table along the
    profile, whose loads are within 2% but whose vibration is not; the piezoelectric
    sensor's slide is solved at every step, the reference's numbers bit for bit."""
    slide = replace(task_slide("roughness8-v1", "roughness8/ra-6.3", None), plate_slides=40)
    other = replace(slide, sensor="icub60")
    assert other.table_plan() is not None  # the set is large enough for the table
    assert slide.table_plan() is None and slide.how.path == "per-step"
    assert slide.how.solve_every == 1
    auto = run(slide, cache).recording
    step = run(replace(slide, options=STEP), cache).recording
    np.testing.assert_array_equal(auto.data, step.data)


@pytest.mark.parametrize(
    ("task", "plate"),
    [
        ("textures20-icub60-v1", "textures20/hemispheres-6.0mm"),
        ("textures20-icub60-v1", "textures20/grating-3.0mm"),
        ("textures20-icub60-v1", "textures20/flat"),
        ("textures20-biotac19-v1", "textures20/boxes-3.0mm"),
        ("roughness8-v1", "roughness8/ra-50"),
        ("multilayer3-v1", "multilayer3/hemispheres-6x6"),
    ],
)
def test_the_planners_reading_of_the_column_reduction_is_the_held_steps(task, plate, cache):
    """``depths_by_column`` (the planner's, from the plate's surface) agrees with the test the
    compiled held step makes on its collider (``y_invariant`` at the bone's offset)."""
    from sim_tactile.sim.collide.choose import make_collider
    from sim_tactile.sim.plan.phase import depths_by_column
    from sim_tactile.sim.step.build import scene_for

    slide = task_slide(task, plate, None)
    proto = slide.drawn()
    scene, _ = scene_for(slide, proto, slide.resolved, slide.window.x_start_m, cache)
    collider = make_collider(scene, True)
    columns = collider.y_invariant(float(collider.bone0[1]))
    assert depths_by_column(slide.plate, slide.pad.patch_m, proto.offset_y_m) == columns


def test_a_spectral_table_keeps_the_tighter_tolerance_and_a_stepped_slide_the_looser():
    """``auto`` solves a spectral skin's phase tables to AUTO_TABLE_TOL and a slide it steps
    to AUTO_SOLVE_TOL (the iCub on a v2 strip, and on a v1 plate)."""
    table = task_slide("textures20-icub60-v2", "textures20-long/boxes-4.5mm", None)
    assert table.spectral and table.how.path == "phase-table"
    assert table.how.solve_tol == AUTO_TABLE_TOL
    stepped = task_slide("textures20-icub60-v1", "textures20/boxes-4.5mm", None)
    assert stepped.spectral and stepped.how.path == "per-step"
    assert stepped.how.solve_tol == AUTO_SOLVE_TOL != AUTO_TABLE_TOL
