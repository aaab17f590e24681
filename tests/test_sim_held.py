"""The held step (sim.held): the compiled call on the reduced problem against the full one,
and against the plain loop over either collider."""

from __future__ import annotations

import numpy as np
import pytest
from _scenes import scene_of

from sim_tactile.sensors import Finger
from sim_tactile.sim.collide.primitive import PrimitiveCollider
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.skin import contact
from sim_tactile.sim.skin.models import CoupledSkin
from sim_tactile.sim.slide import simulate
from sim_tactile.sim.step import held as H
from sim_tactile.sim.step.held import CompiledHeldStep, _mirror_of, _mirror_symmetric
from sim_tactile.sim.step.runner import StepOptions

MARGIN = 0.5e-3
#: Two exact solutions of the same slide (reduced and full problem, compiled and plain loop)
#: agree to this, relative to the load, over a whole slide: round-off accumulated by the
#: contact set's different update schedules, far below any physical effect.
SLIDE_RTOL = 1e-5
SLIDE_ATOL_N = 1e-7


def _setup(plate: str, cache, pitch=(0.5e-3, 2e-3)):
    sc = scene_of(plate, MARGIN, cache, pitch=pitch, dt_s=2e-3)
    col = PrimitiveCollider.from_scene(sc)
    assert col is not None
    sc.skin = CoupledSkin.half_space(sc.grid, Finger())
    return sc, col, col.bone0.copy()


def HeldSkin(sc, col, bone_y, margin=MARGIN, reduce=True):
    """The compiled held step with the bone at ``bone_y`` across the slide."""
    col.bind((col.bone0[0], bone_y, col.bone0[2]), sc.jx, sc.jz)
    return CompiledHeldStep(col, sc.skin, sc.W, sc.grid.area_m2, margin, reduce)


def _positions(n=40):
    """A slide across the ridges at a pressed height, in world coordinates of the bone."""
    xs = np.linspace(0.0, 0.04, n)
    return [(x, -0.3e-3) for x in xs]


def test_ridges_reduce_to_columns_and_a_mirror_half(cache):
    sc, col, bone0 = _setup("finger7/ridges-4", cache)
    h = HeldSkin(sc, col, bone_y=1.3e-3, margin=MARGIN)
    assert h.columns and h.mirrored
    ny = len(np.unique(sc.grid.xy[:, 1]))
    nx = len(np.unique(sc.grid.xy[:, 0]))
    assert h.n == nx * (ny + 1) // 2  # the centre row and one side
    assert h.n_probes < h.n
    # bumps vary along y: no reduction
    sb, cb, _ = _setup("finger7/bumps-4x4", cache)
    hb = HeldSkin(sb, cb, bone_y=0.0, margin=MARGIN)
    assert not hb.columns and not hb.mirrored and hb.n == sb.n_nodes
    # past the ridges' ends in y the depths depend on y again
    hy = max(col.size[g, 1] for g in range(len(col.kind)) if col.size[g, 2] < 2e-3)
    assert not col.y_invariant(hy)
    assert not HeldSkin(sc, col, bone_y=hy, margin=MARGIN).columns
    # reduce=False keeps the full problem
    assert HeldSkin(sc, col, bone_y=0.0, margin=MARGIN, reduce=False).n == sc.n_nodes


def test_reduced_depths_are_the_full_colliders_bit_for_bit(cache):
    sc, col, bone0 = _setup("finger7/ridges-4", cache)
    y = 1.3e-3
    h = HeldSkin(sc, col, bone_y=y, margin=MARGIN)
    mirror = _mirror_of(col)
    full = np.empty(sc.n_nodes)
    near_any = 0
    for x, z in _positions():
        b = np.array([bone0[0] + x, y, bone0[2] + z])
        near = col.depths(b, full)
        assert h.depths(b) == near
        near_any += near
        assert full[h.nodes].tobytes() == h.pen.tobytes()
        assert full[mirror[h.nodes]].tobytes() == h.pen.tobytes()
    assert near_any > 30


def test_the_mirror_halved_solve_equals_the_full_one(cache):
    sc, col, bone0 = _setup("finger7/ridges-4", cache)
    y = -0.7e-3
    h = HeldSkin(sc, col, bone_y=y, margin=MARGIN)
    full_solver = contact.ActiveSet(sc.skin.C, sc.skin.K)
    mirror = _mirror_of(col)
    A = sc.grid.area_m2
    total = 1.0 / A  # 1 N
    full = np.empty(sc.n_nodes)
    changes = 0
    last = None
    for x, z in _positions(60):
        b = np.array([bone0[0] + x, y, bone0[2] + z])
        col.depths(b, full)
        p, dz = full_solver.solve_force(full, total)
        h.depths(b)
        f, dz_r = h.solver.solve_force(h.pen, total)
        assert dz_r == pytest.approx(dz, rel=1e-9, abs=1e-15)
        # f sums each mirror pair's pressures
        pair = p[h.nodes] + np.where(mirror[h.nodes] != h.nodes, p[mirror[h.nodes]], 0.0)
        np.testing.assert_allclose(f, pair, rtol=1e-8, atol=1e-9 * p.max())
        np.testing.assert_allclose(
            h.W @ (f * A), sc.W @ (p * A), rtol=1e-8, atol=1e-10
        )  # the taxel loads
        assert (f * A).sum() == pytest.approx(1.0, rel=1e-9)
        s = frozenset(np.flatnonzero(f > 0))
        changes += last is not None and s != last
        last = s
    assert changes > 10  # the set changed along the way (the update formulas ran)


def test_mirror_symmetry_check_rejects_an_asymmetric_compliance(cache):
    sc, col, _ = _setup("finger7/ridges-4", cache)
    mirror = _mirror_of(col)
    assert _mirror_symmetric(sc.skin.C, mirror)
    C = sc.skin.C.copy()
    C[0, 1] *= 1 + 1e-6
    C[1, 0] = C[0, 1]
    assert not _mirror_symmetric(C, mirror)


@pytest.mark.parametrize(
    "plate", ["finger7/ridges-4", "finger7/bumps-4x4", "multilayer3/grating-9"]
)
def test_a_slide_with_the_reduced_skin_equals_the_full_one(plate, cache):
    # L1: the pad's own lattice at the grid that resolves the plate (auto anchors these two
    # plates' lattices to their walls, tests/test_sim_anchored.py)
    def run(reduce: bool):
        return simulate(
            plate,
            "grid3x3",
            fidelity="L1",
            protocol=Protocol(duration_s=0.5, offset_jitter_m=1e-3),
            ideal=True,
            seed=5,
            options=StepOptions(reduce_skin=reduce, path="per-step"),  # not auto's choice
            cache=cache,
        ).recording

    fast, full = run(True), run(False)
    mirrored = plate != "finger7/bumps-4x4"  # ridges along y, drafted or not
    assert ("mirror-halved" in fast.meta["skin_problem"]) == mirrored
    assert "mirror" not in full.meta["skin_problem"]
    assert fast.data.max() > 0.01
    np.testing.assert_allclose(fast.data, full.data, rtol=SLIDE_RTOL, atol=SLIDE_ATOL_N)
    np.testing.assert_allclose(fast.meta["normal_force_n"], full.meta["normal_force_n"], rtol=1e-6)


def test_weighted_winkler_bed_equals_the_expanded_one():
    rng = np.random.default_rng(1)
    for _ in range(100):
        n = int(rng.integers(1, 40))
        pen = rng.normal(0.0, 1e-4, n)
        pen[rng.random(n) < 0.3] = -np.inf
        if not np.isfinite(pen).any():
            continue
        mult = rng.choice([1.0, 2.0], n)
        total = float(rng.uniform(1e2, 1e6))
        f = np.empty(n)
        dz = H._winkler_force(pen, mult, 3e6, total, f)
        # the same nodes written out once per node they stand for
        full = np.repeat(pen, mult.astype(int))
        p, dz_full = contact.winkler_force(full, 3e6, total)
        assert dz == pytest.approx(dz_full, rel=1e-12, abs=1e-18)
        assert f.sum() == pytest.approx(total, rel=1e-12)
        np.testing.assert_allclose(f / mult, 3e6 * np.maximum(pen + dz, 0.0), rtol=1e-12)
        # unit weights: bit for bit the plain closed form
        p1, dz1 = contact.winkler_force(pen, 3e6, total)
        assert H._winkler_force(pen, np.ones(n), 3e6, total, f) == dz1
        assert f.tobytes() == p1.tobytes()
    assert np.isnan(H._winkler_force(np.full(3, -np.inf), np.ones(3), 3e6, 1.0, np.empty(3)))


@pytest.mark.parametrize("fidelity", ["L0", "L1"])
@pytest.mark.parametrize(
    "reference",
    [StepOptions(compiled_hold=False), StepOptions(primitive_collider=False)],
    ids=["plain-loop", "mujoco-collider"],
)
def test_the_compiled_held_step_equals_the_plain_loop(fidelity, reference, cache):
    """The compiled held step on the reduced problem against the plain loop on the full one,
    over the compiled collider and over MuJoCo's (the path of plates MuJoCo must collide).
    MuJoCo's collider reads a node inside a box to its nearest face, the compiled one the
    height map's depth below the top (tests/test_sim_collide.py): against it, flat ground,
    where the two agree."""
    plate = "finger7/flat" if reference.primitive_collider is False else "finger7/ridges-4"

    def run(options):
        return simulate(
            plate,
            "grid3x3",
            protocol=Protocol(duration_s=0.5),
            fidelity=fidelity,
            ideal=True,
            seed=2,
            options=options,
            cache=cache,
        ).recording

    fast, slow = run(StepOptions(path="per-step")), run(reference)
    assert "mirror-halved" in fast.meta["skin_problem"]
    assert slow.meta["skin_problem"] == "full problem"
    assert fast.data.max() > (0.005 if plate == "finger7/flat" else 0.05)
    np.testing.assert_allclose(fast.data, slow.data, rtol=SLIDE_RTOL, atol=SLIDE_ATOL_N)


@pytest.mark.parametrize("plate", ["multilayer3/grating-9", "textures20/cylinders-3.0mm"])
def test_the_compiled_held_step_on_ridges_and_cylinders(plate, cache):
    """Drafted ridges and cylinders, which MuJoCo's collider served before the compiled one
    took them: the compiled held step against the plain loop, both over the compiled
    collider."""

    kw = dict(fidelity="L1", seed=4, cache=cache)
    fast = _ideal_slide(plate, "grid3x3", 0.5, StepOptions(path="per-step"), **kw)
    slow = _ideal_slide(plate, "grid3x3", 0.5, StepOptions(compiled_hold=False), **kw)
    assert slow.meta["skin_problem"] == "full problem"
    assert fast.data.max() > 0.05
    np.testing.assert_allclose(fast.data, slow.data, rtol=SLIDE_RTOL, atol=SLIDE_ATOL_N)


@pytest.mark.parametrize(
    "reference",
    [StepOptions(compiled_hold=False), StepOptions(reduce_skin=False)],
    ids=["plain-loop", "full-problem"],
)
def test_the_compiled_held_step_on_a_rough_plate(reference, cache):
    """The rough plates' profile collider in the compiled held step (the pvdf2 fingertip is
    mirror-symmetric: a halved solve) against the plain loop and the full problem."""

    fast, slow = (
        _ideal_slide("roughness8/ra-50", "pvdf2", 0.2, options, seed=3, cache=cache)
        for options in (StepOptions(), reference)
    )
    assert "mirror-halved" in fast.meta["skin_problem"]
    assert "mirror" not in slow.meta["skin_problem"]
    assert np.abs(fast.data).max() > 1e-3
    np.testing.assert_allclose(fast.data, slow.data, rtol=SLIDE_RTOL, atol=SLIDE_ATOL_N)
    np.testing.assert_allclose(fast.meta["normal_force_n"], slow.meta["normal_force_n"], rtol=1e-6)


def _ideal_slide(plate, sensor, duration_s, options, **kw):
    """The ideal loads of a slide of ``duration_s`` under the step ``options``."""
    proto = Protocol(duration_s=duration_s)
    return simulate(plate, sensor, protocol=proto, ideal=True, options=options, **kw).recording
