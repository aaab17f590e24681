"""The half-space contact solver against a quadratic-programming reference (scipy)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import nnls

from sim_tactile.scene.elastic import compliance_matrix
from sim_tactile.sim.contact import halfspace, winkler

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
    from sim_tactile.sim._readout import penetration_map, penetration_map_reference

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


def test_factor_cache_gives_the_same_pressures():
    from sim_tactile.sim.contact import FactorCache

    C, pen = _problem(1)
    cache = FactorCache(size=2)
    K = np.linalg.inv(C)
    for shift in (0.0, 1e-6, 0.0, 3e-4, 3e-4 + 1e-7):  # small shifts keep the contact set
        p_ref, _ = halfspace(pen + shift, C, K=K)
        p, _ = halfspace(pen + shift, C, K=K, cache=cache)
        np.testing.assert_allclose(p, p_ref, rtol=1e-9, atol=1e-12 * p_ref.max())
    assert cache.hits > 0 and cache.misses > 0
