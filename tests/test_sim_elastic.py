"""The skin's closed-form elasticity against numerical quadrature (scipy)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from sim_tactile.scene.elastic import compliance_matrix, rect_integral, subsurface_weights

#: dblquad's own accuracy on these smooth (or integrable-singular) integrands.
QUAD_RTOL = 1e-6


@pytest.mark.parametrize(("x", "y"), [(0.3, 0.1), (2.0, 1.0), (0.5, 0.5), (-0.7, 0.2), (0.0, 3.0)])
def test_rect_integral_matches_quadrature(x, y):
    ref, _ = integrate.dblquad(
        lambda yy, xx: 1 / np.hypot(x - xx, y - yy),
        -0.5,
        0.5,
        -0.4,
        0.4,
        epsabs=1e-12,
        epsrel=1e-10,
    )
    assert rect_integral(np.array(x), np.array(y), 0.5, 0.4) == pytest.approx(ref, rel=QUAD_RTOL)


def test_rect_integral_at_the_centre_is_closed_form():
    # integral of 1/r over a square of side 2 seen from its centre: 8 asinh(1)
    assert rect_integral(np.array(0.0), np.array(0.0), 1.0, 1.0) == pytest.approx(
        8 * np.arcsinh(1.0)
    )


def test_compliance_is_symmetric_positive_definite():
    xs = np.arange(-3, 4) * 1e-3
    X, Y = np.meshgrid(xs, xs)
    C = compliance_matrix(np.column_stack([X.ravel(), Y.ravel()]), 1e-3, 0.4e6)
    np.testing.assert_allclose(C, C.T, rtol=1e-12)
    assert np.linalg.eigvalsh(C).min() > 0


@pytest.mark.parametrize("depth", [0.2e-3, 1e-3])
def test_subsurface_weights_match_boussinesq_quadrature(depth):
    node = np.array([[0.4e-3, -0.3e-3]])
    sx, sy = 2e-3, 1.5e-3

    def kernel(yy, xx):  # Boussinesq vertical stress of a unit point load at the node
        r2 = (xx - node[0, 0]) ** 2 + (yy - node[0, 1]) ** 2 + depth**2
        return 3 * depth**3 / (2 * np.pi * r2**2.5)

    ref, _ = integrate.dblquad(kernel, -sx / 2, sx / 2, -sy / 2, sy / 2, epsabs=1e-12)
    w = subsurface_weights(node, 0.1e-3, np.zeros((1, 2)), np.array([[sx, sy]]), np.array([depth]))
    assert w[0, 0] == pytest.approx(ref, rel=QUAD_RTOL)


def test_surface_weights_are_area_overlap_and_conserve_load():
    xs = np.arange(-10, 11) * 0.5e-3
    X, Y = np.meshgrid(xs, xs)
    nodes = np.column_stack([X.ravel(), Y.ravel()])
    # contiguous taxels tiling the nodes' area carry every node load exactly once
    t = np.arange(-2, 3) * 2e-3
    TX, TY = np.meshgrid(t, t)
    taxels = np.column_stack([TX.ravel(), TY.ravel()])
    W = subsurface_weights(nodes, 0.5e-3, taxels, np.full((25, 2), 2e-3), np.zeros(25))
    inside = (np.abs(nodes) <= 5e-3 - 1e-12).all(axis=1)
    np.testing.assert_allclose(W.sum(axis=0)[inside], 1.0, atol=1e-12)


def test_a_rectangular_patch_deflects_as_its_square_halves():
    """Superposition: a 1 x 2 mm patch under uniform pressure deflects every point as its two
    1 x 1 mm halves together (the anisotropic skin grid's compliance)."""
    pts = np.array([[0.0, 0.0], [0.3e-3, 0.7e-3], [2e-3, -1e-3], [5e-3, 4e-3]])
    rect = np.vstack([np.zeros(2), pts])
    C_rect = compliance_matrix(rect, 1e-3, 0.4e6, pitch_y_m=2e-3)[1:, 0]
    halves = np.array([[0.0, -0.5e-3], [0.0, 0.5e-3]])
    sq = np.vstack([halves, pts])
    C_sq = compliance_matrix(sq, 1e-3, 0.4e6)[2:, :2].sum(axis=1)
    np.testing.assert_allclose(C_rect, C_sq, rtol=1e-12)


def test_rectangular_nodes_are_area_overlap_and_conserve_load():
    xs = np.arange(-10, 11) * 0.5e-3
    ys = np.arange(-5, 6) * 1e-3
    X, Y = np.meshgrid(xs, ys)
    nodes = np.column_stack([X.ravel(), Y.ravel()])
    t = np.arange(-2, 3) * 2e-3
    TX, TY = np.meshgrid(t, t)
    taxels = np.column_stack([TX.ravel(), TY.ravel()])
    W = subsurface_weights(
        nodes, 0.5e-3, taxels, np.full((25, 2), 2e-3), np.zeros(25), pitch_y_m=1e-3
    )
    inside = (np.abs(nodes) <= 5e-3 - 1e-12).all(axis=1)
    np.testing.assert_allclose(W.sum(axis=0)[inside], 1.0, atol=1e-12)
    # a node whose 1 mm row straddles a taxel's edge gives it half its load
    k = np.flatnonzero((np.abs(nodes[:, 0]) < 1e-9) & (np.abs(nodes[:, 1] - 1e-3) < 1e-9))[0]
    centre = np.flatnonzero((np.abs(taxels) < 1e-9).all(axis=1))[0]
    assert W[centre, k] == pytest.approx(0.5, abs=1e-12)
