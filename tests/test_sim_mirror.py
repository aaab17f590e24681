"""A phase table solved over half a period and mirrored (sim/plan/phase.py::mirror_centre,
sim/step/mirror.py): the plate's symmetry found from its features and checked on its own
surface heights, the pad's node images, and the mirror image of a held step against the
held step solved at the mirrored position (the physics the mirror stands for)."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from _scenes import task_slide

from sim_tactile.plates import get_plate
from sim_tactile.plates.define.geometry import Feature
from sim_tactile.plates.define.surface import surface_of
from sim_tactile.sim.plan import phase as phase_module
from sim_tactile.sim.plan.phase import PhasePlan, mirror_centre, phase_plan
from sim_tactile.sim.step.build import runner_for
from sim_tactile.sim.step.mirror import mirror_symmetric, mirrored_loads, node_images

#: A held step's image against the step solved at the image position (relative L2 of the
#: taxel loads): measured 4e-15 on the dense step (round-off) and 2e-7 on the spectral one
#: (its tolerance, 1e-4 of the pressures' change a step, in single-precision products).
IMAGE_RTOL = 1e-5


@pytest.mark.parametrize(
    "plate",
    [
        "textures20-long/boxes-4.5mm",
        "textures20-long/cylinders-3.0mm",
        "textures20-long/hemispheres-6.0mm",
        "textures20-long/grating-3.0mm-draft30",
        "multilayer3/grating-9",
    ],
)
def test_the_centre_found_is_a_symmetry_of_the_plates_own_surface(plate):
    p = get_plate(plate)
    plan, why = phase_plan(p, (20e-3, 10e-3), 0.0, "quasi-static")
    assert plan is not None, why
    c = mirror_centre(p, plan)
    assert c is not None
    c += round((0.5 * (plan.x_lo + plan.x_hi) - c) / plan.period_m) * plan.period_m  # mid-plate
    rng = np.random.default_rng(1)
    u = rng.uniform(0.0, 2 * plan.period_m, 4000)
    y = rng.uniform(-p.area_width_m / 2, p.area_width_m / 2, 4000)
    h = surface_of(p)
    inside = (c + u < plan.x_hi) & (c - u > plan.x_lo)
    assert inside.sum() > 1000
    a, b = h.height(c + u[inside], y[inside]), h.height(c - u[inside], y[inside])
    assert a.max() > 0  # the points met the features
    assert np.allclose(a, b, rtol=0.0, atol=1e-12)


def test_an_arrangement_without_a_mirror_has_no_centre(monkeypatch):
    """Two boxes a period of different widths, placed off-centre: no axis maps them onto
    themselves. The same boxes at the same widths placed evenly have one."""
    period = 4e-3

    def boxes(x2: float, hx2: float) -> list[Feature]:
        return [
            f
            for k in range(-3, 4)
            for f in (
                Feature("box", k * period, 0.0, 0.5e-3, 5e-3, 1e-3),
                Feature("box", k * period + x2, 0.0, hx2, 5e-3, 1e-3),
            )
        ]

    plan = PhasePlan(period, -6e-3, 6e-3, -6e-3, 0.0)
    fake = SimpleNamespace(features=boxes(1.5e-3, 0.25e-3))
    monkeypatch.setattr(phase_module, "surface_of", lambda plate: fake)
    assert mirror_centre(None, plan) is None
    fake.features = boxes(2e-3, 0.25e-3)  # the second box half a period on: symmetric
    c = mirror_centre(None, plan)
    assert c is not None and round((c % 2e-3) / 1e-9) in (0, 2_000_000)


def test_each_node_has_its_image_across_the_pad_centre_line_or_none_is_given():
    xs, ys = np.meshgrid(np.linspace(-2e-3, 2e-3, 5), np.linspace(-1e-3, 1e-3, 3))
    local = np.column_stack([xs.ravel(), ys.ravel(), np.abs(xs.ravel()) * 0.1])
    radius, margin = np.full(15, 1e-4), np.full(15, 5e-4)
    img = node_images(local, radius, margin)
    assert img is not None
    assert np.array_equal(img[img], np.arange(15))  # an involution
    assert np.array_equal(local[img, 0], -local[:, 0])
    assert np.array_equal(local[img, 1:], local[:, 1:])
    bent = local.copy()
    bent[3, 2] += 1e-9  # one node's height off its image's
    assert node_images(bent, radius, margin) is None
    wide = radius.copy()
    wide[0] *= 2
    assert node_images(local, wide, margin) is None


def test_a_compliance_that_leans_along_the_slide_is_no_mirror():
    """A half-space-like compliance (a function of the nodes' distance) is its own mirror
    image; one with a lean along the slide, as sliding friction gives a skin, is not."""
    xs, ys = np.meshgrid(np.arange(-6, 7) * 0.5e-3, np.arange(-2, 3) * 0.5e-3)
    local = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)])
    img = node_images(local, np.full(xs.size, 1e-4), np.full(xs.size, 5e-4))
    d = np.hypot(*(local[:, None, :2] - local[None, :, :2]).transpose(2, 0, 1))
    C = 1.0 / (d + 2e-4)
    assert mirror_symmetric(C, img)
    lean = C * (1.0 + 0.1 * np.tanh((local[:, None, 0] - local[None, :, 0]) / 1e-3))
    assert not mirror_symmetric(lean, img)


def _table_scene(task: str, plate: str):
    """The scene a table of the task's first slide of ``plate`` (from the texture) is solved
    in, its plan and the plate's mirror centre; ``task`` None: the grid3x3 pad at a 0.5 mm
    pitch (a small dense skin) on ``plate``."""
    if task is None:
        from sim_tactile.plates import get_plate
        from sim_tactile.sensors import get_sensor
        from sim_tactile.sim import Protocol, Slide

        proto = Protocol(start="texture", duration_s=0.2, speed_m_s=0.04)
        slide = Slide(get_plate(plate), get_sensor("grid3x3"), proto, 0, "auto", True, None, 5e-4)
    else:
        slide = task_slide(task, plate, 0.2, start="texture")
    plan = slide.table_plan()
    proto = replace(slide.drawn(), offset_y_m=plan.y_m)
    scene = runner_for(slide, proto, slide.resolved, plan.x_ref, None)
    return slide, scene, plan, mirror_centre(slide.plate, plan)


@pytest.mark.parametrize(
    ("task", "plate"),
    [
        (None, "textures20-long/cylinders-3.0mm"),  # the dense compiled step
        pytest.param(
            "textures20-icub60-v2",
            "textures20-long/boxes-4.5mm",  # the spectral step, its offset its own
            marks=pytest.mark.slow,
        ),
    ],
)
def test_the_image_of_a_held_step_is_the_step_solved_at_the_mirrored_position(task, plate):
    slide, scene, plan, c = _table_scene(task, plate)
    assert c is not None
    write = mirrored_loads(scene.hold, scene.collider, scene.skin)
    assert write is not None
    q0 = scene.d_dyn.qpos.copy()
    total = slide.drawn().force_n / scene.s.grid.area_m2  # as a table holds it
    n = scene.s.layout.n
    for u in (0.37e-3, 1.1e-3):
        loads = {}
        for sign in (1.0, -1.0):
            q = q0.copy()
            q[scene._jx] = c + sign * u - plan.x_ref
            out = np.zeros(n)
            for _ in range(8):  # settled, as a table's phase is
                z = float(q[scene._jz])
                force, _top = scene.hold.step(q, scene._jz, total, out)
                if abs(float(q[scene._jz]) - z) < 1e-9:
                    break
            image = np.zeros(n)
            write(image)
            loads[sign] = (out, image, force)
        (direct_p, image_p, f_p), (direct_m, image_m, f_m) = loads[1.0], loads[-1.0]
        assert np.abs(direct_p).max() > 0
        assert np.isclose(f_p, f_m, rtol=IMAGE_RTOL)
        scale = np.linalg.norm(direct_m)
        assert np.linalg.norm(image_p - direct_m) <= IMAGE_RTOL * scale
        assert np.linalg.norm(image_m - direct_p) <= IMAGE_RTOL * scale
        # and the image is not the direct answer: the pad at c + u is not at c - u
        assert np.linalg.norm(direct_p - direct_m) > 10 * IMAGE_RTOL * scale


def test_a_dense_step_over_ridges_across_the_pad_solves_the_whole_period():
    """Its images were measured to read further from the per-step slide than the whole
    period (a column meets a wall at once, and the height it settles to there depends on
    the side the pad came from): no mirror is offered for it."""
    _, scene, _, c = _table_scene("multilayer3-v1", "multilayer3/grating-9")
    assert c is not None and scene.hold.columns  # the plate is symmetric, the step by columns
    assert mirrored_loads(scene.hold, scene.collider, scene.skin) is None
