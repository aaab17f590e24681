"""The held-force step's reduced problem (sim.held) against the full one."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.plates import get_plate
from sim_tactile.scene.model import build_scene
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import Finger, get_layout
from sim_tactile.sim import contact
from sim_tactile.sim import held as H
from sim_tactile.sim import simulate as S
from sim_tactile.sim.collide import PrimitiveCollider
from sim_tactile.sim.held import HeldSkin, _mirror_of, _mirror_symmetric
from sim_tactile.sim.simulate import Protocol, simulate

MARGIN = 0.5e-3


def _setup(plate: str, cache, pitch=(0.5e-3, 2e-3)):
    f = Finger()
    sc = build_scene(
        get_plate(plate),
        f,
        skin_grid(f, *pitch),
        get_layout("grid3x3"),
        dt_s=2e-3,
        x0_m=-0.02,
        z0_m=1e-3,
        z_damping=1.0,
        coupled=True,
        node_margin_m=MARGIN,
        cache=cache,
    )
    bone = sc.m_col.body("bone").id
    col = PrimitiveCollider.from_model(sc.m_col, sc.node_of_geom, bone)
    assert col is not None
    return sc, col, sc.m_col.body_pos[bone].copy()


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
    full_solver = contact.ActiveSet(sc.C, sc.K)
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
    assert _mirror_symmetric(sc.C, mirror)
    C = sc.C.copy()
    C[0, 1] *= 1 + 1e-6
    C[1, 0] = C[0, 1]
    assert not _mirror_symmetric(C, mirror)


@pytest.mark.parametrize("plate", ["finger7/ridges-4", "finger7/bumps-4x4"])
def test_a_slide_with_the_reduced_skin_equals_the_full_one(plate, cache, monkeypatch):
    orig = S._Runner.__init__
    seen = []

    def run(reduce: bool):
        def spy(self, *a, **k):
            orig(self, *a, **{**k, "reduce_skin": reduce})
            seen.append(self.held.mirrored)

        monkeypatch.setattr(S._Runner, "__init__", spy)
        return simulate(
            plate,
            "grid3x3",
            protocol=Protocol(duration_s=0.5, offset_jitter_m=1e-3),
            ideal=True,
            seed=5,
            cache=cache,
        ).recording

    fast, full = run(True), run(False)
    assert seen == [plate.startswith("finger7/ridges"), False]
    assert fast.data.max() > 0.01
    np.testing.assert_allclose(fast.data, full.data, rtol=1e-5, atol=1e-7)
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
def test_the_held_step_equals_the_general_loop_with_mujocos_collider(fidelity, cache, monkeypatch):
    """The compiled held step on the reduced problem against the Python loop over MuJoCo's
    collider and the full problem (the path of plates MuJoCo must collide)."""
    orig = S._Runner.__init__
    paths = []

    def run(primitive: bool):
        def spy(self, *a, **k):
            orig(self, *a, **{**k, "use_primitive_collider": primitive})
            paths.append(self.held is not None and self.held.mirrored)

        monkeypatch.setattr(S._Runner, "__init__", spy)
        return simulate(
            "finger7/ridges-4",
            "grid3x3",
            protocol=Protocol(duration_s=0.5),
            fidelity=fidelity,
            ideal=True,
            seed=2,
            cache=cache,
        ).recording

    fast, slow = run(True), run(False)
    assert paths == [True, False]
    assert fast.data.max() > 0.05
    np.testing.assert_allclose(fast.data, slow.data, rtol=1e-5, atol=1e-7)
