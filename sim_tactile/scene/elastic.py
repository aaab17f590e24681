"""Closed-form linear elasticity of the skin, modelled as an elastic half-space.

- :func:`compliance_matrix`: surface deflection at node i per unit pressure on the square
  patch of node j (Love 1929; Johnson, *Contact Mechanics*, eq. 3.25). ``u = C @ p``.
- :func:`compliance_table`: the same on a lattice of nodes, as a function of the offset
  (the kernel the spectral contact solve convolves with).
- :func:`subsurface_weights`: the share of a node's load that reaches a taxel of given size
  at depth d under the surface: Boussinesq's vertical stress of the node's load, spread
  uniformly over the node's patch, integrated over the taxel's rectangle (Holl's corner
  formula over the taxel, Gauss-Legendre over the patch). At depth 0 it is the overlap of
  the node's patch with the taxel.

This is the skin's elastic coupling: a load on one patch deflects its neighbours (``C`` is
dense), and a taxel under the surface feels loads spread from around it.
"""

from __future__ import annotations

import numpy as np


def _F(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Antiderivative of 1/sqrt(X^2 + Y^2) in X and Y, up to terms in X or Y alone (which
    cancel in a four-corner difference): X asinh(Y/|X|) + Y asinh(X/|Y|)."""
    ax, ay = np.abs(X), np.abs(Y)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(ax == 0, 0.0, X * np.arcsinh(Y / np.where(ax == 0, 1.0, ax)))
        b = np.where(ay == 0, 0.0, Y * np.arcsinh(X / np.where(ay == 0, 1.0, ay)))
    return a + b


def rect_integral(x: np.ndarray, y: np.ndarray, half_x: float, half_y: float) -> np.ndarray:
    """Integral of 1/r over the rectangle [-hx, hx] x [-hy, hy] seen from (x, y) [m]."""
    return (
        _F(x + half_x, y + half_y)
        - _F(x - half_x, y + half_y)
        - _F(x + half_x, y - half_y)
        + _F(x - half_x, y - half_y)
    )


def compliance_matrix(
    xy: np.ndarray, pitch_m: float, e_star_pa: float, pitch_y_m: float | None = None
) -> np.ndarray:
    """(N, N) surface compliance [m/Pa] of rectangular patches ``pitch_m`` by ``pitch_y_m``
    (default: square) centred at ``xy`` (N, 2), for a half-space of plane-strain modulus
    ``E* = E / (1 - nu^2)``."""
    d = xy[:, None, :] - xy[None, :, :]
    hx, hy = pitch_m / 2, (pitch_y_m or pitch_m) / 2
    return rect_integral(d[..., 0], d[..., 1], hx, hy) / (np.pi * e_star_pa)


def compliance_table(
    nx: int, ny: int, pitch_m: float, e_star_pa: float, pitch_y_m: float | None = None
) -> np.ndarray:
    """(ny, nx) surface compliance [m/Pa] between node patches ``i`` pitches apart along x and
    ``j`` along y (entry ``[j, i]``), on a half-space of plane-strain modulus ``E*``: the
    kernel of :func:`compliance_matrix` on a lattice, which depends on the offset alone
    (and is even in each axis)."""
    qy = pitch_y_m or pitch_m
    X, Y = np.meshgrid(np.arange(nx) * pitch_m, np.arange(ny) * qy, indexing="xy")
    return rect_integral(X, Y, pitch_m / 2, qy / 2) / (np.pi * e_star_pa)


def _corner(X: np.ndarray, Y: np.ndarray, z: float) -> np.ndarray:
    """Vertical stress factor at depth z under the corner of a uniformly loaded X x Y
    rectangle (signed X, Y), in units of the surface pressure (Holl 1940)."""
    R = np.sqrt(X * X + Y * Y + z * z)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.arctan2(X * Y, z * R) + X * Y * z / R * (1 / (X * X + z * z) + 1 / (Y * Y + z * z))
    return np.nan_to_num(t) / (2 * np.pi)


#: Gauss-Legendre points per node-patch axis: enough that they lie at most a third of the
#: taxel's depth apart, where the integrand (the taxel's stress seen from a load point) bends
#: over a width of about the depth (a quarter moves no test by more than 1e-4); capped so a very shallow taxel under coarse nodes stays
#: cheap (then the points are ``patch / PATCH_POINTS_MAX`` apart).
PATCH_POINTS_PER_DEPTH = 3.0
PATCH_POINTS_MAX = 48


#: a patch this many patch widths (or depths) clear of a taxel is "far" and takes at most
#: FAR_POINTS Gauss points per axis
FAR_PATCHES = 2.0
FAR_POINTS = 3


def gauss_points(
    half: float, length: float, per_length: float, cap: int
) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre offsets [m] and weights (summing to 1) over [-half, half]: enough
    points that ``per_length`` of them fall in each ``length``, at most ``cap``."""
    n = int(min(cap, max(1, np.ceil(2 * half * per_length / length))))
    t, w = np.polynomial.legendre.leggauss(n)
    return t * half, w / 2


def _taxel_stress(X: np.ndarray, Y: np.ndarray, sx: float, sy: float, d: float) -> np.ndarray:
    """Vertical stress of a unit point load at (X, Y) from a taxel's centre, integrated over
    the taxel's 2 sx x 2 sy rectangle at depth d (four corners of Holl's formula)."""
    return (
        _corner(sx - X, sy - Y, d)
        + _corner(sx + X, sy + Y, d)
        + _corner(sx - X, sy + Y, d)
        + _corner(sx + X, sy - Y, d)
    )


def subsurface_weights(
    node_xy: np.ndarray,
    pitch_m: float,
    taxel_xy: np.ndarray,
    taxel_size: np.ndarray,
    depth_m: np.ndarray,
    pitch_y_m: float | None = None,
) -> np.ndarray:
    """(M, N) weights W so that taxel loads [N] = W @ node loads [N].

    Taxel m is a rectangle of size ``taxel_size[m]`` (sx, sy) centred at ``taxel_xy[m]`` at
    depth ``depth_m[m]`` >= 0 under the surface; its reading is the vertical stress integrated
    over its area. A node's load is a uniform pressure over its patch (``pitch_m`` by
    ``pitch_y_m``), as the skin solves it: at depth 0 the weight is the patch's overlap with
    the taxel, below it Boussinesq's stress of that pressure integrated over the taxel, the
    patch by Gauss-Legendre quadrature. A uniform pressure then reads pressure x area at any
    depth; point loads at the node centres would not when the patch is wide against the depth.
    """
    M, N = len(taxel_xy), len(node_xy)
    W = np.zeros((M, N))
    hx, hy = pitch_m / 2, (pitch_y_m or pitch_m) / 2
    for m in range(M):
        sx, sy = taxel_size[m] / 2
        d = float(depth_m[m])
        X = node_xy[:, 0] - taxel_xy[m, 0]
        Y = node_xy[:, 1] - taxel_xy[m, 1]
        if d <= 0:
            ox = np.clip(np.minimum(X + hx, sx) - np.maximum(X - hx, -sx), 0, None)
            oy = np.clip(np.minimum(Y + hy, sy) - np.maximum(Y - hy, -sy), 0, None)
            W[m] = ox * oy / (4 * hx * hy)
            continue
        # only nodes whose patch lies within reach: beyond 30 depths of the taxel the stress
        # has fallen below 1e-9 of the load
        reach = 30 * d
        near = (np.abs(X) <= sx + hx + reach) & (np.abs(Y) <= sy + hy + reach)
        # patches farther than FAR_PATCHES patch widths from the taxel see a smooth stress:
        # at most FAR_POINTS Gauss points per axis integrate it to well under 1e-4
        far = (np.abs(X) > sx + hx + FAR_PATCHES * 2 * max(hx, hy, d)) | (
            np.abs(Y) > sy + hy + FAR_PATCHES * 2 * max(hx, hy, d)
        )
        for sel, cap in ((near & ~far, None), (near & far, FAR_POINTS)):
            W[m, sel] = _patch_average(X[sel], Y[sel], hx, hy, sx, sy, d, cap)
    return W


def _patch_average(X, Y, hx, hy, sx, sy, d, cap) -> np.ndarray:
    """Mean over each node's patch (centres X, Y from the taxel) of the taxel's stress."""
    cap = min(cap or PATCH_POINTS_MAX, PATCH_POINTS_MAX)
    tx, wx = gauss_points(hx, d, PATCH_POINTS_PER_DEPTH, cap)
    ty, wy = gauss_points(hy, d, PATCH_POINTS_PER_DEPTH, cap)
    acc = np.zeros(X.size)
    for ox, wxi in zip(tx, wx, strict=True):
        acc += wxi * (
            wy[None, :] * _taxel_stress((X + ox)[:, None], Y[:, None] + ty[None, :], sx, sy, d)
        ).sum(axis=1)
    return acc
