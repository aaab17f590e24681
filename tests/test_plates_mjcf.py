"""Every preset's MJCF compiles, holds one geom per feature, and a dropped probe sphere
settles where the collision geometry says, with no MuJoCo warning."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from sim_tactile.errors import GeometryError
from sim_tactile.plates import build, get_plate, preset_names, surface_of
from sim_tactile.plates.make.mjcf import check_convex, geom_counts, plate_spec
from sim_tactile.plates.make.probe import ColliderProbe

MM = 1e-3
DROP_RADIUS_M = 1.5 * MM
DT_S = 0.5e-3
#: Stiff contact that held at dt = 0.5 ms (docs/physics.md, "Plates as MuJoCo geometry").
SOLREF = (0.002, 1.0)
SOLIMP = (0.95, 0.99, 0.0001, 0.5, 2.0)
#: Under that contact (the ball's, by priority) a ball sinks about g * tc^2 = 40 um; allow 60 um.
SETTLE_TOL_M = 0.06 * MM
#: Sliding, torsional [m] and rolling [m] friction, so a ball in a rough valley stops rolling.
ROLL_FRICTION = (1.0, 0.005, 0.0005)


def _drop_points(plate) -> list[tuple[float, float]]:
    pts = [(-45 * MM, 0.0)]  # flat run-in
    fs = surface_of(plate).features
    if not fs:
        pts.append((0.0, 0.0))
    elif fs[0].kind == "cap":
        rows = sum(1 for f in fs if f.x == fs[0].x)
        block = [fs[0], fs[1], fs[rows], fs[rows + 1]]  # a pocket between four caps
        pts.append((float(np.mean([f.x for f in block])), float(np.mean([f.y for f in block]))))
    else:
        pts.append((fs[len(fs) // 2].x, fs[len(fs) // 2].y))  # on a flat feature top
    return pts


def _drop(
    xml: str, x: float, y: float, z0: float
) -> tuple[np.ndarray, mujoco.MjData, mujoco.MjModel]:
    spec = mujoco.MjSpec.from_string(xml)
    spec.option.timestep = DT_S
    ball = spec.worldbody.add_body(name="ball", pos=(x, y, z0))
    ball.add_freejoint()
    ball.add_geom(
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        size=(DROP_RADIUS_M, 0, 0),
        density=7800,
        solref=SOLREF,
        solimp=SOLIMP,
        condim=6,
        friction=ROLL_FRICTION,
        priority=1,
    )
    m = spec.compile()
    d = mujoco.MjData(m)
    for _ in range(int(0.4 / DT_S)):
        mujoco.mj_step(m, d)
    return d.qpos[:3].copy(), d, m


@pytest.mark.parametrize(
    "name",
    [  # the long strips repeat their short plates: they run in ``make test`` only
        pytest.param(n, marks=pytest.mark.slow) if n.startswith("textures20-long/") else n
        for n in preset_names()
    ],
)
def test_mjcf_compiles_and_a_dropped_sphere_settles(name, cache):
    plate = get_plate(name)
    xml = build(plate, kinds=("mjcf",), cache=cache).files["mjcf"].read_text()
    m = mujoco.MjModel.from_xml_string(xml)
    assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "plate") >= 0
    counts = geom_counts(m)
    n_feat = len(surface_of(plate).features)
    assert sum(counts.values()) == n_feat + (4 if counts.get("hfield") else 1)
    probe = ColliderProbe(xml, radius_m=DROP_RADIUS_M)
    for x, y in _drop_points(plate):
        pos, d, m2 = _drop(xml, x, y, 0.012)
        assert not any(w.number for w in d.warning), [
            mujoco.mjtWarning(i).name for i, w in enumerate(d.warning) if w.number
        ]
        assert np.isfinite(d.qpos).all()
        assert np.linalg.norm(d.qvel[:3]) < 1e-3  # at rest
        expected = probe.height(pos[0], pos[1]) + DROP_RADIUS_M
        assert pos[2] == pytest.approx(expected, abs=SETTLE_TOL_M), (x, y, pos)
        assert expected >= -1e-9  # rests on the plate, not inside it


def test_one_geom_per_feature_and_primitives_where_exact():
    assert geom_counts(plate_spec(get_plate("finger7/bumps-6x6"))) == {"box": 37}
    assert geom_counts(plate_spec(get_plate("multilayer3/hemispheres-6x6"))) == {
        "box": 1,
        "sphere": 36,
    }
    assert geom_counts(plate_spec(get_plate("multilayer3/grating-9"))) == {"box": 1, "mesh": 9}
    assert geom_counts(plate_spec(get_plate("textures20/cylinders-4.5mm"))) == {
        "box": 1,
        "cylinder": 64,
    }
    assert geom_counts(plate_spec(get_plate("roughness8/ra-50"))) == {"box": 3, "hfield": 1}


def test_convexity_check_rejects_a_dented_mesh():
    cube = np.array([(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    check_convex(cube)
    with pytest.raises(GeometryError, match="not convex"):
        check_convex(np.vstack([cube, [[0.5, 0.5, 0.5]]]))
    with pytest.raises(GeometryError, match="degenerate"):
        check_convex(cube * [1, 1, 0])  # a flat square
