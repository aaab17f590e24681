"""The layered skin's Fourier-domain solution against its limits, a closed form and a
plane-strain finite-element model (scikit-fem, a test extra)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate, special

from sim_tactile.errors import ConfigError
from sim_tactile.scene.elastic import compliance_matrix, subsurface_weights
from sim_tactile.scene.layered import (
    Layer,
    Stack,
    layer_response,
    layered_compliance_matrix,
    layered_subsurface_weights,
)
from sim_tactile.scene.tractions import shear_normal_compliance, shear_subsurface_weights
from sim_tactile.sim.skin.contact import ActiveSet

#: identities that hold to rounding
EXACT_RTOL = 1e-10
#: scikit-fem, P2 triangles 1/16 of the thickness, against the spectral solution: at most
#: 0.11% apart over these cases (the stress at depth, whose FEM value is a projection of a
#: piecewise-linear field), and closer when the mesh is refined to 1/32 (0.03%)
FEM_RTOL = 2e-3
#: the same under a shear strip, the stress at depth: 0.21% apart at 1/16 of the thickness,
#: 0.05% at 1/32 (the FEM converging on the spectral value)
FEM_SHEAR_STRESS_RTOL = 3e-3
#: the node grid's layered kernels, extrapolated to zero pitch, against axisymmetric Hankel
#: integrals: what is left is the tabulated remainder, its spline and its patch quadrature
#: (measured: at most 3.3e-4)
GRID_RTOL = 1e-3
#: a uniform pressure read by buried taxels in a stack (the remainder's table is cut at 60
#: stack thicknesses)
UNIFORM_ATOL = 1e-3
#: friction's normal deflection on the node grid (0.25 x 2 mm) against the plane-strain
#: strip integral: what is left is the collocation at the node centres and the Hankel table
#: (measured 0.02% to 0.06%)
STRIP_GRID_RTOL = 2e-3
#: the shear weights' FFT against Cerruti's closed form integrated by dblquad (measured 3e-4)
CERRUTI_RTOL = 1e-3

E, H = 0.3e6, 4e-3
K = np.logspace(0, 5.5, 23)  # wave numbers [1/m]: wavelengths from 6 m to 20 um


@pytest.mark.parametrize("nu", [0.3, 0.49, 0.5])
def test_a_layer_on_a_half_space_of_the_same_material_is_the_half_space(nu):
    """Deflection 2 / (E* k) and Boussinesq's stress (1 + kz) exp(-kz), at any depth."""
    st = Stack((Layer(H, E, nu),), "halfspace", E, nu)
    depths = np.array([0.0, 0.5e-3, 2e-3, 6e-3])
    w, s = layer_response(st, K, depths)
    np.testing.assert_allclose(w * K * E / (1 - nu**2) / 2, 1.0, rtol=EXACT_RTOL)
    kz = K[:, None] * depths[None, :]
    np.testing.assert_allclose(s, (1 + kz) * np.exp(-kz), rtol=EXACT_RTOL, atol=1e-300)


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45, 0.5])
def test_a_layer_bonded_to_a_rigid_base_has_the_closed_form(nu):
    """w = 2 / (E* k) K(kh), K(t) = (2c sinh 2t - 4t) / (2c cosh 2t + 1 + c^2 + 4t^2),
    c = 3 - 4 nu: the bonded layer's closed form, derived independently of the mode basis
    used here."""
    st = Stack((Layer(H, E, nu),))
    w, _ = layer_response(st, K)
    t, c = K * H, 3 - 4 * nu
    closed = np.ones_like(t)  # K -> 1 where sinh and cosh overflow
    ok = t < 300
    t = t[ok]
    closed_ok = (2 * c * np.sinh(2 * t) - 4 * t) / (2 * c * np.cosh(2 * t) + 1 + c**2 + 4 * t**2)
    closed[ok] = closed_ok
    np.testing.assert_allclose(w * K * E / (1 - nu**2) / 2, closed, rtol=1e-9)


def test_a_thin_compressible_layer_deflects_as_its_oedometric_modulus():
    nu = 0.3
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    w, _ = layer_response(Stack((Layer(H, E, nu),)), np.array([1e-2 / H]))
    assert w[0] == pytest.approx(H / M, rel=1e-4)


def test_equal_sublayers_are_one_layer_and_a_stiff_backing_is_rigid():
    one = Stack((Layer(H, E, 0.45),))
    two = Stack((Layer(H / 4, E, 0.45), Layer(3 * H / 4, E, 0.45)))
    d = np.array([0.3e-3, 1e-3, 3.5e-3])
    w1, s1 = layer_response(one, K, d)
    w2, s2 = layer_response(two, K, d)
    np.testing.assert_allclose(w2, w1, rtol=EXACT_RTOL)
    np.testing.assert_allclose(s2, s1, rtol=1e-9, atol=1e-12)
    # a backing 1e6 times stiffer: rigid, at wavelengths up to 6 cm (at longer ones any
    # half-space backing takes over: its deflection grows as 1 / k, the layer's stays h / M)
    stiff = Stack((Layer(H, E, 0.45),), "halfspace", 1e6 * E, 0.3)
    k = K[K >= 100]
    w1, s1 = layer_response(one, k, d)
    w3, s3 = layer_response(stiff, k, d)
    np.testing.assert_allclose(w3, w1, rtol=1e-4)
    np.testing.assert_allclose(s3, s1, rtol=1e-4, atol=1e-9)


def test_uniform_pressure_reaches_every_depth_whole():
    """At long wavelengths the vertical stress is the pressure at any depth (equilibrium)."""
    st = Stack((Layer(1e-3, 2 * E, 0.5), Layer(H, E, 0.45)), "halfspace", 5 * E, 0.3)
    _, s = layer_response(st, np.array([1e-3]), np.array([0.2e-3, 2e-3, 8e-3]))
    np.testing.assert_allclose(s, 1.0, atol=1e-5)


def test_bad_stacks_name_the_parameter():
    with pytest.raises(ConfigError, match="layer.poisson"):
        Layer(H, E, 0.6)
    with pytest.raises(ConfigError, match="stack.backing_young_pa"):
        Stack((Layer(H, E),), "halfspace")
    with pytest.raises(ConfigError, match="rigid backing"):
        layer_response(Stack((Layer(H, E),)), K, np.array([H]))


# --- plane strain against scikit-fem -------------------------------------------------------


def _gauss_panels(f, lo: float, hi: float, n_panels: int) -> float:
    """Composite 8-point Gauss-Legendre of a vectorised ``f`` over [lo, hi]."""
    t, w = np.polynomial.legendre.leggauss(8)
    e = np.linspace(lo, hi, n_panels + 1)
    half, mid = (e[1:] - e[:-1]) / 2, (e[1:] + e[:-1]) / 2
    k = (mid[:, None] + half[:, None] * t[None, :]).ravel()
    return float(np.sum((half[:, None] * w[None, :]).ravel() * f(k)))


def _strip_reference(
    stack: Stack, a: float, x: float, depth: float | None = None, load: str = "normal"
) -> float:
    """Unit pressure on |x| < a, plane strain: (1/pi) int_0^inf F(k) 2 sin(ka)/k cos(kx) dk,
    F the deflection (depth None) or the compressive vertical stress at ``depth``. A unit
    traction along +x (``load="shear"``): the response ``i F`` turns cos(kx) into
    -sin(kx), and the deflection's tail is ``c / k`` (zero for an incompressible top layer).

    Gauss panels a fraction of a radian of the integrand's phase wide, up to k1 = 40 / (top
    layer's thickness); beyond it the deflection is the top layer's half-space, 2 / (E* k),
    whose tail integrates in closed form (sine and cosine integrals), and the stress is
    integrated on until exp(-k depth) < 1e-17."""

    shear = load == "shear"

    def f(k):
        w, s = layer_response(stack, k, None if depth is None else [depth], load=load)
        F = w if depth is None else s[:, 0]
        phase = -np.sin(k * x) if shear else np.cos(k * x)
        return F * 2 * np.sin(k * a) / k * phase / np.pi

    k1 = 40 / stack.layers[0].thickness_m
    span = a + abs(x) + stack.thickness_m
    total = _gauss_panels(f, 0.0, k1, int(k1 * span / 0.5) + 10)
    if depth is None and shear:
        top = stack.layers[0]
        c = -(1 - 2 * top.poisson) * (1 + top.poisson) / top.young_pa

        # -(c / pi) int_k1^inf 2 sin(ka) sin(kx) / k^2 dk, 2 sin sin = cos(b-) - cos(b+), and
        # int_k1^inf cos(bk) / k^2 dk = cos(b k1) / k1 - |b| (pi / 2 - Si(|b| k1))
        def tail(b):
            return np.cos(b * k1) / k1 - abs(b) * (np.pi / 2 - special.sici(abs(b) * k1)[0])

        return total - c / np.pi * (tail(a - x) - tail(a + x))
    if depth is None:
        # (1/pi) (2/E*) int_k1^inf sin(ck)/k^2 dk per c = a +- x, and that integral is
        # sin(c k1)/k1 - c Ci(|c| k1)
        for c in (a + x, a - x):
            if c != 0:
                total += (
                    2
                    / (np.pi * stack.top_e_star_pa)
                    * (np.sin(c * k1) / k1 - c * special.sici(abs(c) * k1)[1])
                )
        return total
    k2 = 40 / depth
    if k2 > k1:
        total += _gauss_panels(f, k1, k2, int((k2 - k1) * span / 0.5) + 10)
    return total


def _strip_fem(layers, a, depth, n_per_h=16, far=12.0, load="normal"):
    """scikit-fem, plane strain: pressure 1 on |x| < a over ``layers`` ((thickness, E, nu)
    from the top) bonded to a rigid base, by symmetry on 0 < x < a + far H. Returns the
    deflection at x = 0 and x = a + H / 2 and the compressive vertical stress at (0, depth).
    ``load="shear"``: a traction 1 along +x on |x| < a instead, by antisymmetry (no vertical
    motion at x = 0); the deflection at x = a / 2 and a + H / 2 and the stress at
    (a / 2, depth)."""
    skfem = pytest.importorskip("skfem")
    from skfem.helpers import sym_grad
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    H_ = sum(t for t, _, _ in layers)
    L = a + far * H_
    xs = np.unique(np.r_[np.linspace(0, L, round(L / H_ * n_per_h) + 1), a])
    tops = np.cumsum([0.0] + [t for t, _, _ in layers])  # depths of the interfaces
    ys = np.unique(
        np.concatenate(
            [
                np.linspace(H_ - tops[j + 1], H_ - tops[j], max(2, round(n_per_h * t / H_)) + 1)
                for j, (t, _, _) in enumerate(layers)
            ]
        )
    )
    tol = 1e-9 * H_
    m = skfem.MeshTri.init_tensor(xs, ys).with_boundaries(
        {
            "bottom": lambda x: x[1] < tol,
            "left": lambda x: x[0] < tol,
            "right": lambda x: x[0] > L - tol,
        }
    )
    e = skfem.ElementVector(skfem.ElementTriP2())
    ib = skfem.Basis(m, e)
    depth_of = H_ - m.p[1, m.t].mean(axis=0)  # each element's depth
    K_ = None
    lame = np.zeros((2, m.t.shape[1]))
    for j, (_, young, nu) in enumerate(layers):
        ids = np.flatnonzero((depth_of > tops[j]) & (depth_of < tops[j + 1]))
        lam, mu = lame_parameters(young, nu)
        lame[:, ids] = [[lam], [mu]]
        part = skfem.asm(linear_elasticity(lam, mu), skfem.Basis(m, e, elements=ids))
        K_ = part if K_ is None else K_ + part
    loaded = m.facets_satisfying(lambda x: (x[1] > H_ - tol) & (x[0] < a + tol))

    shear = load == "shear"

    @skfem.LinearForm
    def traction(v, w):
        return 1.0 * v[0] if shear else -1.0 * v[1]

    f = skfem.asm(traction, skfem.FacetBasis(m, e, facets=loaded))
    D = np.concatenate(
        [
            ib.get_dofs("bottom").all(),
            ib.get_dofs("left").all("u^2" if shear else "u^1"),
            ib.get_dofs("right").all("u^1"),
        ]
    )
    u = skfem.solve(*skfem.condense(K_, f, D=D))
    xo = a + H_ / 2  # outside the load: at its edge the pressure steps, a weak point for P2
    xi = a / 2 if shear else 0.0
    uy = ib.probes(np.array([[xi, xo], [H_, H_]])) @ u  # (ux(xi), ux(xo), uy(xi), uy(xo))
    eps = sym_grad(ib.interpolate(u))
    lam_q, mu_q = lame[0][:, None], lame[1][:, None]
    syy = lam_q * (eps[0, 0] + eps[1, 1]) + 2 * mu_q * eps[1, 1]
    sb = ib.with_element(skfem.ElementTriP1())
    s = sb.probes(np.array([[xi], [H_ - depth]])) @ sb.project(syy)
    return -uy[2], -uy[3], -float(s[0])


@pytest.mark.parametrize(
    ("layers", "a", "depth"),
    [
        (((H, E, 0.3),), H, 0.5e-3),  # a strip as wide as the layer is thick
        (((H, E, 0.45),), H / 2, 2e-3),
        (((H, E, 0.49),), 2 * H, 0.5e-3),  # nearly incompressible silicone, a wide pad
        (((1e-3, 2 * E, 0.45), (3e-3, E / 2, 0.3)), H, 2e-3),  # two bonded layers
    ],
)
def test_strip_load_on_a_layer_matches_plane_strain_fem(layers, a, depth):
    st = Stack(tuple(Layer(t, young, nu) for t, young, nu in layers))
    w0, wo, s = _strip_fem(layers, a, depth)
    assert _strip_reference(st, a, 0.0) == pytest.approx(w0, rel=FEM_RTOL)
    assert _strip_reference(st, a, a + st.thickness_m / 2) == pytest.approx(wo, rel=FEM_RTOL)
    assert _strip_reference(st, a, 0.0, depth) == pytest.approx(s, rel=FEM_RTOL)


@pytest.mark.parametrize(
    ("layers", "a", "depth"),
    [
        (((H, E, 0.49),), H, 1e-3),  # nearly incompressible silicone: the base makes it move
        (((H, E, 0.3),), H / 2, 2e-3),
        (((1e-3, 2 * E, 0.45), (3e-3, E / 2, 0.3)), H, 2e-3),
    ],
)
def test_a_shear_strip_on_a_layer_matches_plane_strain_fem(layers, a, depth):
    """A tangential traction on |x| < a: the surface's normal deflection (the coupling of
    friction into the normal problem) and the stress at depth, against scikit-fem."""
    st = Stack(tuple(Layer(t, young, nu) for t, young, nu in layers))
    wi, wo, s = _strip_fem(layers, a, depth, load="shear")
    ref = (
        _strip_reference(st, a, a / 2, load="shear"),
        _strip_reference(st, a, a + st.thickness_m / 2, load="shear"),
        _strip_reference(st, a, a / 2, depth, load="shear"),
    )
    scale = max(abs(wi), abs(wo))
    assert ref[0] == pytest.approx(wi, abs=FEM_RTOL * scale)
    assert ref[1] == pytest.approx(wo, abs=FEM_RTOL * scale)
    assert ref[2] == pytest.approx(s, rel=FEM_SHEAR_STRESS_RTOL)


# --- real space: node compliance and taxel weights ----------------------------------------


def _gaussian_load(sigma: float, pitch: float):
    """Node patches of ``pitch`` out to 3 sigma, a Gaussian pressure of width ``sigma``
    sampled at their centres, and the index of the centre node."""
    n = round(3 * sigma / pitch)
    X, Y = np.meshgrid(np.arange(-n, n + 1) * pitch, np.arange(-n, n + 1) * pitch)
    xy = np.column_stack([X.ravel(), Y.ravel()])
    load = np.exp(-(xy[:, 0] ** 2 + xy[:, 1] ** 2) / (2 * sigma**2))
    return xy, load, int(np.argmin(np.hypot(xy[:, 0], xy[:, 1])))


def _richardson(f) -> float:
    """f at node pitches 0.2 and 0.1 mm, extrapolated to zero pitch (second order)."""
    coarse, fine = f(0.2e-3), f(0.1e-3)
    return (4 * fine - coarse) / 3


def _gaussian_hankel(stack: Stack | None, sigma: float, depth: float | None = None) -> float:
    """On the axis of the pressure exp(-r^2 / 2 sigma^2): sigma^2 int F(k) exp(-k^2 sigma^2
    / 2) k dk, F the deflection or the compressive stress at ``depth`` (scipy's quad)."""

    def f(k):
        w, s = layer_response(stack, np.atleast_1d(k), None if depth is None else [depth])
        F = w[0] if depth is None else s[0, 0]
        return F * np.exp(-((k * sigma) ** 2) / 2) * k * sigma**2

    edges = np.r_[0.0, np.geomspace(1e-3, 12, 60) / sigma]
    return sum(
        integrate.quad(f, lo, hi, limit=200)[0]
        for lo, hi in zip(edges[:-1], edges[1:], strict=True)
    )


def test_the_layers_half_space_limit_is_todays_half_space():
    """A stack of the half-space's own material: the compliance and the taxel weights of the
    half-space skin, to 1e-6."""
    st = Stack((Layer(2e-3, E, 0.45),), "halfspace", E, 0.45)
    xs = np.arange(-12, 13) * 0.5e-3
    ys = np.arange(-3, 4) * 2e-3
    X, Y = np.meshgrid(xs, ys)
    xy = np.column_stack([X.ravel(), Y.ravel()])
    C_hs = compliance_matrix(xy, 0.5e-3, E / (1 - 0.45**2), pitch_y_m=2e-3)
    C = layered_compliance_matrix(xy, 0.5e-3, st, pitch_y_m=2e-3)
    assert np.abs(C - C_hs).max() <= 1e-6 * np.abs(C_hs).max()
    taxels = np.array([[0.0, 0.0], [1.3e-3, -2.1e-3]])
    sizes = np.full((2, 2), 2e-3)
    depths = np.array([0.5e-3, 2.5e-3])
    W_hs = subsurface_weights(xy, 0.5e-3, taxels, sizes, depths, pitch_y_m=2e-3)
    W = layered_subsurface_weights(xy, 0.5e-3, taxels, sizes, depths, st, pitch_y_m=2e-3)
    assert np.abs(W - W_hs).max() <= 1e-6 * np.abs(W_hs).max()


@pytest.mark.slow
@pytest.mark.parametrize(("h", "nu"), [(2e-3, 0.3), (1e-3, 0.5), (4e-3, 0.5)])
def test_a_gaussian_load_on_the_node_grid_deflects_as_hankels_integral(h, nu):
    """The centre of a Gaussian pressure (sigma 1 mm) on a layer bonded to a rigid base: the
    node grid's layered compliance, extrapolated to zero pitch, against the axisymmetric
    Hankel integral. The grid itself converges at second order: at 0.2 mm nodes it is 0.2%
    to 0.8% low (the most for the thin incompressible layer), at 0.1 mm four times closer."""
    sigma = 1e-3
    st = Stack((Layer(h, E, nu),))

    def centre(pitch):
        xy, load, c = _gaussian_load(sigma, pitch)
        return (layered_compliance_matrix(xy, pitch, st) @ load)[c]

    assert _richardson(centre) == pytest.approx(_gaussian_hankel(st, sigma), rel=GRID_RTOL)


def test_buried_taxels_on_a_layer_read_a_uniform_pressure_whole():
    """Equilibrium: a uniform pressure reaches every depth of a stack whole, so a buried
    taxel reads pressure x area (icub60-like: 2 mm taxels 0.5 mm deep in a 1.5 mm two-layer
    skin on a rigid board, nodes 0.45 x 3 mm)."""
    st = Stack((Layer(0.5e-3, 2 * E, 0.45), Layer(1e-3, E, 0.49)))
    hx, hy = 0.45e-3, 3e-3
    X, Y = np.meshgrid(np.arange(-45, 46) * hx, np.arange(-7, 8) * hy)
    xy = np.column_stack([X.ravel(), Y.ravel()])
    taxels = np.array([[0.0, 0.0], [1.3e-3, 0.9e-3], [-2.2e-3, -1.7e-3]])
    sizes = np.full((3, 2), 2e-3)
    depths = np.array([0.5e-3, 0.5e-3, 1.2e-3])
    W = layered_subsurface_weights(xy, hx, taxels, sizes, depths, st, pitch_y_m=hy)
    reading = W @ np.full(len(xy), hx * hy)
    np.testing.assert_allclose(reading / sizes.prod(axis=1), 1.0, atol=UNIFORM_ATOL)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("depth", "stack"),
    [
        (0.5e-3, Stack((Layer(2e-3, E, 0.45),))),
        (1.5e-3, Stack((Layer(2e-3, E, 0.45),))),
        (1.2e-3, Stack((Layer(0.5e-3, 2 * E, 0.45), Layer(1e-3, E, 0.49)))),
    ],
)
def test_the_stress_under_a_gaussian_load_matches_hankels_integral(depth, stack):
    """A 0.1 mm taxel at depth on the axis of a Gaussian pressure (sigma 1 mm) on layers
    bonded to a rigid base reads the Hankel integral's stress x its area (the node grid
    extrapolated to zero pitch)."""
    sigma, t = 1e-3, 0.1e-3

    def reading(pitch):
        xy, load, _ = _gaussian_load(sigma, pitch)
        W = layered_subsurface_weights(
            xy, pitch, np.zeros((1, 2)), np.full((1, 2), t), np.array([depth]), stack
        )
        return (W @ (load * pitch**2))[0] / t**2

    assert _richardson(reading) == pytest.approx(
        _gaussian_hankel(stack, sigma, depth), rel=GRID_RTOL
    )


def test_a_grid_too_fine_for_the_taxel_weights_is_refused_with_the_reason():
    """Shallow taxels under a very thin top layer over a wide pad would need an FFT grid
    beyond its cap: refused, naming the depth and the layer, not read coarsely."""
    st = Stack((Layer(20e-6, E, 0.45), Layer(2e-3, E, 0.45)))
    xy = np.array([[-20e-3, -15e-3], [20e-3, 15e-3]])
    with pytest.raises(ConfigError, match="need a .* grid to read"):
        layered_subsurface_weights(
            xy, 0.5e-3, np.zeros((1, 2)), np.full((1, 2), 1e-3), np.array([10e-6]), st
        )


# --- sliding friction: tangential tractions on the skin ---------------------------------------


def test_a_shear_traction_on_a_half_space_has_cerruti_and_johnsons_closed_forms():
    """Per wave number: the stress at depth is -k d exp(-k d) (Cerruti's, a quarter wave
    out of phase), and the surface moves normally by (1 - 2 nu) / (2 (1 - nu)) of a pressure's
    deflection (zero when incompressible)."""
    d = np.array([0.5e-3, 2e-3])
    for nu in (0.3, 0.5):
        st = Stack((Layer(H, E, nu),), "halfspace", E, nu)
        w, s = layer_response(st, K, d, load="shear")
        kd = K[:, None] * d
        np.testing.assert_allclose(s, -kd * np.exp(-kd), rtol=EXACT_RTOL, atol=1e-300)
        ratio = -(1 - 2 * nu) / (2 * (1 - nu))
        np.testing.assert_allclose(w * K * E / (1 - nu**2) / 2, ratio, atol=1e-12)


@pytest.mark.parametrize("node", [(0.8e-3, 0.3e-3), (-1.5e-3, 0.2e-3), (2.5e-3, -1e-3)])
def test_shear_weights_on_a_half_space_are_cerrutis_stress(node):
    """A tangential point force Q along +x: the vertical stress at depth d is compressive
    ahead of it, 3 Q x d^2 / (2 pi R^5) (Cerruti), integrated over the taxel by dblquad."""
    d, sx, sy = 1e-3, 2e-3, 1.5e-3

    def cerruti(yy, xx):
        X, Y = xx - node[0], yy - node[1]
        return 3 * X * d * d / (2 * np.pi * np.sqrt(X * X + Y * Y + d * d) ** 5)

    want, _ = integrate.dblquad(cerruti, -sx / 2, sx / 2, -sy / 2, sy / 2, epsabs=1e-13)
    st = Stack((Layer(H, E, 0.5),), "halfspace", E, 0.5)
    got = shear_subsurface_weights(
        np.array([node]), 1e-5, np.zeros((1, 2)), np.array([[sx, sy]]), np.array([d]), st
    )
    assert got[0, 0] == pytest.approx(want, rel=CERRUTI_RTOL)


@pytest.mark.parametrize("node", [(0.8e-3, 0.3e-3), (-1.5e-3, 0.2e-3), (0.1e-3, -0.05e-3)])
def test_friction_deflects_a_compressible_half_space_as_cerruti_and_not_an_incompressible_one(
    node,
):
    """A tangential force Q along +x on a half-space moves the surface by
    (1 - 2 nu)(1 + nu) Q x / (2 pi E r^2) into the body (Cerruti; the sign by reciprocity
    with the inward pull of a normal load): the deflection at a node's centre per unit
    traction over a patch, against dblquad. At nu = 0.5 it is zero."""
    pitch, nu = 0.5e-3, 0.3
    x0, y0 = node

    def cerruti(yy, xx):  # the source point (xx, yy), the receiver at the node
        X, Y = x0 - xx, y0 - yy
        return (1 - 2 * nu) * (1 + nu) / (2 * np.pi * E) * X / (X * X + Y * Y)

    want, _ = integrate.dblquad(
        cerruti, -pitch / 2, pitch / 2, -pitch / 2, pitch / 2, epsabs=1e-20, epsrel=1e-9
    )
    xy = np.array([[0.0, 0.0], node])
    st = Stack((Layer(H, E, nu),), "halfspace", E, nu)
    D = shear_normal_compliance(xy, pitch, st)
    assert D[1, 0] == pytest.approx(want, rel=1e-6)
    # along y: the same field turned a quarter
    Dy = shear_normal_compliance(xy[:, ::-1], pitch, st, direction=(0.0, 1.0))
    assert Dy[1, 0] == pytest.approx(want, rel=1e-6)
    inc = Stack((Layer(H, E, 0.5),), "halfspace", E, 0.5)
    assert np.abs(shear_normal_compliance(xy, pitch, inc)).max() == 0.0


@pytest.mark.parametrize(("nu", "x"), [(0.5, H / 2 + 2e-3), (0.5, 0.5e-3), (0.45, 3e-3)])
def test_friction_on_a_layer_deflects_the_node_grid_as_the_plane_strain_strip(nu, x):
    """A traction strip (|x| < 2 mm, 80 mm long) on a 4 mm layer bonded to a rigid base,
    on 0.25 x 2 mm nodes: the deflection at a node on the strip's midline against the
    plane-strain integral of the spectral solution (which the FEM test pins)."""
    a, pitch = 2e-3, 0.25e-3
    st = Stack((Layer(H, E, nu),))
    xs = np.arange(-a + pitch / 2, a + 4e-3, pitch)
    ys = (np.arange(-20, 20) + 0.5) * 2e-3
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    xy = np.column_stack([X.ravel(), Y.ravel()])
    D = shear_normal_compliance(xy, pitch, st, pitch_y_m=2e-3)
    q = (np.abs(xy[:, 0]) < a).astype(float)
    i = int(np.argmin(np.abs(xy[:, 0] - x) + np.abs(xy[:, 1] - 1e-3)))
    want = _strip_reference(st, a, float(xy[i, 0]), load="shear")
    assert (D @ q)[i] == pytest.approx(want, rel=STRIP_GRID_RTOL)


#: friction coupled into the contact of a flat punch on a layer, the node grid (0.25 x 2 mm)
#: against scikit-fem (P2, 1/16 of the thickness, graded at the punch's edges): the share of
#: the load on the trailing half (measured 0.2 points apart) and friction's change of the
#: punch's stiffness (0.3%)
PUNCH_SHARE_ATOL = 5e-3
PUNCH_STIFFNESS_RTOL = 5e-3


def _punch_fem(h, nu, a, mu, n_per_h=16, far=10.0, delta=1e-5):
    """scikit-fem, plane strain: a rigid flat punch on |x| < a pressed ``delta`` into a layer
    of thickness h bonded to a rigid base, whose face slides along +x over the layer with
    friction mu: the tangential traction on the layer is mu p along -x. The punch's whole
    face is in contact (checked), so the problem is linear: on each contact node the normal
    displacement is set, and the tangential force is mu times the normal reaction (the same
    shape functions carry both). Returns the stiffness per unit length [Pa] and the shares
    of the load on the trailing (x < 0) and leading halves."""
    skfem = pytest.importorskip("skfem")
    from scipy.sparse.linalg import spsolve
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    L = a + far * h
    base = np.linspace(-L, L, round(2 * L / h * n_per_h) + 1)
    edges = [c + np.linspace(-h / 4, h / 4, 2 * n_per_h + 1) for c in (-a, a)]
    xs = np.unique(np.round(np.concatenate([base, *edges, [-a, a, 0.0]]), 12))
    tol = 1e-9 * h
    m = skfem.MeshTri.init_tensor(xs, np.linspace(0, h, n_per_h + 1)).with_boundaries(
        {"bottom": lambda x: x[1] < tol}
    )
    ib = skfem.Basis(m, skfem.ElementVector(skfem.ElementTriP2()))
    K_ = skfem.asm(linear_elasticity(*lame_parameters(E, nu)), ib).tocsr()
    face = ib.get_dofs(m.facets_satisfying(lambda x: (x[1] > h - tol) & (np.abs(x[0]) <= a + tol)))
    xc, yc = face.all("u^1"), face.all("u^2")
    A = K_.tolil()
    for xi, yi in zip(xc, yc, strict=True):  # the x equation: K_x u = mu (K_y u), the friction
        A[xi, :] = K_[xi, :] - mu * K_[yi, :]
    A = A.tocsr()
    u = np.zeros(K_.shape[0])
    u[yc] = -delta
    fixed = np.unique(np.concatenate([ib.get_dofs("bottom").all(), yc]))
    free = np.setdiff1d(np.arange(u.size), fixed)
    u[free] = spsolve(A[free][:, free].tocsc(), -A[free][:, fixed] @ u[fixed])
    P = -(K_ @ u)[yc]  # the face's compressive nodal forces
    assert P.min() > 0, "the punch's face must stay in contact"
    x = ib.doflocs[0, yc]
    return P.sum() / delta, P[x < 0].sum() / P.sum(), P[x > 0].sum() / P.sum()


@pytest.mark.slow
@pytest.mark.parametrize("nu", [0.49, 0.3])
def test_friction_shifts_a_punch_on_a_layer_as_plane_strain_fem(nu):
    """A flat pad 8 mm wide (80 mm long: plane strain at its middle) pressed on a 4 mm layer
    bonded to a rigid base while it slides along +x with mu 0.5. On nearly incompressible
    silicone the trailing half carries 58% of the load and the pad is 5% softer; at nu 0.3
    friction moves almost nothing. The node grid's coupled solve (C - mu D, every node in
    contact) against the FEM."""
    a, pitch, mu = 4e-3, 0.25e-3, 0.5
    st = Stack((Layer(H, E, nu),))
    xs = np.arange(-a + pitch / 2, a, pitch)
    ys = (np.arange(-20, 20) + 0.5) * 2e-3
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    xy = np.column_stack([X.ravel(), Y.ravel()])
    C = layered_compliance_matrix(xy, pitch, st, pitch_y_m=2e-3)
    D = shear_normal_compliance(xy, pitch, st, pitch_y_m=2e-3)
    middle = np.abs(xy[:, 1]) < 1.5e-3
    x = xy[middle, 0]
    ours = []
    for m in (0.0, mu):
        p, _ = ActiveSet(C - m * D, None, refresh=0).solve(np.full(len(xy), 1e-5))
        P = p[middle]
        ours.append((P.sum(), P[x < 0].sum() / P.sum()))
    k0, _, _ = _punch_fem(H, nu, a, 0.0)
    k1, trailing, leading = _punch_fem(H, nu, a, mu)
    assert ours[1][1] == pytest.approx(trailing / (trailing + leading), abs=PUNCH_SHARE_ATOL)
    assert ours[1][0] / ours[0][0] == pytest.approx(k1 / k0, rel=PUNCH_STIFFNESS_RTOL)
    if nu == 0.49:
        assert trailing > 0.55 and k1 / k0 < 0.96


#: a flat-topped ridge 8 mm wide pressed 10 um into a 4 mm layer (nu 0.49) on a bone,
#: frictionless: the stiffness per unit length against scikit-fem (P2, 1/16 of the
#: thickness), at the default node pitch over ridges (0.5 mm) and the finest auto picks
#: (0.125 mm here): measured -3.2% and -1.4% (the punch's edge singularity converges
#: slowly in both; the FEM itself moves -0.3% from 1/16 to 1/32)
RIDGE_DEFAULT_RTOL = 0.04
RIDGE_FINEST_RTOL = 0.02


@pytest.mark.slow
def test_a_flat_ridge_pressed_into_a_layered_pad_matches_fem_at_default_and_finest_pitch():
    a = 4e-3
    st = Stack((Layer(H, E, 0.49),))
    k_fem = _punch_fem(H, 0.49, a, 0.0)[0]
    err = {}
    for pitch in (0.5e-3, 0.125e-3):
        xs = np.arange(-a + pitch / 2, a, pitch)
        ys = (np.arange(-20, 20) + 0.5) * 2e-3
        X, Y = np.meshgrid(xs, ys, indexing="ij")
        xy = np.column_stack([X.ravel(), Y.ravel()])
        C = layered_compliance_matrix(xy, pitch, st, pitch_y_m=2e-3)
        p, _ = ActiveSet(C, None).solve(np.full(len(xy), 1e-5))
        middle = np.abs(xy[:, 1]) < 1.5e-3
        err[pitch] = p[middle].sum() * pitch / 2 / 1e-5 / k_fem - 1
    assert abs(err[0.5e-3]) < RIDGE_DEFAULT_RTOL
    assert abs(err[0.125e-3]) < RIDGE_FINEST_RTOL
    assert abs(err[0.125e-3]) < abs(err[0.5e-3])


def test_the_kept_stress_tables_read_as_the_exact_ones(fresh_memo):
    """Tables reaching offsets rounded up to 2 mm (kept in the process and shared by the
    rig's slides of nearby offsets) give the weights of the tables fitted to each slide's
    offsets within 1e-5 of the largest (the cubic interpolation's own error), and two
    offsets that round alike share one table."""
    from sim_tactile.scene.layered import layered_subsurface_weights
    from sim_tactile.sensors import get_sensor

    s = get_sensor("multilayer3x3x2").with_paper_stack()
    h = 0.25e-3
    X, Y = np.meshgrid(np.arange(-40, 41) * h, np.arange(-30, 31) * h)
    nodes = np.column_stack([X.ravel(), Y.ravel()])
    lay = s.layout
    for off in (0.0, 0.37e-3, -0.41e-3):
        txy = lay.positions[:, :2] - [0.0, off]
        args = (nodes, h, txy, lay.sizes, lay.depth_m, s.finger.stack)
        exact = layered_subsurface_weights(*args)
        kept = layered_subsurface_weights(*args, reach_quantum_m=2e-3)
        err = np.abs(kept - exact).max() / np.abs(exact).max()
        assert 0 < err < 1e-5, err
    assert len(fresh_memo) == 2  # one table per taxel depth, for all three offsets


def test_the_spline_on_a_grid_is_scipys_map_coordinates():
    """The kept tables are read on the nodes' tensor grid in two passes of four taps: the
    numbers of scipy's cubic spline (order 3, periodic, no prefilter) at every point to
    round-off, wrapped ends and integer coordinates included; and the nodes' tensor grid is
    found only where the nodes are one."""
    from scipy.ndimage import map_coordinates

    from sim_tactile.scene.spline_grid import spline_on_grid, tensor_grid

    rng = np.random.default_rng(4)
    coef = rng.standard_normal((97, 61))
    cx = np.concatenate([rng.uniform(-7, 104, 50), [0.0, 1.0, 96.0, 97.0, -1.0]])
    cy = np.concatenate([rng.uniform(-3, 64, 20), [0.0, 60.0, 61.0]])
    X, Y = np.meshgrid(cx, cy)
    ref = map_coordinates(coef, [X.ravel(), Y.ravel()], order=3, mode="grid-wrap", prefilter=False)
    got = spline_on_grid(coef, cx, cy)
    assert got.shape == X.shape
    assert np.max(np.abs(got.ravel() - ref)) <= 1e-13 * np.abs(ref).max()
    xs, ys = np.arange(5) * 0.3, np.arange(3) * 0.2 - 1
    nodes = np.column_stack([np.tile(xs, 3), np.repeat(ys, 5)])
    got_xs, got_ys = tensor_grid(nodes)
    assert np.array_equal(got_xs, xs) and np.array_equal(got_ys, ys)
    rx, ry = tensor_grid(nodes[::-1])  # a grid in any order of its axes is one
    assert np.array_equal(rx, xs[::-1]) and np.array_equal(ry, ys[::-1])
    assert tensor_grid(nodes[:-1]) is None  # a row short
    swapped = nodes.copy()
    swapped[[1, 2]] = swapped[[2, 1]]
    assert tensor_grid(swapped) is None
