"""The primitive collider against MuJoCo's collider: the same penetration-depth map."""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest
from _scenes import scene_of

from sim_tactile.plates import get_plate, surface_of
from sim_tactile.plates.define.surface import ProfileArrays
from sim_tactile.scene.model import build_scene
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import get_layout, get_sensor
from sim_tactile.sim.collide.choose import make_collider, probe_depths
from sim_tactile.sim.collide.height import SurfaceCollider, interp_at
from sim_tactile.sim.collide.primitive import PrimitiveCollider
from sim_tactile.sim.collide.reference import MujocoCollider, penetration_map
from sim_tactile.sim.collide.shapes import cylinder_distance, ridge_distance
from sim_tactile.sim.plan.fidelity import choose_fidelity
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.slide import simulate
from sim_tactile.sim.step.runner import StepOptions


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
    sc = scene_of(plate, margin, cache)
    bone = sc.m_col.body("bone").id
    col = PrimitiveCollider.from_model(sc.m_col, sc.node_of_geom, bone)
    assert col is not None
    d = mujoco.MjData(sc.m_col)
    rng = np.random.default_rng(0)
    ours, ref = np.empty(sc.n_nodes), np.empty(sc.n_nodes)
    touched = deep = 0
    for _ in range(100):
        d.qpos[0] = rng.uniform(0, 0.04)  # along the plate
        d.qpos[1] = rng.uniform(-3.5e-3, 0.5e-3)  # from above the features into them
        mujoco.mj_kinematics(sc.m_col, d)
        mujoco.mj_collision(sc.m_col, d)
        penetration_map(d.contact.geom, d.contact.dist, sc.node_of_geom, ref)
        col.depths(d.xpos[bone].copy(), ours)
        # a node exactly at the margin is a tie MuJoCo may break either way
        tie = np.isclose(np.where(np.isfinite(ours), ours, ref), -margin, rtol=0, atol=1e-12)
        # over a box's footprint, below its top, ours is the depth below the top (the
        # height map's); MuJoCo's is to the nearest face, never deeper
        inside = _under_a_box_top(col, d.xpos[bone])
        np.testing.assert_array_equal(ours[~tie & ~inside], ref[~tie & ~inside])
        assert (ours[inside] >= ref[inside]).all()
        centre = d.xpos[bone] + col.local
        top = _box_top(col, centre)
        vertical = top - (centre[:, 2] - col.radius)  # a sphere (cap) may reach deeper
        np.testing.assert_allclose(
            ours[inside], np.maximum(vertical, ref)[inside], rtol=0, atol=1e-12
        )
        touched += int((ref > 0).sum())
        deep += int((ours[inside] > ref[inside]).sum())
    assert touched > 1000  # the poses did press nodes into the plate
    if plate != "multilayer3/hemispheres-6x6":
        assert deep > 0  # and some into a box deeper than its nearest side


def _box_top(col, centre):
    """The highest top face of the upright boxes over each point's footprint [m] (-inf
    where none)."""
    top = np.full(len(centre), -np.inf)
    for g in range(len(col.kind)):
        if col.kind[g] != 6 or abs(col.mat[g, 2, 2] - 1) > 1e-12:
            continue
        loc = (centre - col.pos[g]) @ col.mat[g]
        over = (np.abs(loc[:, 0]) <= col.size[g, 0]) & (np.abs(loc[:, 1]) <= col.size[g, 1])
        top = np.where(over, np.maximum(top, col.pos[g, 2] + col.size[g, 2]), top)
    return top


def _under_a_box_top(col, bone):
    """Nodes whose centre lies over a box's footprint and below its top."""
    centre = bone + col.local
    return centre[:, 2] < _box_top(col, centre)


def test_the_colliders_answer_alike_from_the_joints(cache):
    """depths_at(qpos) of both colliders, bound to the scene's joints, against each other."""
    sc = scene_of("finger7/ridges-4", 0.5e-3, cache)
    prim, ref = make_collider(sc), make_collider(sc, primitive=False)
    assert isinstance(prim, PrimitiveCollider) and isinstance(ref, MujocoCollider)
    qpos = np.zeros(sc.m_col.nq)
    a, b = np.empty(sc.n_nodes), np.empty(sc.n_nodes)
    for x in np.linspace(0.0, 0.04, 30):
        qpos[sc.jx], qpos[sc.jz] = x, -2.5e-3
        assert prim.depths_at(qpos, a) == ref.depths_at(qpos, b)
        inside = _under_a_box_top(prim, prim.bone0 + [qpos[sc.jx], 0.0, qpos[sc.jz]])
        np.testing.assert_array_equal(a[~inside], b[~inside])
        assert (a[inside] >= b[inside]).all()
    assert ref.warnings() == [] and prim.warnings() == []


def test_every_preset_kind_takes_a_compiled_collider(cache):
    """Drafted ridges (meshes) and cylinders take the compiled collider, roughness the height
    map; MuJoCo's stays the reference, and the collider of a mesh that is not one of the
    plate's drafted ridges."""
    for plate in ("multilayer3/grating-9", "textures20/cylinders-3.0mm"):
        sc = scene_of(plate, 0.0, cache)
        assert isinstance(make_collider(sc), PrimitiveCollider)
        assert isinstance(make_collider(sc, primitive=False), MujocoCollider)
    sc = scene_of("multilayer3/grating-9", 0.0, cache)
    bone = sc.m_col.body("bone").id
    # without the plate's features a mesh is any mesh: MuJoCo's collider serves
    assert PrimitiveCollider.from_model(sc.m_col, sc.node_of_geom, bone) is None
    sc = scene_of("roughness8/ra-50", 0.0, cache)
    c = make_collider(sc)
    assert isinstance(c, SurfaceCollider) and isinstance(c.probe.surface, ProfileArrays)
    assert isinstance(make_collider(sc, primitive=False), MujocoCollider)  # the reference


#: How far MuJoCo's depth may lie from ours where both are exact signed distances: cylinders
#: to rounding; drafted ridges to MuJoCo's mesh penetration, which its convex solver finds
#: approximately (measured 4.5e-7 m off, where ours equals a brute-force distance: below)
EXACT_ATOL_M = {"textures20/cylinders-3.0mm": 1e-15, "multilayer3/grating-9": 1e-6}


@pytest.mark.parametrize("margin", [0.0, 0.5e-3])
@pytest.mark.parametrize(
    "plate",
    ["multilayer3/grating-9", "textures20/grating-3.0mm-draft30", "textures20/cylinders-3.0mm"],
)
def test_ridges_and_cylinders_against_mujoco_and_the_height_map(plate, margin, cache):
    """At random poses: a node whose centre lies above the plate's surface reads MuJoCo's
    depth (within :data:`EXACT_ATOL_M`); one whose centre lies below it reads the depth below
    the height map at its centre, or MuJoCo's where a neighbouring geom reaches deeper (never
    less than MuJoCo's nearest face); the same nodes are reported."""
    sc = scene_of(plate, margin, cache)
    atol = EXACT_ATOL_M.get(plate, 1e-6)
    bone = sc.m_col.body("bone").id
    col = PrimitiveCollider.from_model(sc.m_col, sc.node_of_geom, bone, sc.plate)
    assert col is not None
    d = mujoco.MjData(sc.m_col)
    rng = np.random.default_rng(0)
    ours, ref = np.empty(sc.n_nodes), np.empty(sc.n_nodes)
    above = under = deeper = 0
    for _ in range(60):
        d.qpos[0] = rng.uniform(0, 0.04)
        d.qpos[1] = rng.uniform(-3.5e-3, 0.5e-3)
        mujoco.mj_kinematics(sc.m_col, d)
        mujoco.mj_collision(sc.m_col, d)
        penetration_map(d.contact.geom, d.contact.dist, sc.node_of_geom, ref)
        col.depths(d.xpos[bone].copy(), ours)
        assert (np.isfinite(ours) == np.isfinite(ref)).all()
        c = d.xpos[bone] + col.local
        h = surface_of(sc.plate).height(c[:, 0], c[:, 1])
        seen, below = np.isfinite(ref), c[:, 2] < h
        np.testing.assert_allclose(ours[seen & ~below], ref[seen & ~below], rtol=0, atol=atol)
        vertical = h - (c[:, 2] - col.radius)
        np.testing.assert_allclose(
            ours[seen & below], np.maximum(vertical, ref)[seen & below], rtol=0, atol=atol
        )
        above += int((seen & ~below & (ref > 0)).sum())
        under += int((seen & below).sum())
        deeper += int((ours[seen & below] > ref[seen & below] + 1e-9).sum())
    assert above > 50 and under > 500 and deeper > 0  # each case met, and depths that differ


def _trapezoid_distance_brute(u, v, hx, tx, h, n=200_001):
    """Distance from (u, v) to the boundary of the trapezoid (bottom half-width hx at v = 0,
    top half-width tx at v = h), by sampling its four edges finely."""
    t = np.linspace(0.0, 1.0, n)
    corners = [(-hx, 0.0), (hx, 0.0), (tx, h), (-tx, h), (-hx, 0.0)]
    best = np.inf
    for (ax, az), (bx, bz) in zip(corners, corners[1:], strict=False):
        best = min(best, np.hypot(ax + t * (bx - ax) - u, az + t * (bz - az) - v).min())
    return best


def test_the_ridge_and_cylinder_distances_against_brute_force():
    """The compiled signed distances, outside the solids, against a brute-force distance to
    finely sampled edges (ridge) and the closed form (cylinder); inside the footprint they are
    the height map's depth below the top surface."""
    rng = np.random.default_rng(3)
    hx, hy, hz, tx = 1.0e-3, 5e-3, 0.5e-3, 0.42e-3
    for _ in range(200):
        lx, lz = rng.uniform(-2e-3, 2e-3), rng.uniform(-0.8e-3, 1.5e-3)
        d = ridge_distance(lx, 0.0, lz, hx, hy, hz, tx)
        u = abs(lx)
        top = hz if u <= tx else hz - 2 * hz * (u - tx) / (hx - tx)
        if u <= hx and lz <= top:
            assert d == pytest.approx(lz - top, abs=1e-15)
        else:
            assert d == pytest.approx(
                _trapezoid_distance_brute(lx, lz + hz, hx, tx, 2 * hz), abs=2e-9
            )
    # past the ridge's end along y, the distance adds the y-gap in quadrature
    d = ridge_distance(0.0, hy + 0.3e-3, hz + 0.4e-3, hx, hy, hz, tx)
    assert d == pytest.approx(0.5e-3, abs=1e-15)
    r, h = 1.5e-3, 0.25e-3
    assert cylinder_distance(0.0, 0.5e-3, -0.1e-3, r, h, True) == pytest.approx(-0.35e-3)
    assert cylinder_distance(2.0e-3, 0.0, 0.0, r, h, True) == pytest.approx(0.5e-3)
    assert cylinder_distance(1.8e-3, 0.0, h + 0.4e-3, r, h, True) == pytest.approx(0.5e-3)
    assert cylinder_distance(0.0, 0.0, -h + 0.05e-3, r, h, False) == pytest.approx(-0.05e-3)


def test_the_profile_collider_reads_a_run_of_one_x_once_bit_for_bit():
    """The held step's probes come in runs of one x (columns): the compiled loop reads the
    profile once a run and keeps the surface's own numpy height bit for bit, at nodes inside
    the textured area, on the base beside it and off the plate (NaN), and at x = 0 and -0."""
    plate = get_plate("roughness8/ra-50")
    half_w = plate.width_m / 2
    rng = np.random.default_rng(5)
    xs = np.concatenate([rng.uniform(-6e-3, 6e-3, 10), [0.0, -0.0]])
    n = 600
    local = np.column_stack(
        [
            np.sort(rng.choice(xs, n)),
            rng.uniform(-1.3 * half_w, 1.3 * half_w, n),  # across the area's and plate's edges
            rng.uniform(0.0, 1e-4, n),
        ]
    )
    c = SurfaceCollider(local, np.full(n, 1e-4), np.full(n, 1e-4), surface_of(plate))
    c.bind([0.0, 0.0, 0.0], 0, 1)
    kinds = {"near": 0, "far": 0, "off": 0}
    for _ in range(60):
        q = np.array([rng.uniform(-0.6, 0.6) * plate.length_m, rng.uniform(-2e-4, 6e-4)])
        got, want = np.empty(n), np.empty(n)
        assert c.depths_at(q, got) == c.depths_numpy(q, want)
        assert got.tobytes() == want.tobytes()
        centre = c.bone0 + [q[0], 0.0, q[1]] + c.local
        h = surface_of(plate).height(centre[:, 0], centre[:, 1])
        kinds["near"] += int(np.isfinite(got).sum())
        kinds["far"] += int((np.isfinite(h) & ~np.isfinite(got)).sum())
        kinds["off"] += int(np.isnan(h).sum())
    assert min(kinds.values()) > 500, kinds


@pytest.mark.parametrize("plate", ["roughness8/ra-50", "textures20/rough-ra100"])
def test_the_profile_collider_reads_the_height_map_at_each_node(plate, cache):
    """Each node's depth is the plate's height at its centre (height_at) less its lowest
    point, reported within its margin; over the flat base MuJoCo's collider reads the same
    (on the profile MuJoCo's convex-prism contacts read another depth: the height map is what
    the skin model and its reference take)."""
    sc = scene_of(plate, 0.1e-3, cache)
    col, ref = make_collider(sc), MujocoCollider(sc)
    rng = np.random.default_rng(1)
    qpos = np.zeros(sc.m_col.nq)
    pl = get_plate(plate)
    for _ in range(12):
        qpos[sc.jx] = rng.uniform(-0.02, 0.06)  # off, across and past the textured area
        qpos[sc.jz] = rng.uniform(-1.3e-3, -0.8e-3)
        got, want = np.empty(sc.n_nodes), np.empty(sc.n_nodes)
        near = col.depths_at(qpos, got)
        plain = np.empty(sc.n_nodes)  # the compiled loop against its numpy reference
        assert col.depths_numpy(qpos, plain) == near
        assert got.tobytes() == plain.tobytes()
        bone = col.bone0 + [qpos[sc.jx], 0.0, qpos[sc.jz]]  # the held step's kernel too
        assert probe_depths(bone, col.probe, plain) == near
        assert got.tobytes() == plain.tobytes()
        x = col.bone0[0] + qpos[sc.jx] + col.local[:, 0]
        y = col.bone0[1] + col.local[:, 1]
        z = col.bone0[2] + qpos[sc.jz] + col.local[:, 2] - col.radius
        d = surface_of(pl).height(x, y) - z
        expect = np.where(d >= -col.margin, d, -np.inf)
        np.testing.assert_allclose(got, expect, rtol=0, atol=1e-15)
        assert near == bool(np.isfinite(expect).any())
        ref.depths_at(qpos, want)
        base = (np.abs(x) > pl.area_length_m / 2 + 1e-3) & np.isfinite(want)
        np.testing.assert_allclose(got[base], want[base], rtol=0, atol=1e-12)
    assert col.warnings() == []


@pytest.mark.parametrize("force_control", ["dynamic", "quasi-static"])
def test_a_slide_is_bit_identical_with_either_collider(force_control, cache):
    """On flat ground (every node over the base's top face) the two colliders read the same
    depths, so a slide is the same to the bit. Over boxes they differ where a node lies
    inside a box nearer a side than the top: the compiled collider reads the height map's
    depth there, MuJoCo's the nearest face (on finger7/ridges-4 at 0.25 x 2 mm the taxel
    loads then differ by up to 22% of the largest, at the walls)."""
    proto = Protocol(duration_s=0.4, force_control=force_control)

    def run(options):
        return simulate(
            "finger7/flat",
            "grid3x3",
            protocol=proto,
            fidelity="L1",
            ideal=True,
            options=options,
            cache=cache,
        ).recording

    # the plain held loop over both colliders: only the collider differs
    fast = run(StepOptions(compiled_hold=False))
    slow = run(StepOptions(primitive_collider=False))
    assert fast.data.tobytes() == slow.data.tobytes()
    assert fast.data.max() > 0


def test_a_held_pad_rides_over_the_bumps_at_a_fine_grid(cache):
    """finger7/bumps-4x4 at 0.5 mm nodes under the held force: the pad climbs onto the
    2.5 mm bumps and the middle taxel reads nothing while they carry it (read to the bumps'
    nearest faces, the nodes that entered a bump's side held the pad on the base, and every
    taxel read as on flat ground)."""
    proto = Protocol(
        duration_s=0.6,
        force_control="quasi-static",
        speed_jitter=0.0,
        force_jitter=0.0,
        offset_jitter_m=0.0,
    )
    s = get_sensor("grid3x3")
    plate = get_plate("finger7/bumps-4x4")
    fid = replace(
        choose_fidelity(plate, s.layout, s.finger, proto, "L1"), pitch_m=0.5e-3, pitch_y_m=None
    )
    r = simulate(plate, s, protocol=proto, fidelity=fid, ideal=True, cache=cache).recording
    x = np.asarray(r.meta["x_pad_m"])
    on_bumps = np.abs(x) < 3e-3  # the bumps at +-4.5 mm under the pad's flat face
    assert on_bumps.sum() > 5
    centre = r.data[on_bumps, 4]
    assert centre.max() < 1e-3, centre.max()  # the middle taxel lies between the bump rows
    flat = r.data[x < -26.5e-3, 4]  # before the pad's face reaches the texture at -26 mm
    assert flat.size and flat.min() > 5e-3  # on flat ground it carries its share


def test_a_large_pad_on_a_rough_plate_fills_mujocos_buffer_and_not_the_height_maps(cache):
    """icub60 pressed on textures20/rough-ra100 at auto's 0.385 mm grid (6231 nodes):
    MuJoCo's height-field collider gives several contacts a node and fills its contact
    buffer (a slide stopped there with mjWARN_CONTACTFULL) or, pressed further, runs out of
    its stack (a fatal error); the height map has no buffer."""
    f = get_sensor("icub60").finger
    grid = skin_grid(f, 1.1563489339913178e-3 / 3)
    sc = build_scene(
        get_plate("textures20/rough-ra100"),
        f,
        grid,
        get_layout("icub60"),
        dt_s=1e-3,
        x0_m=0.0,
        z0_m=0.15e-3,  # the pad's face 0.15 mm above the base: the profile's peaks press in
        z_damping=1.0,
        node_margin_m=0.1e-3,
        cache=cache,
    )
    assert grid.n == 6231
    qpos = np.zeros(sc.m_col.nq)
    got, ref = np.empty(grid.n), MujocoCollider(sc)
    make_collider(sc).depths_at(qpos, got)
    assert np.isfinite(got).sum() > 1000 and make_collider(sc).warnings() == []
    try:  # its buffer full, or (pressed this far) its stack
        ref.depths_at(qpos, np.empty(grid.n))
        failed = "mjWARN_CONTACTFULL" in ref.warnings()
    except mujoco.FatalError as exc:
        failed = "out of memory" in str(exc)
    assert failed


@pytest.mark.slow
def test_the_icub_slides_over_a_rough_plate_at_autos_fine_grid(cache):
    """A short slide of icub60 onto textures20/rough-ra100 at auto's grid runs through."""
    sensor = get_sensor("icub60")
    proto = Protocol(speed_m_s=0.04, force_n=1.0, duration_s=0.3)
    rec = simulate("textures20/rough-ra100", sensor, protocol=proto, ideal=True, cache=cache)
    assert "93 x 67 nodes" in rec.recording.meta["skin_problem"]
    assert rec.recording.data.max() > 0.01


def test_interp_at_is_numpys_interp_bit_for_bit():
    rng = np.random.default_rng(5)
    xp = np.cumsum(rng.uniform(1e-6, 3e-6, 500))
    fp = rng.normal(size=500) * 1e-5
    fp[10] = fp[11]  # a flat piece
    qs = np.concatenate([rng.uniform(xp[0] - 1e-4, xp[-1] + 1e-4, 2000), xp[[0, 7, -1]], [np.nan]])
    for left, right in ((fp[0], fp[-1]), (0.0, 0.0), (-1.0, 2.0)):
        got = np.array([interp_at(q, xp, fp, left, right) for q in qs])
        want = np.interp(qs, xp, fp, left=left, right=right)
        assert got.tobytes() == want.tobytes()


def test_the_stepped_model_drops_the_node_spheres_and_nothing_else(cache):
    """MuJoCo steps a model without the skin's probe spheres (massless, out of contact): the
    bone's mass, inertia and frame are the collision model's, bit for bit, and the sample
    loop's stepping is unchanged (the golden slides hold it bit for bit too)."""
    sc = scene_of("finger7/bumps-4x4", 0.5e-3, cache)
    col, dyn = sc.m_col, sc.m_dyn
    assert col.ngeom - dyn.ngeom == sc.n_nodes
    assert not any(
        mujoco.mj_id2name(dyn, mujoco.mjtObj.mjOBJ_GEOM, g).startswith("node")
        for g in range(dyn.ngeom)
        if mujoco.mj_id2name(dyn, mujoco.mjtObj.mjOBJ_GEOM, g)
    )
    b = col.body("bone").id
    for key in ("body_mass", "body_inertia", "body_ipos", "body_iquat", "dof_M0"):
        assert np.array_equal(getattr(col, key), getattr(dyn, key)), key
    assert dyn.body("bone").id == b


def _buckets_by_loop(lo, hi, tops, origin, cell, shape):
    """The broad phase's cells as the collider first built them, geom by geom and cell by
    cell in Python: the reference for :func:`grid_buckets`."""
    n0, n1 = int(shape[0]), int(shape[1])
    buckets: list[list[int]] = [[] for _ in range(n0 * n1)]
    for g in range(len(lo)):
        i0, j0 = np.floor((lo[g] - origin) / cell).astype(int)
        i1, j1 = np.floor((hi[g] - origin) / cell).astype(int)
        for i in range(max(i0, 0), min(i1, n0 - 1) + 1):
            for j in range(max(j0, 0), min(j1, n1 - 1) + 1):
                buckets[i * n1 + j].append(g)
    start = np.zeros(len(buckets) + 1, dtype=np.int64)
    start[1:] = np.cumsum([len(b) for b in buckets])
    items = np.array([g for b in buckets for g in b], dtype=np.int64)
    top = np.array([max((tops[g] for g in b), default=-np.inf) for b in buckets])
    return start, items, top


@pytest.mark.parametrize("seed", range(6))
def test_the_broad_phase_cells_are_the_loops_exactly(seed):
    """Vectorised, the broad phase lists the same geoms in the same order in every cell
    as the loop it replaced (and the same highest top), geoms partly or wholly outside the
    grid, and empty cells, included."""
    from sim_tactile.sim.collide.primitive import grid_buckets

    rng = np.random.default_rng(seed)
    g = int(rng.integers(1, 60))
    centre = rng.uniform(-0.02, 0.02, (g, 2))
    half = rng.uniform(1e-4, 6e-3, (g, 2))
    lo, hi = centre - half, centre + half
    tops = rng.uniform(0, 2e-3, g)
    origin = lo.min(axis=0) + rng.uniform(0, 4e-3, 2)  # some geoms start before the grid
    cell = float(rng.uniform(1e-3, 5e-3))
    shape = np.maximum(rng.integers(1, 14, 2), 1)  # some end beyond it
    want = _buckets_by_loop(lo, hi, tops, origin, cell, shape)
    got = grid_buckets(lo, hi, tops, origin, cell, shape)
    for a, b in zip(got, want, strict=True):
        assert a.dtype == b.dtype and np.array_equal(a, b)


def test_a_plates_collider_is_built_as_before(cache):
    """On a plate of boxes (finger7's bumps: many geoms, many cells), the collider's cells
    are the loop's."""
    col = make_collider(scene_of("finger7/bumps-4x4", 0.5e-3, cache))
    assert isinstance(col, PrimitiveCollider)
    from sim_tactile.sim.collide.primitive import _half_extents

    half = _half_extents(col.kind, col.mat, col.size)
    reach = float((col.radius + col.margin).max())
    lo = col.pos[:, :2] - half[:, :2] - reach
    hi = col.pos[:, :2] + half[:, :2] + reach
    want = _buckets_by_loop(lo, hi, col.pos[:, 2] + half[:, 2], col.origin, col.cell, col.shape)
    assert col.items.size > 0
    for a, b in zip((col.start, col.items, col.cell_top), want, strict=True):
        assert np.array_equal(a, b)


def test_scenes_placed_from_one_kept_model_share_its_collider(cache):
    """Two slides of one plate at different offsets and starts: their scenes are placed
    copies of one kept model, so their colliders share what the model gives (the plate's
    geoms, the nodes in the bone's frame) and each binds its own pose; each reads the
    depths a collider made afresh from its own scene reads."""
    from sim_tactile.sim import Slide
    from sim_tactile.sim.step.build import scene_for

    plate = get_plate("finger7/bumps-4x4")
    a = Slide(plate, "grid3x3", Protocol(offset_y_m=0.0), 0)
    b = replace(a, protocol=Protocol(offset_y_m=0.7e-3, speed_m_s=0.05))
    scenes = []
    for s in (a, b):
        proto = s.drawn()
        scenes.append(scene_for(s, proto, s.resolved, s.window.x_start_m + 1e-3, cache)[0])
    sa, sb = scenes
    assert sa.model_key and sa.model_key == sb.model_key
    ca, cb = PrimitiveCollider.from_scene(sa), PrimitiveCollider.from_scene(sb)
    assert ca.local is cb.local and ca.pos is cb.pos  # shared, read only
    assert not np.array_equal(ca.bone0, cb.bone0)  # each at its own start
    for sc, c in ((sa, ca), (sb, cb)):
        bone = sc.m_col.body("bone").id
        fresh = PrimitiveCollider.from_model(sc.m_col, sc.node_of_geom, bone, plate)
        fresh.bind(sc.m_col.body_pos[bone], sc.jx, sc.jz)
        qpos = np.zeros(sc.m_col.nq)
        qpos[sc.jz] = -0.4e-3  # pressed into the bumps
        got, want = np.empty(len(c.radius)), np.empty(len(c.radius))
        assert c.depths_at(qpos, got) == fresh.depths_at(qpos, want)
        np.testing.assert_array_equal(got, want)
        assert np.isfinite(got).any()
