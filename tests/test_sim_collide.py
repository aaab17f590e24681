"""The primitive collider against MuJoCo's collider: the same penetration-depth map."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from sim_tactile.plates import get_plate
from sim_tactile.scene.model import build_scene
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import Finger, get_layout
from sim_tactile.sim.collide import (
    MujocoCollider,
    PrimitiveCollider,
    make_collider,
    penetration_map,
)
from sim_tactile.sim.protocol import Protocol
from sim_tactile.sim.runner import StepOptions
from sim_tactile.sim.simulate import simulate


def _scene(plate: str, margin: float, cache):
    f = Finger()
    grid = skin_grid(f, 1e-3)
    return build_scene(
        get_plate(plate),
        f,
        grid,
        get_layout("grid3x3"),
        dt_s=1e-3,
        x0_m=-0.02,
        z0_m=1e-3,
        z_damping=1.0,
        node_margin_m=margin,
        cache=cache,
    )


@pytest.mark.parametrize("margin", [0.0, 0.5e-3])
@pytest.mark.parametrize(
    "plate",
    [
        "finger7/ridges-4",
        "finger7/bumps-6x6",
        "multilayer3/hemispheres-6x6",
        "textures20/boxes-3.0mm",
    ],
)
def test_depth_map_equals_mujocos(plate, margin, cache):
    sc = _scene(plate, margin, cache)
    bone = sc.m_col.body("bone").id
    col = PrimitiveCollider.from_model(sc.m_col, sc.node_of_geom, bone)
    assert col is not None
    d = mujoco.MjData(sc.m_col)
    rng = np.random.default_rng(0)
    ours, ref = np.empty(sc.n_nodes), np.empty(sc.n_nodes)
    touched = 0
    for _ in range(100):
        d.qpos[0] = rng.uniform(0, 0.04)  # along the plate
        d.qpos[1] = rng.uniform(-3.5e-3, 0.5e-3)  # from above the features into them
        mujoco.mj_kinematics(sc.m_col, d)
        mujoco.mj_collision(sc.m_col, d)
        penetration_map(d.contact.geom, d.contact.dist, sc.node_of_geom, ref)
        col.depths(d.xpos[bone].copy(), ours)
        # a node exactly at the margin is a tie MuJoCo may break either way
        tie = np.isclose(np.where(np.isfinite(ours), ours, ref), -margin, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(ours[~tie], ref[~tie])
        touched += int((ref > 0).sum())
    assert touched > 1000  # the poses did press nodes into the plate


def test_the_colliders_answer_alike_from_the_joints(cache):
    """depths_at(qpos) of both colliders, bound to the scene's joints, against each other."""
    sc = _scene("finger7/ridges-4", 0.5e-3, cache)
    prim, ref = make_collider(sc), make_collider(sc, primitive=False)
    assert isinstance(prim, PrimitiveCollider) and isinstance(ref, MujocoCollider)
    qpos = np.zeros(sc.m_col.nq)
    a, b = np.empty(sc.n_nodes), np.empty(sc.n_nodes)
    for x in np.linspace(0.0, 0.04, 30):
        qpos[sc.jx], qpos[sc.jz] = x, -2.5e-3
        assert prim.depths_at(qpos, a) == ref.depths_at(qpos, b)
        np.testing.assert_array_equal(a, b)
    assert ref.warnings() == [] and prim.warnings() == []


def test_meshes_and_height_fields_keep_mujocos_collider(cache):
    for plate in ("multilayer3/grating-9", "roughness8/ra-50"):
        sc = _scene(plate, 0.0, cache)
        bone = sc.m_col.body("bone").id
        assert PrimitiveCollider.from_model(sc.m_col, sc.node_of_geom, bone) is None
        assert isinstance(make_collider(sc), MujocoCollider)


@pytest.mark.parametrize("force_control", ["dynamic", "quasi-static"])
def test_a_slide_is_bit_identical_with_either_collider(force_control, cache):
    proto = Protocol(duration_s=0.4, force_control=force_control)

    def run(options):
        return simulate(
            "finger7/ridges-4", "grid3x3", protocol=proto, ideal=True, options=options, cache=cache
        ).recording

    # the plain held loop over both colliders: only the collider differs
    fast = run(StepOptions(compiled_hold=False))
    slow = run(StepOptions(primitive_collider=False))
    assert fast.data.tobytes() == slow.data.tobytes()
    assert fast.data.max() > 0
