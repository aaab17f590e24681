"""The height-map plates' collider (:class:`~sim_tactile.sim.collide.height.SurfaceCollider`):
its bilinear height against ``height_at`` bit for bit, its compiled loop against its numpy
reference, against MuJoCo's height-field collider on a smooth map, in the compiled held step,
and slides over a height-map grating (the finger and the probe rig) that obey the grating
law."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _scenes import scene_of

from sim_tactile.bench.closed_forms import pulse_period
from sim_tactile.plates import HeightMap, Plate
from sim_tactile.plates.define.surface import QS_MARGIN_M, MapArrays, map_height, surface_of
from sim_tactile.sensors import Finger, get_sensor
from sim_tactile.sim.collide.choose import make_collider, probe_depths
from sim_tactile.sim.collide.height import (
    SurfaceCollider,
    map_height_at,
    map_surface_at,
)
from sim_tactile.sim.collide.reference import MujocoCollider
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.plan.rig import ProbeRig
from sim_tactile.sim.rig_sim import probe_contact, probe_grid, simulate_rig
from sim_tactile.sim.skin.models import CoupledSkin
from sim_tactile.sim.slide import simulate
from sim_tactile.sim.step.held import CompiledHeldStep
from sim_tactile.sim.step.runner import StepOptions

MM = 1e-3
#: The grating: ridges 2 mm wide every 4 mm along x, 0.3 mm high, sampled every 50 um. (At a
#: 2 mm period grid3x3's 2 mm taxels average the fundamental out: the dominant period came out
#: at half the law's; the rig's 3 mm elements at a 3 mm period read an almost flat signal.)
PERIOD_M = 4 * MM
PIXEL_M = 50e-6
RIDGE_M = 0.3 * MM
#: The grating law's tolerance: the taxel stream's dominant period against spacing / speed.
PERIOD_RTOL = 0.02
#: Two exact solutions of one slide (the compiled held step and the plain loop) agree to
#: this, relative to the load (as tests/test_sim_held.py): round-off of the contact set's
#: different update schedules.
SLIDE_RTOL = 1e-5
SLIDE_ATOL_N = 1e-7
#: The smooth map MuJoCo's collider is compared on: A sin(kx) cos(ky), A = 10 um, 5 mm
#: wavelength, sampled every 0.25 mm. Its slope is at most A k (0.0126), so a node's distance
#: to the surface along its normal (MuJoCo's) falls short of the vertical gap (ours) by at most
#: gap * (1 - cos(atan(A k))) (7.9e-5 of the gap; measured up to 2.7e-8 m at gaps below
#: 0.35 mm, the node's radius and margin); the triangulation against the bilinear map and
#: MuJoCo's float32 elevations add below 1e-9 m.
SMOOTH_A_M, SMOOTH_WAVE_M, SMOOTH_PIXEL_M = 10e-6, 5 * MM, 0.25 * MM
TRIANGLES_ATOL_M = 1e-9


def _plate(z: np.ndarray, pixel: float, **kw) -> Plate:
    ny, nx = z.shape
    return Plate(
        HeightMap(z, pixel), area_length_m=(nx - 1) * pixel, area_width_m=(ny - 1) * pixel, **kw
    )


def _grating() -> Plate:
    """Ridges along y as a sampled map: 54 x 20 mm, the plate 108 x 36 mm."""
    nx, ny = 1081, 401
    x = (np.arange(nx) - (nx - 1) / 2) * PIXEL_M
    row = np.where(np.mod(x, PERIOD_M) < PERIOD_M / 2, RIDGE_M, 0.0)
    return _plate(np.tile(row, (ny, 1)), PIXEL_M, name="test/heightmap-grating-4mm")


def _smooth() -> Plate:
    """A sin(kx) cos(ky) over 36 x 20 mm (whole half-waves: zero at the area's x edges)."""
    p = SMOOTH_PIXEL_M
    nx, ny = round(36 * MM / p) + 1, round(20 * MM / p) + 1
    x = (np.arange(nx) - (nx - 1) / 2) * p
    y = (np.arange(ny) - (ny - 1) / 2) * p
    k = 2 * np.pi / SMOOTH_WAVE_M
    return _plate(SMOOTH_A_M * np.sin(k * x)[None, :] * np.cos(k * y)[:, None], p)


def _rough(seed=0) -> Plate:
    """A random map with holes (NaN: no material) on a plate wider than it: odd pixel,
    71 x 53 samples."""
    rng = np.random.default_rng(seed)
    z = rng.normal(0.0, 30e-6, (53, 71))
    z[rng.random(z.shape) < 0.05] = np.nan
    return _plate(z, 0.1 * MM, length_m=12 * MM, width_m=8 * MM, thickness_m=1 * MM)


def _wide(seed=1) -> Plate:
    """A random map that spans more than the textured area (7 x 5.2 mm over 5 x 4 mm): the
    map, not the area, bounds the sampled surface."""
    rng = np.random.default_rng(seed)
    z = rng.normal(0.0, 30e-6, (53, 71))
    z[rng.random(z.shape) < 0.05] = np.nan
    return Plate(
        HeightMap(z, 0.1 * MM),
        length_m=12 * MM,
        width_m=8 * MM,
        thickness_m=1 * MM,
        area_length_m=5 * MM,
        area_width_m=4 * MM,
    )


def _points(plate: Plate, rng, n=20_000) -> tuple[np.ndarray, np.ndarray]:
    """Random points over and past the plate, the map's samples and cell edges (in x, in y,
    both), and the map's, textured area's and plate's borders (and just past the map's)."""
    t = plate.texture
    xs, ys = t.grid()
    L, W = plate.length_m / 2, plate.width_m / 2
    x = [rng.uniform(-1.1 * L, 1.1 * L, n), rng.choice(xs, n), rng.choice(xs, n)]
    y = [rng.uniform(-1.1 * W, 1.1 * W, n), rng.uniform(ys[0], ys[-1], n), rng.choice(ys, n)]
    ax, ay = plate.area_length_m / 2, plate.area_width_m / 2
    sx, sy = t.extent_m[0] / 2, t.extent_m[1] / 2
    edges_x = [xs[0], xs[-1], -ax, ax, -sx, sx, -L, L, np.nextafter(sx, 1), np.nextafter(-sx, -1)]
    edges_y = [ys[0], ys[-1], -ay, ay, -sy, sy, -W, W, np.nextafter(sy, 1), np.nextafter(-sy, -1)]
    ex, ey = np.meshgrid(edges_x + list(xs[::7]), edges_y + list(ys[::5]))
    x += [rng.uniform(xs[0], xs[-1], n), ex.ravel()]
    y += [rng.choice(ys, n), ey.ravel()]
    return np.concatenate(x), np.concatenate(y)


def _same_bits(a: np.ndarray, b: np.ndarray) -> None:
    """Equal bit for bit where finite, NaN (and -inf) at the same places."""
    assert (np.isnan(a) == np.isnan(b)).all()
    ok = ~np.isnan(a)
    assert a[ok].tobytes() == b[ok].tobytes()


@pytest.mark.parametrize(
    "make", [_rough, _wide, _grating, _smooth], ids=["rough", "wide", "grating", "smooth"]
)
def test_the_compiled_height_is_height_at_bit_for_bit(make):
    plate = make()
    t = plate.texture
    s = surface_of(plate).arrays
    rng = np.random.default_rng(7)
    x, y = _points(plate, rng)
    want = surface_of(plate).height(x, y)
    got = np.array([map_surface_at(a, b, *s) for a, b in zip(x, y, strict=True)])
    _same_bits(got, want)
    inside = (np.abs(x) <= s[2]) & (np.abs(y) <= s[3])
    bare = np.array([map_height_at(a, b, t.z, t.pixel_m) for a, b in zip(x, y, strict=True)])
    _same_bits(bare[inside], map_height(x[inside], y[inside], t.z, t.pixel_m))
    # every case met: material, holes, the base, off the plate
    assert np.isfinite(got[inside]).sum() > 1000 and (got[~inside] == 0.0).sum() > 1000
    assert np.isnan(got[inside]).any() == bool(np.isnan(t.z).any())
    assert np.isnan(got[~inside]).sum() > 1000


def _bound(plate: Plate, n=400, seed=0, columns=False) -> SurfaceCollider:
    """A collider on ``n`` random probes bound to the joints ``qpos = (x, z)``; with
    ``columns``, in runs of one x (12 of them, in order), as the held step's probes come."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-5 * MM, 5 * MM, n)
    if columns:
        x = np.sort(rng.choice(x[:12], n))
    local = np.column_stack([x, rng.uniform(-4 * MM, 4 * MM, n), rng.uniform(0, 1e-4, n)])
    r, m = rng.uniform(0.05, 0.2, n) * MM, rng.uniform(0.0, 0.5, n) * MM
    c = SurfaceCollider(local, r, m, surface_of(plate))
    c.bind([0.0, rng.uniform(-1 * MM, 1 * MM), 0.0], 0, 1)
    return c


@pytest.mark.parametrize("columns", [False, True], ids=["scattered", "columns"])
@pytest.mark.parametrize("make", [_rough, _wide, _grating], ids=["rough", "wide", "grating"])
def test_the_compiled_loop_is_its_numpy_reference_and_height_at(make, columns):
    """The depths bit for bit three ways (the compiled loop, its numpy reference, height_at
    less each probe's lowest point), within each probe's margin, at poses on, off and past
    the plate; the kernel of the held step and a subset of the probes alike. In columns, the
    loop reads a rough plate's profile once a run of one x."""
    plate = make()
    c = _bound(plate, columns=columns)
    n = len(c.radius)
    rng = np.random.default_rng(3)
    sub = rng.permutation(n)[: n // 3]
    part = c.subset(sub)
    seen = {"near": 0, "far": 0, "hole": 0}
    for _ in range(200):
        q = np.array([rng.uniform(-0.6, 0.6) * plate.length_m, rng.uniform(-0.3, 1.0) * MM])
        a, b, k, s = np.empty(n), np.empty(n), np.empty(n), np.empty(len(sub))
        near = c.depths_at(q, a)
        assert c.depths_numpy(q, b) == near
        assert a.tobytes() == b.tobytes()
        bone = c.bone0 + [q[0], 0.0, q[1]]
        assert probe_depths(bone, c.probe, k) == near
        assert k.tobytes() == a.tobytes()
        part.depths_at(q, s)
        assert s.tobytes() == a[sub].tobytes()
        centre = bone + c.local
        d = surface_of(plate).height(centre[:, 0], centre[:, 1]) - (centre[:, 2] - c.radius)
        want = np.where(d >= -c.margin, d, -np.inf)
        assert a.tobytes() == want.tobytes()
        assert near == bool(np.isfinite(want).any())
        seen["near"] += int(np.isfinite(a).sum())
        seen["far"] += int((np.isfinite(d) & ~np.isfinite(a)).sum())
        seen["hole"] += int(np.isnan(d).sum())
    assert seen["near"] > 1000 and seen["far"] > 1000 and seen["hole"] > 1000
    assert not c.y_invariant(0.0) and c.warnings() == []


def test_a_height_map_takes_the_map_collider_and_the_wide_margin(cache):
    plate = _grating()
    assert surface_of(plate).margin_m == QS_MARGIN_M
    sc = scene_of(plate, QS_MARGIN_M, cache, x0_m=-0.01)
    c = make_collider(sc)
    assert isinstance(c, SurfaceCollider) and isinstance(c.probe.surface, MapArrays)
    assert c.compiled
    assert isinstance(make_collider(sc, primitive=False), MujocoCollider)  # the reference
    assert surface_of(plate).feature_scale_m == pytest.approx(PERIOD_M / 2)
    assert surface_of(plate).period_m == pytest.approx(PERIOD_M)


def test_the_map_collider_agrees_with_mujocos_on_a_smooth_map(cache):
    """Nodes clear of the surface (their lowest point above it): MuJoCo's distance to the
    nearest facet lies at most the slope's cosine term above our vertical depth (see
    :data:`SMOOTH_A_M`), never below it; the same nodes are reported. The margin is narrow,
    and the pixel coarse, so that each node meets fewer prisms than MuJoCo's 50 contacts per
    pair (at 0.5 mm and 0.1 mm pixels the nearest was often left out)."""
    plate = _smooth()
    margin = 0.1 * MM
    sc = scene_of(plate, margin, cache, x0_m=-0.01)
    col, ref = make_collider(sc), MujocoCollider(sc)
    assert isinstance(col, SurfaceCollider)
    cos = math.cos(math.atan(SMOOTH_A_M * 2 * math.pi / SMOOTH_WAVE_M))
    rng = np.random.default_rng(0)
    q = np.zeros(sc.m_col.nq)
    ours, theirs = np.empty(sc.n_nodes), np.empty(sc.n_nodes)
    worst, count = 0.0, 0
    for _ in range(40):
        q[sc.jx], q[sc.jz] = rng.uniform(-5 * MM, 25 * MM), rng.uniform(-1.6 * MM, -0.9 * MM)
        col.depths_at(q, ours)
        ref.depths_at(q, theirs)
        centre = col.bone0 + [q[sc.jx], 0.0, q[sc.jz]] + col.local
        h = surface_of(plate).height(centre[:, 0], centre[:, 1])
        clear = centre[:, 2] - col.radius > h
        both = clear & np.isfinite(ours) & np.isfinite(theirs)
        # reported alike, but where the two depths straddle the margin
        differ = clear & (np.isfinite(ours) != np.isfinite(theirs))
        assert (np.abs(np.maximum(ours, theirs)[differ] + margin) < 1e-7).all()
        gap = centre[both, 2] - h[both]
        over = theirs[both] - ours[both]
        assert (over >= -TRIANGLES_ATOL_M).all()
        assert (over <= gap * (1 - cos) + TRIANGLES_ATOL_M).all()
        worst, count = max(worst, float(np.abs(over).max(initial=0.0))), count + int(both.sum())
    assert count > 1000 and 1e-9 < worst < 3e-8, (count, worst)
    assert ref.warnings() == []


@pytest.fixture(scope="module")
def grating():
    return _grating()


def test_the_compiled_held_step_reads_the_maps_depths(grating, cache):
    """The compiled held step's depth map (its one call's map kernel) is the collider's, bit
    for bit, on the full problem (a map never reduces)."""
    sc = scene_of(grating, QS_MARGIN_M, cache, x0_m=-0.01)
    col = make_collider(sc)
    f = Finger()
    h = CompiledHeldStep(
        col, CoupledSkin.half_space(sc.grid, f), sc.W, sc.grid.area_m2, QS_MARGIN_M
    )
    assert not h.columns and not h.mirrored and h.n == sc.n_nodes == h.n_probes
    full = np.empty(sc.n_nodes)
    near_any = 0
    for x in np.linspace(0.0, 0.03, 30):
        bone = col.bone0 + [x, 0.0, -0.3 * MM]
        near = probe_depths(bone, col.probe, full)
        assert h.depths(bone) == near
        assert h.pen.tobytes() == full.tobytes()
        near_any += near
    assert near_any > 20


def _slide(plate, options, cache, **kw):
    proto = Protocol(
        speed_m_s=0.04, duration_s=kw.pop("duration_s", 0.5), start=kw.pop("start", "flat")
    )
    return simulate(
        plate, "grid3x3", protocol=proto, ideal=True, options=options, cache=cache, **kw
    )


def test_the_compiled_held_step_on_a_height_map_equals_the_plain_loop(grating, cache):
    """The map collider in the compiled held step against the plain loop over it."""
    kw = dict(fidelity="L1", seed=3)
    fast = _slide(grating, StepOptions(path="per-step"), cache, **kw).recording  # not auto's
    slow = _slide(grating, StepOptions(compiled_hold=False), cache, **kw).recording
    assert fast.meta["skin_problem"].endswith("nodes: full problem")  # the compiled step's
    assert slow.meta["skin_problem"] == "full problem"
    assert fast.data.max() > 0.05
    np.testing.assert_allclose(fast.data, slow.data, rtol=SLIDE_RTOL, atol=SLIDE_ATOL_N)
    np.testing.assert_allclose(fast.meta["normal_force_n"], slow.meta["normal_force_n"], rtol=1e-6)


def test_a_slide_over_a_height_map_grating_obeys_the_grating_law(grating, cache):
    """The middle taxel's dominant period is the spacing over the speed (4 mm at 40 mm/s:
    100 ms), within 2%, with auto's grid (the map's 2 mm ridges and gaps set its pitch): one
    stroke, the pad starting on the grating."""
    res = _slide(grating, StepOptions(), cache, duration_s=0.8, start="texture")
    rec = res.recording
    assert "smallest feature 2 mm" in res.fidelity.reason
    middle = int(np.flatnonzero(np.all(rec.taxels[:, :2] == 0, axis=1))[0])
    # the pad's face wholly over the grating, 1 mm in from its ends (past the climb onto it)
    pad = get_sensor("grid3x3").finger.patch_m[0] + 2 * MM
    over = np.abs(np.asarray(rec.meta["x_pad_m"])) < grating.area_length_m / 2 - pad / 2
    core = rec.data[over, middle].astype(float)
    assert core.min() >= 0 and np.ptp(core) > 0.5 * core.max() > 0.005  # pulses
    m = pulse_period(rec, middle, grating.area_length_m, PERIOD_M, 0.04, pad)
    assert m["periods"] > 7 and m["ripple"] > 0.3
    assert m["period_s"] == pytest.approx(PERIOD_M / 0.04, rel=PERIOD_RTOL)


@pytest.mark.slow
def test_the_probe_rig_slides_a_height_map_grating(grating):
    """The probe rig on the map (its face the map's samples at the rig's nodes): the centre
    element's dominant period over the cruise is the spacing over the speed."""
    sensor = get_sensor("multilayer3x3x2")
    speed = 0.065
    rec = simulate_rig(
        grating,
        sensor,
        rig=ProbeRig(direction="+x"),
        protocol=Protocol(speed_m_s=speed, force_n=5.0, duration_s=2.0),
        finger=sensor.with_paper_stack().finger,
        seed=11,
        ideal=True,
    ).recording
    x = np.asarray(rec.meta["x_probe_m"])
    centre = int(np.flatnonzero(np.all(sensor.layout.positions[:, :2] == 0, axis=1))[0])
    reach = 2 * (1.5e-3 + 2.5e-3)  # the element wholly under the face
    m = pulse_period(rec, centre, grating.area_length_m, PERIOD_M, speed, reach, x_m=x)
    assert m["periods"] > 5 and m["ripple"] > 0.1
    assert m["period_s"] == pytest.approx(PERIOD_M / speed, rel=PERIOD_RTOL)


def test_the_probe_face_of_a_map_with_holes_carries_the_force_on_its_material():
    """Where the map holds no material (NaN) the probe's face has no node in reach: zero
    pressure there, the force carried by the rest."""
    plate = _rough()
    sensor = get_sensor("multilayer3x3x2")
    grid = probe_grid(plate, 0.1 * MM)
    p, approach, _ = probe_contact(plate, sensor.with_paper_stack().finger, grid, 1.0)
    hole = np.isnan(surface_of(plate).height(grid.xy[:, 0], grid.xy[:, 1]))
    assert hole.any() and np.isfinite(p).all() and np.isfinite(approach)
    assert (p[hole] == 0).all() and (p[~hole] > 0).sum() > 10
    assert p.sum() * grid.area_m2 == pytest.approx(1.0, rel=1e-6)
