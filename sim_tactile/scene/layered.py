"""A skin of bonded elastic layers on a backing, solved in the Fourier domain.

A sensor's skin is a stack of layers of finite thickness (silicone, fabric, a dielectric) on
a backing: a rigid bone or circuit board, or a softer half-space. A half-space model is exact
only when the contact is small against the thickness; this module gives the stack's own
response, from which the skin's compliance and the taxels' stresses follow.

Under a surface load ``p exp(i k.x)`` of one wave vector ``k`` the elastic field of a layered
body is a plane-strain field in the plane of ``k`` and the depth ``z`` (the normal load
excites no antiplane motion), so the 3D answer at wave number ``|k|`` is the 2D answer at
wave number ``|k|``. In each layer the displacement is a sum of four modes (Papkovich's
solution of Navier's equations for one wave number): two decaying from the layer's top,
``(a1 + a2 kz') exp(-kz')``, and two decaying from its bottom, written the same way from the
bottom, so that every coefficient multiplies a function bounded by one: the linear system
stays well conditioned however thick the layer is against the wavelength. The layers are
bonded (displacement and traction continuous), the top is loaded by a normal pressure and
free of shear, and the backing holds the bottom fixed (rigid) or continues as a half-space.

:func:`layer_response` returns, per wave number, the surface deflection and the vertical
stress at any depths under a unit pressure. Limits it meets, each tested: a stack of one
material on a half-space of the same is the half-space (``2 / (E* k)`` and Boussinesq's
``(1 + kz) exp(-kz)``); a thin bonded layer deflects ``p h / M`` with ``M`` the oedometric
modulus; and a plane-strain finite-element model (scikit-fem) of a strip load on a layer.
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..sensors.stack import Layer, Stack

__all__ = [
    "Layer",
    "Stack",
    "layer_response",
    "layered_compliance_matrix",
    "layered_compliance_table",
    "layered_subsurface_weights",
    "surface_remainder",
]


def _modes(
    k: np.ndarray, zeta_top: np.ndarray, zeta_bot: np.ndarray | None, mu: float, nu: float
) -> np.ndarray:
    """(nk, 4, 4): the state (U, W, S, T) at one depth of a layer from its four mode
    coefficients (a1, a2, c1, c2).

    ``zeta_top = k (z - z_top) >= 0``, ``zeta_bot = k (z - z_bottom) <= 0`` (None: a
    half-space, without the modes from below). U is the horizontal displacement along k over
    i, W the deflection into the body, S the vertical normal stress (tension positive) and T
    the shear stress over i, in Pa per unit coefficient.
    """
    kap = 3 - 4 * nu
    ed = np.exp(-zeta_top)
    s = 2 * k * mu
    M = np.zeros((k.size, 4, 4))
    # decaying from the top: (a1 + a2 zeta) exp(-zeta)
    M[:, 0, 0], M[:, 0, 1] = ed, zeta_top * ed
    M[:, 1, 0], M[:, 1, 1] = -ed, -(zeta_top + kap) * ed
    M[:, 2, 0], M[:, 2, 1] = s * ed, s * (zeta_top + 2 * (1 - nu)) * ed
    M[:, 3, 0], M[:, 3, 1] = -s * ed, -s * (zeta_top + (1 - 2 * nu)) * ed
    if zeta_bot is None:
        return M
    # decaying from the bottom: (c1 + c2 zeta) exp(zeta), zeta <= 0
    eg = np.exp(zeta_bot)
    M[:, 0, 2], M[:, 0, 3] = eg, zeta_bot * eg
    M[:, 1, 2], M[:, 1, 3] = eg, (zeta_bot - kap) * eg
    M[:, 2, 2], M[:, 2, 3] = s * eg, s * (zeta_bot - 2 * (1 - nu)) * eg
    M[:, 3, 2], M[:, 3, 3] = s * eg, s * (zeta_bot - (1 - 2 * nu)) * eg
    return M


def _shear_modulus(young: float, nu: float) -> float:
    return young / (2 * (1 + nu))


def layer_response(
    stack: Stack, k: np.ndarray, depths_m: np.ndarray | None = None, *, load: str = "normal"
) -> tuple[np.ndarray, np.ndarray]:
    """Response of ``stack`` to a unit surface load ``exp(i k x)`` at wave numbers ``k``
    [1/m] (all > 0): a normal pressure (``load="normal"``) or a shear traction along +x
    (``load="shear"``).

    Returns ``w`` (nk,): the surface deflection into the skin [m/Pa], and ``s`` (nk, nd): the
    compressive vertical stress at ``depths_m`` [Pa/Pa] (a depth at or below the backing's
    top is not allowed on a rigid backing). Under a pressure both are in phase with it (``s``
    is 1 at the surface). Under a shear traction both lag it by a quarter wave: the actual
    responses are ``i w`` and ``i s`` (``s`` is 0 at the surface; on a half-space
    ``s = -k d exp(-k d)``, Cerruti's stress, compressive ahead of the traction).
    """
    if load not in ("normal", "shear"):
        raise ConfigError(f"load = {load!r}; valid: 'normal', 'shear'")
    k = np.asarray(k, float)
    if np.any(k <= 0):
        raise ValueError("layer_response: wave numbers must be > 0")
    depths = np.zeros(0) if depths_m is None else np.asarray(depths_m, float)
    H = stack.thickness_m
    if stack.backing == "rigid" and np.any(depths >= H):
        raise ConfigError(
            f"depth {depths.max():g} m is at or below the rigid backing; valid: [0, {H:g}) m"
        )
    mats = [(_shear_modulus(la.young_pa, la.poisson), la.poisson) for la in stack.layers]
    tops = np.concatenate([[0.0], np.cumsum([la.thickness_m for la in stack.layers])])
    n_lay = len(stack.layers)
    half = stack.backing == "halfspace"
    n = 4 * n_lay + (2 if half else 0)
    nk = k.size
    A = np.zeros((nk, n, n))
    b = np.zeros((nk, n))
    # stresses are scaled by 2 k mu of the top layer: all rows of one order
    scale = 1.0 / (2 * k * mats[0][0])
    zero = np.zeros(nk)

    def state(j: int, z: float) -> np.ndarray:
        mu, nu = mats[j]
        Mj = _modes(k, k * (z - tops[j]), k * (z - tops[j + 1]), mu, nu)
        Mj[:, 2:, :] *= scale[:, None, None]
        return Mj

    # surface: S = -1, T = 0 (a unit pressure), or S = 0 and sigma_xz = -i: T = i (a unit
    # traction along +x; the field of the real system T = 1 times i)
    top = state(0, 0.0)
    A[:, 0:2, 0:4] = top[:, 2:4, :]
    if load == "normal":
        b[:, 0] = -scale
    else:
        b[:, 1] = scale
    row = 2
    for j in range(n_lay - 1):
        z = tops[j + 1]
        A[:, row : row + 4, 4 * j : 4 * j + 4] = state(j, z)
        A[:, row : row + 4, 4 * j + 4 : 4 * j + 8] = -state(j + 1, z)
        row += 4
    last = state(n_lay - 1, tops[-1])
    if not half:
        A[:, row : row + 2, 4 * (n_lay - 1) :] = last[:, 0:2, :]
    else:
        nu_b = stack.backing_poisson
        sub = _modes(k, zero, None, _shear_modulus(stack.backing_young_pa, nu_b), nu_b)
        sub[:, 2:, :] *= scale[:, None, None]
        A[:, row : row + 4, 4 * (n_lay - 1) : 4 * n_lay] = last
        A[:, row : row + 4, 4 * n_lay :] = -sub[:, :, 0:2]
    coef = np.linalg.solve(A, b[..., None])[..., 0]
    w = np.einsum("kj,kj->k", top[:, 1, :], coef[:, 0:4])
    s = np.zeros((nk, depths.size))
    for i, d in enumerate(depths):
        if d >= H:  # in the half-space backing
            mu_b = _shear_modulus(stack.backing_young_pa, stack.backing_poisson)
            Mb = _modes(k, k * (d - H), None, mu_b, stack.backing_poisson)
            s[:, i] = -np.einsum("kj,kj->k", Mb[:, 2, 0:2], coef[:, 4 * n_lay :])
            continue
        j = int(np.searchsorted(tops, d, side="right") - 1)
        Mj = _modes(k, k * (d - tops[j]), k * (d - tops[j + 1]), *mats[j])
        s[:, i] = -np.einsum("kj,kj->k", Mj[:, 2, :], coef[:, 4 * j : 4 * j + 4])
    return w, s


# --- real space: the node grid's compliance and the taxels' weights --------------------------
#
# The stack's response to a point load is the half-space's of its top layer (closed forms in
# :mod:`~sim_tactile.scene.elastic`) plus a remainder whose Fourier transform falls off
# exponentially (the top layer's half-space dominates at wavelengths short against it), so
# the remainder is smooth on the scale of the layers: it is tabulated over the distance r
# by a Hankel transform and integrated over the node patches and taxels by Gauss-Legendre.

#: Gauss points per Hankel panel, and the panel width in radians of k r at the table's end.
_HANKEL_POINTS = 8
_HANKEL_PHASE = 1.0
#: the table reaches REACH_LAYERS total thicknesses; beyond it the remainder takes its
#: asymptote (exponentially close on a rigid backing, to about (H / r)^2 on a half-space)
REACH_LAYERS = 60.0
#: table spacing: this fraction of the top layer's thickness
_TABLE_STEP = 1 / 24
#: Gauss points per patch or taxel axis: one per this fraction of the smoothing length
_POINTS_PER_LENGTH = 3.0
_POINTS_MAX = 12


class _Radial:
    """A remainder tabulated over r in [0, r_end] (cubic spline), ``tail / r`` beyond."""

    def __init__(self, r: np.ndarray, values: np.ndarray, tail: float) -> None:
        from scipy.interpolate import CubicSpline

        self.r_end, self.tail = float(r[-1]), float(tail)
        self.spline = CubicSpline(r, values)

    def __call__(self, r: np.ndarray) -> np.ndarray:
        out = np.empty_like(r)
        inside = r <= self.r_end
        out[inside] = self.spline(r[inside])
        out[~inside] = self.tail / r[~inside]
        return out


def _hankel_table(
    stack: Stack, f, r_end: float, length: float, tail: float, order: int = 0
) -> _Radial:
    """(1/2pi) int_0^inf f(k) k J_order(k r) dk on r in [0, r_end] (order 0 or 1), f
    vectorised and decaying exponentially beyond k ~ 1 / length."""
    from scipy.special import j0, j1

    bessel = j0 if order == 0 else j1

    # the last k where f still matters: 40 smoothing lengths (exp(-40) ~ 4e-18)
    k_end = 40.0 / length
    width = min(_HANKEL_PHASE / r_end, 0.2 / stack.thickness_m, k_end / 50)
    n = int(np.ceil(k_end / width))
    t, w = np.polynomial.legendre.leggauss(_HANKEL_POINTS)
    edges = np.linspace(0.0, k_end, n + 1)
    half, mid = (edges[1:] - edges[:-1]) / 2, (edges[1:] + edges[:-1]) / 2
    k = (mid[:, None] + half[:, None] * t[None, :]).ravel()
    wk = (half[:, None] * w[None, :]).ravel() * f(k) * k / (2 * np.pi)
    r = np.linspace(0.0, r_end, int(np.ceil(r_end / (length * _TABLE_STEP))) + 1)
    vals = np.empty_like(r)
    for i in range(0, r.size, 256):  # in blocks: (256 x nk) at a time
        vals[i : i + 256] = bessel(np.outer(r[i : i + 256], k)) @ wk
    return _Radial(r, vals, tail)


def _top_length(stack: Stack) -> float:
    return stack.layers[0].thickness_m


def surface_remainder(stack: Stack, r_max_m: float) -> _Radial:
    """Surface deflection [m/N] of a unit point load on ``stack`` minus that of the top
    layer's half-space, ``1 / (pi E* r)``, over r [m]."""
    e_top = stack.top_e_star_pa
    if stack.backing == "rigid":
        tail = -1 / (np.pi * e_top)
    else:
        e_b = stack.backing_young_pa / (1 - stack.backing_poisson**2)
        tail = (1 / e_b - 1 / e_top) / np.pi
    r_end = min(r_max_m, REACH_LAYERS * stack.thickness_m)

    def f(k):
        return layer_response(stack, k)[0] - 2 / (e_top * k)

    return _hankel_table(stack, f, max(r_end, 1e-6), _top_length(stack), tail)


def patch_quadrature(stack: Stack, hx: float, hy: float):
    """Gauss-Legendre offsets and weights (tx, wx, ty, wy) over a node patch of half-sides
    hx, hy, spaced for a remainder that varies over the top layer's thickness."""
    from .elastic import gauss_points

    length = _top_length(stack)
    tx, wx = gauss_points(hx, length, _POINTS_PER_LENGTH, _POINTS_MAX)
    ty, wy = gauss_points(hy, length, _POINTS_PER_LENGTH, _POINTS_MAX)
    return tx, wx, ty, wy


def lattice_indices(xy: np.ndarray, hx: float, hy: float) -> tuple[np.ndarray, np.ndarray] | None:
    """Each node's (column, row) on its lattice of patches ``2 hx`` by ``2 hy``, or None if
    the nodes do not lie on one."""
    ix = np.rint((xy[:, 0] - xy[:, 0].min()) / (2 * hx)).astype(np.int64)
    iy = np.rint((xy[:, 1] - xy[:, 1].min()) / (2 * hy)).astype(np.int64)
    on = np.allclose(xy[:, 0] - xy[:, 0].min(), ix * 2 * hx, atol=1e-9 * hx) and np.allclose(
        xy[:, 1] - xy[:, 1].min(), iy * 2 * hy, atol=1e-9 * hy
    )
    return (ix, iy) if on else None


def layered_compliance_matrix(
    xy: np.ndarray, pitch_m: float, stack: Stack, pitch_y_m: float | None = None
) -> np.ndarray:
    """(N, N) surface compliance [m/Pa] of the node patches centred at ``xy`` on ``stack``:
    the top layer's half-space (Love's closed form) plus the stack's remainder, integrated
    over each patch."""
    from .elastic import compliance_matrix

    hx, hy = pitch_m / 2, (pitch_y_m or pitch_m) / 2
    r_max = float(np.hypot(np.ptp(xy[:, 0]) + 2 * hx, np.ptp(xy[:, 1]) + 2 * hy))
    rem = surface_remainder(stack, r_max)
    tx, wx, ty, wy = patch_quadrature(stack, hx, hy)
    area = 4 * hx * hy

    def patch_mean(dx: np.ndarray, dy: np.ndarray) -> np.ndarray:
        acc = np.zeros(np.broadcast(dx, dy).shape)
        for ox, wxi in zip(tx, wx, strict=True):
            for oy, wyi in zip(ty, wy, strict=True):
                acc += wxi * wyi * rem(np.hypot(dx - ox, dy - oy))
        return acc

    C = compliance_matrix(xy, pitch_m, stack.top_e_star_pa, pitch_y_m=pitch_y_m)
    # the node grid is a lattice: the remainder depends on the offset in pitches only, and
    # (the Gauss points being symmetric) on its magnitude along each axis
    lattice = lattice_indices(xy, hx, hy)
    if lattice is not None:
        ix, iy = lattice
        gx, gy = np.meshgrid(np.arange(ix.max() + 1), np.arange(iy.max() + 1), indexing="ij")
        table = patch_mean(gx * 2 * hx, gy * 2 * hy)
        C += area * table[np.abs(ix[:, None] - ix[None, :]), np.abs(iy[:, None] - iy[None, :])]
    else:
        d = xy[:, None, :] - xy[None, :, :]
        C += area * patch_mean(d[..., 0], d[..., 1])
    return 0.5 * (C + C.T)  # symmetric by reciprocity; the quadrature is symmetric to rounding


def layered_compliance_table(
    nx: int, ny: int, pitch_m: float, stack: Stack, pitch_y_m: float | None = None
) -> np.ndarray:
    """(ny, nx) surface compliance [m/Pa] between node patches ``i`` pitches apart along x
    and ``j`` along y on ``stack``: the kernel of :func:`layered_compliance_matrix` on an
    ``nx`` by ``ny`` lattice (the matrix's entries, as a function of the offset)."""
    from .elastic import compliance_table

    hx, hy = pitch_m / 2, (pitch_y_m or pitch_m) / 2
    r_max = float(np.hypot(nx * 2 * hx, ny * 2 * hy))  # as the matrix takes it
    rem = surface_remainder(stack, r_max)
    tx, wx, ty, wy = patch_quadrature(stack, hx, hy)
    gy, gx = np.meshgrid(np.arange(ny) * 2 * hy, np.arange(nx) * 2 * hx, indexing="ij")
    table = np.zeros(gx.shape)
    for ox, wxi in zip(tx, wx, strict=True):
        for oy, wyi in zip(ty, wy, strict=True):
            table += wxi * wyi * rem(np.hypot(gx - ox, gy - oy))
    T = compliance_table(nx, ny, pitch_m, stack.top_e_star_pa, pitch_y_m)
    return T + 4 * hx * hy * table


#: the FFT grid of the taxel weights: its spacing resolves the remainder's transform out to
#: exp(-FFT_DECAY) of its peak, and it reaches FFT_MARGIN smoothing lengths beyond the
#: farthest node-taxel offset (the remainder falls off as r^-5 there)
FFT_DECAY = 36.0
FFT_MARGIN = 12.0
_FFT_MAX_SIDE = 4096


def _radial_stress(stack: Stack, depth_m: float, length: float, load: str):
    """The compressive stress transform at ``depth_m`` (:func:`layer_response`) as a function
    of |k|, tabulated on a radial grid out past exp(-FFT_DECAY) of ``length``; under a
    pressure less Boussinesq's (the remainder), under a shear traction whole."""
    k = np.r_[np.geomspace(1e-4, 1.0, 200)[:-1], np.linspace(1.0, 1.2 * FFT_DECAY, 2000)] / length
    s = layer_response(stack, k, np.array([depth_m]), load=load)[1][:, 0]
    if load == "normal":
        s = s - (1 + k * depth_m) * np.exp(-k * depth_m)

    def f(q: np.ndarray) -> np.ndarray:
        return np.interp(q, k, s, left=0.0, right=0.0)

    return f


def _stress_remainder_hat(stack: Stack, depth_m: float) -> tuple[callable, float]:
    """The transform of the stress remainder at ``depth_m`` as a function of |k|, and its
    smoothing length [m]."""
    h1 = _top_length(stack)
    length = 2 * h1 - depth_m if depth_m < h1 else depth_m
    return _radial_stress(stack, depth_m, length, "normal"), length


def _fft_taxel_weights(
    hat, length, node_xy, hx, hy, taxel_xy, tx, ty, ms, table_key=None, reach_quantum_m=None
) -> np.ndarray:
    """(len(ms), N): taxel ms's reading of a unit load spread over each node's patch, for a
    stress whose 2D transform at (kx, ky) is ``hat(KX, KY)`` and falls off as
    exp(-|k| length); one FFT over every node-taxel offset, read by cubic interpolation.

    With ``reach_quantum_m``, the table reaches the offsets rounded up to a multiple of it,
    and is kept in this process under ``table_key`` (JSON data naming the stress: what
    ``hat`` computes) with its grid: the readings of taxels whose offsets differ by less than
    the quantum (a probe's random offset across the slide) come from one table."""
    from scipy.fft import next_fast_len
    from scipy.ndimage import map_coordinates

    dx = taxel_xy[ms, None, 0] - node_xy[None, :, 0]
    dy = taxel_xy[ms, None, 1] - node_xy[None, :, 1]
    step = np.pi * length / FFT_DECAY
    reach_x = np.abs(dx).max() + FFT_MARGIN * length
    reach_y = np.abs(dy).max() + FFT_MARGIN * length
    if reach_quantum_m is not None:
        reach_x = float(np.ceil(reach_x / reach_quantum_m) * reach_quantum_m)
        reach_y = float(np.ceil(reach_y / reach_quantum_m) * reach_quantum_m)
    nx = next_fast_len(int(np.ceil(2 * reach_x / step)))
    ny = next_fast_len(int(np.ceil(2 * reach_y / step)))
    if max(nx, ny) > _FFT_MAX_SIDE:
        raise ConfigError(
            f"taxels {length * 1e3:g} mm from where their stress settles need a {nx} x {ny} grid "
            f"to read {2 * reach_x * 1e3:.3g} x {2 * reach_y * 1e3:.3g} mm of skin; valid: at "
            f"most {_FFT_MAX_SIDE} a side (deeper taxels, a thicker top layer, or a smaller pad)"
        )
    sx_, sy_ = 2 * reach_x / nx, 2 * reach_y / ny
    grid = (nx, ny, sx_, sy_, hx, hy, tx, ty)
    coords = np.array([dx.ravel() / sx_ + nx // 2, dy.ravel() / sy_ + ny // 2])
    if reach_quantum_m is None:
        F = _fft_table(hat, grid)
        return map_coordinates(F, coords, order=3, mode="grid-wrap").reshape(dx.shape)
    from ..cache import setup_memo

    parts = {"stress": table_key, "grid": [float(g) for g in grid]}
    (coef,) = setup_memo(
        "a taxel's stress table, spline coefficients",
        parts,
        lambda: (_spline(_fft_table(hat, grid)),),
        (__name__,),
    )
    from .spline_grid import spline_on_grid, tensor_grid

    tensor = tensor_grid(node_xy)
    if tensor is not None:
        xs, ys = tensor
        return np.stack(
            [
                spline_on_grid(
                    coef,
                    (taxel_xy[m, 0] - xs) / sx_ + nx // 2,
                    (taxel_xy[m, 1] - ys) / sy_ + ny // 2,
                ).ravel()
                for m in ms
            ]
        )
    return map_coordinates(coef, coords, order=3, mode="grid-wrap", prefilter=False).reshape(
        dx.shape
    )


def _fft_table(hat, grid) -> np.ndarray:
    """The reading of a unit load on a node patch at every offset of the grid ``(nx, ny,
    sx, sy, hx, hy, tx, ty)``, fftshifted: offset (x, y) at (x / sx + nx // 2, y / sy + ny //
    2)."""
    from scipy.fft import ifft2

    nx, ny, sx_, sy_, hx, hy, tx, ty = grid
    kx = 2 * np.pi * np.fft.fftfreq(nx, sx_)
    ky = 2 * np.pi * np.fft.fftfreq(ny, sy_)
    KX, KY = np.meshgrid(kx, ky, indexing="ij")
    boxes = (
        np.sinc(KX * tx / (2 * np.pi))
        * np.sinc(KY * ty / (2 * np.pi))
        * np.sinc(KX * hx / np.pi)
        * np.sinc(KY * hy / np.pi)
    )
    F = np.real(ifft2(hat(KX, KY) * boxes)) * (tx * ty) / (sx_ * sy_)
    return np.fft.fftshift(F)


def _spline(F: np.ndarray) -> np.ndarray:
    """The cubic spline coefficients :func:`scipy.ndimage.map_coordinates` would make of
    ``F`` (periodic), made once for many readings."""
    from scipy.ndimage import spline_filter

    return spline_filter(F, order=3, output=np.float64, mode="grid-wrap")


def _groups(taxel_size, depth_m):
    """Buried taxels grouped by (depth, size x, size y)."""
    groups = {}
    for m in np.flatnonzero(np.asarray(depth_m) > 0):
        groups.setdefault((float(depth_m[m]), *map(float, taxel_size[m])), []).append(m)
    return groups


def layered_subsurface_weights(
    node_xy: np.ndarray,
    pitch_m: float,
    taxel_xy: np.ndarray,
    taxel_size: np.ndarray,
    depth_m: np.ndarray,
    stack: Stack,
    pitch_y_m: float | None = None,
    reach_quantum_m: float | None = None,
) -> np.ndarray:
    """(M, N) weights W, taxel loads [N] = W @ node loads [N], on ``stack``: Boussinesq's
    weights of the top layer (:func:`~sim_tactile.scene.elastic.subsurface_weights`) plus the
    stack's remainder of the vertical stress averaged over each node's patch and integrated
    over each taxel. The remainder's transform times the taxel's and the patch's box
    transforms is brought back to real space by one FFT per taxel size and depth, and read
    at each node-taxel offset by cubic interpolation. ``reach_quantum_m``: see
    :func:`_fft_taxel_weights` (the tables are then kept in the process, by content)."""
    from .elastic import subsurface_weights

    W = subsurface_weights(node_xy, pitch_m, taxel_xy, taxel_size, depth_m, pitch_y_m=pitch_y_m)
    hx, hy = pitch_m / 2, (pitch_y_m or pitch_m) / 2
    for (d, tx, ty), ms in _groups(taxel_size, depth_m).items():
        f, length = _stress_remainder_hat(stack, d)
        key = {"stack": stack.to_json(), "depth_m": d, "length_m": length, "kind": "normal"}
        W[ms] += _fft_taxel_weights(
            lambda KX, KY, f=f: f(np.hypot(KX, KY)),
            length,
            node_xy,
            hx,
            hy,
            taxel_xy,
            tx,
            ty,
            ms,
            table_key=key,
            reach_quantum_m=reach_quantum_m,
        )
    return W
