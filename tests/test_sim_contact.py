"""The half-space contact solver against a quadratic-programming reference (scipy)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import nnls

from sim_tactile.errors import PhysicsError
from sim_tactile.scene.elastic import compliance_matrix
from sim_tactile.sim.skin.contact import halfspace, winkler

#: Agreement of two exact solvers of the same problem, relative to the largest pressure.
SOLVER_RTOL = 1e-8


def _problem(seed: int, n: int = 9):
    rng = np.random.default_rng(seed)
    xs = np.arange(n) * 1e-3
    X, Y = np.meshgrid(xs, xs)
    xy = np.column_stack([X.ravel(), Y.ravel()])
    C = compliance_matrix(xy, 1e-3, 0.4e6)
    # a rough indenter: smooth bump plus noise, partly penetrating
    pen = 1e-4 * (
        1 - ((X - 4e-3) ** 2 + (Y - 4e-3) ** 2).ravel() / 2e-5
    ) + 2e-5 * rng.standard_normal(X.size)
    return C, pen


def _reference(C: np.ndarray, pen: np.ndarray) -> np.ndarray:
    """min 1/2 p'Cp - pen'p, p >= 0 (whose KKT conditions are the contact problem), as an
    NNLS problem through the Cholesky factor C = L L'."""
    L = np.linalg.cholesky(C)
    p, _ = nnls(L.T, np.linalg.solve(L, pen), maxiter=10_000)
    return p


@pytest.mark.parametrize("seed", range(5))
def test_halfspace_matches_the_qp_reference(seed):
    C, pen = _problem(seed)
    p, active = halfspace(pen, C)
    ref = _reference(C, pen)
    np.testing.assert_allclose(p, ref, atol=SOLVER_RTOL * ref.max())
    u = C @ p
    assert (p >= 0).all()
    assert u[active] == pytest.approx(pen[active], rel=1e-9)
    assert (u >= pen - 1e-12).all()  # no node left inside the plate


@pytest.mark.parametrize("seed", range(3))
def test_schur_path_and_warm_start_agree(seed):
    C, pen = _problem(seed)
    pen = pen + 2e-4  # most nodes in contact: the Schur-complement path
    p1, a1 = halfspace(pen, C)
    p2, a2 = halfspace(pen, C, active=None, K=np.linalg.inv(C))
    p3, _ = halfspace(pen, C, active=~a1, K=np.linalg.inv(C))  # a bad warm start
    np.testing.assert_allclose(p2, p1, rtol=1e-7, atol=1e-9 * p1.max())
    np.testing.assert_allclose(p3, p1, rtol=1e-7, atol=1e-9 * p1.max())
    assert (a1 == a2).all()


def test_no_penetration_no_load_and_winkler_is_local():
    C, pen = _problem(0)
    p, active = halfspace(-np.abs(pen), C)
    assert not p.any() and not active.any()
    np.testing.assert_array_equal(winkler(np.array([-1.0, 0.0, 2e-4]), 1e8), [0.0, 0.0, 2e4])


def test_numba_readout_equals_numpy_reference():
    from sim_tactile.sim.collide.reference import penetration_map, penetration_map_reference

    rng = np.random.default_rng(3)
    node_of_geom = np.array([-1, -1, 0, 1, 2, 3, 4, -1])
    # contacts between node geoms (2..6) and plate geoms (0, 1, 7), either order, duplicates
    g_node = rng.integers(2, 7, 40)
    g_plate = rng.choice([0, 1, 7], 40)
    flip = rng.random(40) < 0.5
    geom = np.where(flip[:, None], np.c_[g_plate, g_node], np.c_[g_node, g_plate]).astype(np.int32)
    dist = rng.normal(0, 1e-4, 40)
    pen = np.empty(5)
    penetration_map(geom, dist, node_of_geom, pen)
    np.testing.assert_array_equal(pen, penetration_map_reference(geom, dist, node_of_geom, 5))


@pytest.mark.parametrize("with_k", [False, True])
def test_active_set_updates_agree_with_the_fresh_solve(with_k):
    """The incrementally updated inverse gives the fresh solve's pressures while the contact
    set grows, shrinks, jumps and empties, including through its periodic rebuilds."""
    from sim_tactile.sim.skin.contact import ActiveSet

    C, pen = _problem(1, n=11)
    K = np.linalg.inv(C) if with_k else None
    solver = ActiveSet(C, K, refresh=7)  # small refresh: the rebuild path runs too
    rng = np.random.default_rng(0)
    X = (np.arange(C.shape[0]) % 11) * 1e-3
    shifts = list(np.linspace(-1e-4, 4e-4, 12)) + [0.0, -1.0, 2e-4]  # -1: no contact at all
    for k, shift in enumerate(shifts):
        # a ridge edge sweeping across the grid changes the set by whole columns
        edge = 0.5e-3 * k
        step = np.where(X < edge, 5e-5, 0.0)
        pen_k = pen + shift + step + 1e-6 * rng.standard_normal(pen.size)
        p_ref, a_ref = halfspace(pen_k, C)
        p, a = solver.solve(pen_k)
        scale = max(p_ref.max(), 1e-30)
        np.testing.assert_allclose(p, p_ref, rtol=0, atol=1e-9 * scale)
        assert (a == a_ref).all()
        if a.any():
            # the pad's contact stiffness is 1' inv(C_SS) 1
            S = np.flatnonzero(a)
            want = np.linalg.solve(C[np.ix_(S, S)], np.ones(S.size)).sum()
            assert solver.stiffness_per_area() == pytest.approx(want, rel=1e-8)
    assert solver.rebuilds > 1


def test_active_set_is_deterministic():
    from sim_tactile.sim.skin.contact import ActiveSet

    C, pen = _problem(2)
    outs = []
    for _ in range(2):
        solver = ActiveSet(C, np.linalg.inv(C), refresh=5)
        outs.append([solver.solve(pen + s)[0] for s in np.linspace(-5e-5, 3e-4, 9)])
    for a, b in zip(*outs, strict=True):
        np.testing.assert_array_equal(a, b)


# --- a skin that bulges: the layered compliance has negative entries --------------------------


def _layered_problem():
    """A 1 mm incompressible layer bonded to the bone: a load lifts the surface around it
    toward the plate (C has negative entries), so nodes that do not overlap the plate can be
    pushed into contact. A 1 mm wide ridge pressed 40 um deep, the rest of the plate 1 um below the
    pad."""
    from sim_tactile.scene.layered import layered_compliance_matrix
    from sim_tactile.sensors.stack import Layer, Stack

    xs = np.arange(-12, 13) * 0.25e-3
    X, Y = np.meshgrid(xs, xs[::3])
    xy = np.column_stack([X.ravel(), Y.ravel()])
    C = layered_compliance_matrix(xy, 0.25e-3, Stack((Layer(1e-3, 0.3e6, 0.5),)), pitch_y_m=0.75e-3)
    pen = np.where(np.abs(xy[:, 0]) <= 0.5e-3, 40e-6, -1e-6)
    return C, pen


def test_a_bulging_skin_brings_nodes_below_the_plate_into_contact():
    from sim_tactile.sim.skin.contact import ActiveSet

    C, pen = _layered_problem()
    assert (C < 0).any()
    ref = _reference(C, pen)
    assert (ref[pen < 0] > 0).any(), "the case must have nodes pushed into contact by the bulge"
    s = ActiveSet(C, np.linalg.inv(C))
    p, _ = s.solve(pen)
    np.testing.assert_allclose(p, ref, atol=SOLVER_RTOL * ref.max())
    assert (C @ p >= pen - 1e-12).all()


def test_a_bulging_skin_holds_its_force():
    """Held at a total pressure: the shift and pressures satisfy the contact conditions at
    every node, the bulged ones included, and sum to the total."""
    from sim_tactile.sim.skin.contact import ActiveSet

    C, pen = _layered_problem()
    total = 2 * _reference(C, pen).sum()
    p, dz = ActiveSet(C, np.linalg.inv(C)).solve_force(pen, total)
    assert p.sum() == pytest.approx(total, rel=1e-9)
    ref = _reference(C, pen + dz)
    np.testing.assert_allclose(p, ref, atol=SOLVER_RTOL * ref.max())


# --- friction coupled into the normal problem: a compliance that is not symmetric ------------


def test_friction_coupled_contact_solves_the_unsymmetric_problem():
    """The layered problem with the tractions mu p of a slide along +x: the compliance
    C - mu D is not symmetric, so the solver factorises each contact set anew (no K, no
    block updates). Its answer is the fixed point of the symmetric problem with the
    tractions' deflection moved to the right-hand side (each step solved by the NNLS
    reference), and it satisfies the contact conditions at every node; the load moves to
    the trailing (-x) side."""
    from sim_tactile.scene.tractions import shear_normal_compliance
    from sim_tactile.sensors.stack import Layer, Stack
    from sim_tactile.sim.skin.contact import REFRESH, ActiveSet

    C, pen = _layered_problem()
    xs = np.arange(-12, 13) * 0.25e-3
    X, Y = np.meshgrid(xs, xs[::3])
    xy = np.column_stack([X.ravel(), Y.ravel()])
    mu = 0.5
    D = shear_normal_compliance(xy, 0.25e-3, Stack((Layer(1e-3, 0.3e6, 0.5),)), pitch_y_m=0.75e-3)
    Ce = C - mu * D
    assert np.abs(Ce - Ce.T).max() > 0.01 * np.abs(C).max()
    p, _ = ActiveSet(Ce, None, refresh=0, symmetric=False).solve(pen)
    ref = _reference(C, pen)
    for _ in range(200):  # C p = pen + mu D p on the contact set
        nxt = _reference(C, pen + mu * D @ ref)
        if np.abs(nxt - ref).max() <= 1e-13 * nxt.max():
            break
        ref = nxt
    np.testing.assert_allclose(p, nxt, atol=SOLVER_RTOL * nxt.max())
    u = Ce @ p
    assert (p >= 0).all() and (u >= pen - 1e-12 * pen.max()).all()
    assert u[p > 0] == pytest.approx(pen[p > 0], rel=1e-9)
    frictionless = _reference(C, pen)
    trailing, leading = xy[:, 0] < 0, xy[:, 0] > 0
    assert p[trailing].sum() > 1.05 * p[leading].sum()
    assert frictionless[trailing].sum() == pytest.approx(frictionless[leading].sum(), rel=1e-6)
    # held at a force: the same answer as the displacement-controlled solve at its shift
    held, dz = ActiveSet(Ce, None, refresh=0, symmetric=False).solve_force(pen, 2 * p.sum())
    assert held.sum() == pytest.approx(2 * p.sum(), rel=1e-9)
    again, _ = ActiveSet(Ce, None, refresh=0, symmetric=False).solve(pen + dz)
    np.testing.assert_allclose(held, again, atol=SOLVER_RTOL * held.max())
    assert REFRESH > 0


def test_the_unsymmetric_block_updates_follow_a_sliding_contact():
    """The friction-coupled problem solved step after step while the ridge slides across
    the pad, with the inverse of C - mu D updated by the general block formulas (and its K
    for large sets, refreshed every 3 updates): every step equals a fresh factorisation of
    its own contact set. Taking the symmetric formulas instead is wrong: answers off, or no
    convergence (checked)."""
    from sim_tactile.scene.layered import layered_compliance_matrix
    from sim_tactile.scene.tractions import shear_normal_compliance
    from sim_tactile.sensors.stack import Layer, Stack
    from sim_tactile.sim.skin.contact import ActiveSet

    xs = np.arange(-12, 13) * 0.25e-3
    X, Y = np.meshgrid(xs, xs[::3])
    xy = np.column_stack([X.ravel(), Y.ravel()])
    st = Stack((Layer(1e-3, 0.3e6, 0.5),))
    Ce = layered_compliance_matrix(xy, 0.25e-3, st, pitch_y_m=0.75e-3) - 0.5 * (
        shear_normal_compliance(xy, 0.25e-3, st, pitch_y_m=0.75e-3)
    )
    K = np.linalg.inv(Ce)
    general = ActiveSet(Ce, K, refresh=3, symmetric=False)
    wrong = ActiveSet(Ce, K, refresh=3, symmetric=True)
    worst_wrong = 0.0
    for k, centre in enumerate(np.linspace(-2.5e-3, 2.5e-3, 21)):
        width = 1.0e-3 if k % 2 else 3.5e-3  # the set grows and shrinks by blocks
        pen = np.where(np.abs(xy[:, 0] - centre) <= width / 2, 40e-6, -1e-6)
        fresh, _ = ActiveSet(Ce, None, refresh=0, symmetric=False).solve(pen)
        p, _ = general.solve(pen)
        np.testing.assert_allclose(p, fresh, atol=SOLVER_RTOL * fresh.max())
        try:
            q, _ = wrong.solve(pen)
        except PhysicsError:  # the symmetric formulas can lose the solve altogether
            worst_wrong = np.inf
            wrong = ActiveSet(Ce, K, refresh=3, symmetric=True)
            continue
        worst_wrong = max(worst_wrong, np.abs(q - fresh).max() / fresh.max())
    assert general.updates + general.rebuilds > 10  # the block paths ran
    assert worst_wrong > 1e-3


def test_block_updates_stay_the_inverse_while_ridges_slide_under_fine_nodes():
    """finger7's ridges (2.5 mm wide, 9 mm apart) slide under a 16 mm pad of 0.25 x 2 mm
    nodes, the force held: the set changes by whole columns at every step. Unchecked, the block
    updates amplified round-off about 1.6x per update, to 5e-3 of the inverse before the
    periodic rebuild (the mirror taxels then read 3% apart); the drift check rebuilds first.
    Every step's pressures equal a fresh factorisation of their set, and the inverse stays
    the inverse."""
    from sim_tactile.sim.skin.contact import ActiveSet

    xs = (np.arange(64) - 31.5) * 0.25e-3
    ys = (np.arange(8) - 3.5) * 2e-3
    X, Y = np.meshgrid(xs, ys)
    xy = np.column_stack([X.ravel(), Y.ravel()])
    C = compliance_matrix(xy, 0.25e-3, 0.4e6, pitch_y_m=2e-3)
    solver = ActiveSet(C)
    total = 1.0 / (0.25e-3 * 2e-3)  # 1 N over the node area
    worst, changes, last = 0.0, 0, None
    for k in range(150):
        x0 = k * 0.12e-3  # 60 mm/s at 2 ms
        phase = np.mod(xy[:, 0] + x0, 9e-3)
        on = phase < 2.5e-3
        pen = np.where(on, 1e-4 * (1 - (xy[:, 0] / 8e-3) ** 2), -2.5e-3)
        p, dz = solver.solve_force(pen, total)
        S = solver.S
        changes += last is not None and set(S) != last
        last = set(S)
        if S.size:
            worst = max(worst, np.abs(solver.M @ C[np.ix_(S, S)] - np.eye(S.size)).max())
            fresh = np.zeros_like(p)
            fresh[S] = np.linalg.solve(C[np.ix_(S, S)], (pen + dz)[S])
            np.testing.assert_allclose(p, fresh, rtol=0, atol=SOLVER_RTOL * fresh.max())
    assert changes > 50  # the update paths ran
    assert worst < 1e-8


def test_the_drift_checks_running_sums_follow_the_set():
    """The drift check reads ``C_SS v`` (v: ones, and each node's sign) from sums the block
    updates keep by node; while the set grows, shrinks and is rebuilt, they stay the sums a
    fresh pass over C gives, to rounding, and every set's inverse passes the check."""
    from sim_tactile.sim.skin.contact import ActiveSet
    from sim_tactile.sim.skin.contact.inverse import DRIFT_TOL

    xs = (np.arange(40) - 19.5) * 0.25e-3
    ys = (np.arange(6) - 2.5) * 1e-3
    X, Y = np.meshgrid(xs, ys)
    xy = np.column_stack([X.ravel(), Y.ravel()])
    C = compliance_matrix(xy, 0.25e-3, 0.4e6, pitch_y_m=1e-3)
    solver = ActiveSet(C, refresh=30)
    sign = np.where(np.arange(C.shape[0]) % 2 == 0, 1.0, -1.0)
    total = 0.5 / (0.25e-3 * 1e-3)
    sizes, changes, last = set(), 0, None
    for k in range(80):
        phase = np.mod(xy[:, 0] + k * 0.1e-3, 3e-3)
        pen = np.where(phase < 1.2e-3, 5e-5 * (1 - (xy[:, 1] / 4e-3) ** 2), -1e-3)
        solver.solve_force(pen, total)
        S = solver.S
        sizes.add(S.size)
        changes += last is not None and set(S) != last
        last = set(S)
        if not S.size:
            continue
        CSS = C[np.ix_(S, S)]
        want = np.column_stack([CSS.sum(axis=1), CSS @ sign[S]])
        np.testing.assert_allclose(
            solver.sums[S], want, rtol=1e-10, atol=1e-12 * np.abs(want).max()
        )
        resid = np.abs(solver.M @ want - np.column_stack([np.ones(S.size), sign[S]])).max()
        assert resid <= 2 * DRIFT_TOL
    assert len(sizes) > 5 and changes > 40 and solver.rebuilds > 1  # the paths ran


@pytest.mark.parametrize("sym", [True, False])
def test_each_block_update_checks_the_inverse_it_writes(sym):
    """A node block joining (the Schur complement of C) and leaving (of M), on a symmetric
    and on a friction-coupled compliance: the updated inverse is inv(C_TT) of the new set, and
    the update's own drift check, made row by row as it writes, passes it; an inverse put off
    by 1e-6 in one row, in the set's kept part or in its new rows, is flagged."""
    from sim_tactile.scene.layered import layered_compliance_matrix
    from sim_tactile.scene.tractions import shear_normal_compliance
    from sim_tactile.sensors.stack import Layer, Stack
    from sim_tactile.sim.skin.contact.inverse import (
        NO_SUMS,
        check_vectors,
        inverse_with,
        inverse_without,
    )

    xs = np.arange(-5, 6) * 0.5e-3
    X, Y = np.meshgrid(xs, xs[::2])
    xy = np.column_stack([X.ravel(), Y.ravel()])
    st = Stack((Layer(1e-3, 0.3e6, 0.5),))
    C = layered_compliance_matrix(xy, 0.5e-3, st, pitch_y_m=1e-3)
    if not sym:
        C = C - 0.5 * shear_normal_compliance(xy, 0.5e-3, st, pitch_y_m=1e-3)
    S = np.arange(3, 40, dtype=np.int64)
    A = np.array([0, 50, 62], dtype=np.int64)
    T = np.concatenate((S, A))
    M = np.linalg.inv(C[np.ix_(S, S)])
    out, off = inverse_with(M, C, S, A, sym, check_vectors(C, T, NO_SUMS))
    np.testing.assert_allclose(out, np.linalg.inv(C[np.ix_(T, T)]), rtol=1e-9, atol=0)
    assert not off
    bad = M.copy()
    bad[7] *= 1 + 1e-6
    assert inverse_with(bad, C, S, A, sym, check_vectors(C, T, NO_SUMS))[1]
    keep = np.flatnonzero(~np.isin(T, [5, 17, 50]))
    kept = T[keep]
    drop = np.flatnonzero(np.isin(T, [5, 17, 50]))
    u = check_vectors(C, kept, NO_SUMS)
    back, off = inverse_without(out, keep, drop, sym, T, u)
    np.testing.assert_allclose(back, np.linalg.inv(C[np.ix_(kept, kept)]), rtol=1e-9, atol=0)
    assert not off
    for row in (0, T.size - 1):  # a kept row of S, a kept row that joined
        bad = out.copy()
        bad[row] *= 1 + 1e-6
        assert inverse_without(bad, keep, drop, sym, T, u)[1], row


def test_the_ordered_product_is_the_plain_loops_bit_for_bit():
    """The same-set checks' displacements at the nodes outside the set, four rows at a time:
    each equals the plain loop's sum over the set in its order, in Python's floats, byte for
    byte, for every count of rows (the blocks of four and the rest) and a set out of order."""
    from sim_tactile.sim.skin.contact.kernels import ordered_product

    rng = np.random.default_rng(3)
    C = rng.standard_normal((40, 40))
    S = rng.permutation(40)[:23].astype(np.int64)
    pS = rng.standard_normal(23) * 1e3
    for count in range(10):
        rows = rng.choice(40, size=count, replace=False).astype(np.int64)
        got = ordered_product(C, rows, S, pS)
        want = []
        for j in rows:
            acc = 0.0
            for k in range(S.size):
                acc += float(C[j, S[k]]) * float(pS[k])
            want.append(acc)
        assert got.tobytes() == np.array(want, dtype=np.float64).tobytes(), count


def test_a_read_only_compliance_has_its_floor_read_once():
    """A skin's kept matrix is read-only: its floor is read once per process (the entry holds
    the array, so its id is not reused); a writeable matrix is read each time, so a change
    to it is seen."""
    from sim_tactile.sim.skin.contact import active_set

    C = np.eye(5) + 0.1
    assert active_set.skin_floor(C) == 0.0
    C[0, 1] = -1e-3  # writeable: read again
    assert active_set.skin_floor(C) == -np.inf
    kept = np.eye(5) + 0.1
    kept.flags.writeable = False
    assert active_set.skin_floor(kept) == 0.0
    assert active_set._FLOORS[id(kept)][0] is kept
    bulging = -np.ones((3, 3))
    bulging.flags.writeable = False
    assert active_set.skin_floor(bulging) == -np.inf
    assert len(active_set._FLOORS) <= active_set.FLOORS_KEPT


def test_a_kept_matrix_read_from_the_cache_has_its_floor_read_once(tmp_path):
    """A matrix read from a cache entry is a view of the buffer it was read into; the
    set-up memo makes that buffer read-only too, so the floor is read once for it. A
    read-only view of a writeable array is read each time: a change through the array is
    seen."""
    from sim_tactile.cache import ArrayMemo
    from sim_tactile.sim.skin.contact import active_set

    buf = np.ones(36)
    view = buf.reshape(6, 6)
    view.flags.writeable = False
    assert active_set.skin_floor(view) == 0.0 and id(view) not in active_set._FLOORS
    buf[3] = -1.0  # through the writeable array it views
    assert active_set.skin_floor(view) == -np.inf
    buf[3] = 1.0
    (kept,) = ArrayMemo(1 << 20).put("k", (view,))
    assert not buf.flags.writeable  # the memo's arrays are read-only through and through
    assert active_set.skin_floor(kept) == 0.0 and active_set._FLOORS[id(kept)][0] is kept
