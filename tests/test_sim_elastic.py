"""The skin's closed-form elasticity against numerical quadrature (scipy)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from sim_tactile.scene.elastic import compliance_matrix, rect_integral, subsurface_weights

#: dblquad's own accuracy on these smooth (or integrable-singular) integrands.
QUAD_RTOL = 1e-6
#: the patch quadrature (points a quarter of the depth apart) against scipy's
PATCH_RTOL = 1e-4
#: a uniform pressure read by buried taxels: the issue's bound is 1%; the far field cut at
#: 30 depths leaves about 4e-5
UNIFORM_ATOL = 1e-3


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


def _boussinesq_over_taxel(px, py, depth, sx, sy):
    """Vertical stress of a unit point load at (px, py), integrated by dblquad over the
    sx x sy taxel centred at the origin at ``depth``."""

    def kernel(yy, xx):
        r2 = (xx - px) ** 2 + (yy - py) ** 2 + depth**2
        return 3 * depth**3 / (2 * np.pi * r2**2.5)

    ref, _ = integrate.dblquad(kernel, -sx / 2, sx / 2, -sy / 2, sy / 2, epsabs=1e-12)
    return ref


@pytest.mark.parametrize("depth", [0.2e-3, 1e-3])
def test_subsurface_weights_of_a_small_patch_match_boussinesq_quadrature(depth):
    """A patch far smaller than the depth acts as a point load."""
    node = np.array([[0.4e-3, -0.3e-3]])
    sx, sy = 2e-3, 1.5e-3
    ref = _boussinesq_over_taxel(*node[0], depth, sx, sy)
    w = subsurface_weights(node, 1e-7, np.zeros((1, 2)), np.array([[sx, sy]]), np.array([depth]))
    assert w[0, 0] == pytest.approx(ref, rel=QUAD_RTOL)


@pytest.mark.parametrize(
    ("depth", "node"), [(0.5e-3, (0.9e-3, 0.2e-3)), (0.3e-3, (1.2e-3, 0.7e-3))]
)
def test_subsurface_weights_average_the_patch(depth, node):
    """A patch wide against the depth (1 x 0.6 mm at 0.3-0.5 mm, straddling the taxel's edge):
    its weight is the patch average of the point-load stress, by scipy's Gauss-Legendre rule
    (fixed_quad, 12 x 12 points) over dblquad."""
    sx, sy, hx, hy = 2e-3, 1.5e-3, 0.5e-3, 0.3e-3

    def over_y(px):
        return np.array(
            [
                integrate.fixed_quad(
                    lambda ys, p=p: np.array(
                        [_boussinesq_over_taxel(p, y, depth, sx, sy) for y in ys]
                    ),
                    node[1] - hy,
                    node[1] + hy,
                    n=12,
                )[0]
                for p in np.atleast_1d(px)
            ]
        )

    ref = integrate.fixed_quad(over_y, node[0] - hx, node[0] + hx, n=12)[0] / (4 * hx * hy)
    w = subsurface_weights(
        np.array([node]),
        2 * hx,
        np.zeros((1, 2)),
        np.array([[sx, sy]]),
        np.array([depth]),
        pitch_y_m=2 * hy,
    )
    assert w[0, 0] == pytest.approx(ref, rel=PATCH_RTOL)


def test_icub_taxels_read_a_uniform_pressure_as_pressure_times_area():
    """icub60's default nodes (0.45 x 3 mm) are coarse against its taxels' depth (0.5 mm).
    Under a uniform pressure over a wide field of nodes every taxel reads pressure x area;
    point loads at the node centres read 0.3 to 1.5 of it."""
    from sim_tactile.sensors import get_sensor

    layout = get_sensor("icub60").layout
    hx, hy = 0.45e-3, 3e-3
    xs = np.arange(-50, 51) * hx
    ys = np.arange(-8, 9) * hy
    X, Y = np.meshgrid(xs, ys)
    nodes = np.column_stack([X.ravel(), Y.ravel()])
    W = subsurface_weights(
        nodes, hx, layout.positions[:, :2], layout.sizes, layout.depth_m, pitch_y_m=hy
    )
    p = 1e3  # Pa
    reading = W @ np.full(len(nodes), p * hx * hy)
    exact = p * layout.sizes.prod(axis=1)
    np.testing.assert_allclose(reading / exact, 1.0, atol=UNIFORM_ATOL)


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
