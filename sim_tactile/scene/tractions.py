"""Sliding friction on a layered skin: the tractions' normal deflection and their stress.

A skin that carries its sliding friction has tangential tractions ``q = mu p`` on its
surface, against the slide. On a stack (:mod:`~sim_tactile.scene.layered`; a half-space is a
stack of one material on a half-space of the same) they

- deflect the surface normally (:func:`shear_normal_compliance`), which couples them into
  the normal contact problem unless the skin is an incompressible half-space;
- stress the taxels under the surface (:func:`shear_subsurface_weights`): on a half-space
  Cerruti's stress, compressive ahead of the traction.

Both come from the stack's response to a shear traction per wave number
(:func:`~sim_tactile.scene.layered.layer_response` with ``load="shear"``), brought to the
node grid as the normal load's are.
"""

from __future__ import annotations

import numpy as np

from ..sensors.stack import Layer, Stack
from .layered import (
    REACH_LAYERS,
    _fft_taxel_weights,
    _groups,
    _hankel_table,
    _radial_stress,
    _top_length,
    lattice_indices,
    layer_response,
    patch_quadrature,
)

__all__ = ["shear_normal_compliance", "shear_subsurface_weights"]


# --- the normal deflection of tangential tractions (friction on the skin) ------------------
#
# A tangential force Q along a unit vector d deflects the surface normally by
# ``cos(theta) g(r)``, theta the angle between d and the offset: odd about the force. Its
# transform is ``i (d.k / |k|) w_s(|k|)`` (w_s: :func:`layer_response` under a shear
# traction), so ``g(r) = -(1/2pi) int w_s(k) k J1(k r) dk``. On a half-space ``w_s = c / k``,
# ``c = -(1 - 2 nu)(1 + nu) / E``, and ``g = -c / (2 pi r)`` (Cerruti's normal displacement):
# the surface sinks ahead of the force and rises behind it, by reciprocity with the inward
# pull of a normal load; an incompressible half-space does not move. A stack's ``g`` is that
# of its top layer's half-space, integrated over the patch in closed form, plus a smooth
# remainder tabulated by a Hankel transform of order one.


def _cerruti_coefficient(layer: Layer) -> float:
    """``c`` of the layer's material as a half-space: k times its normal deflection under a
    unit shear traction of wave number k [m/Pa * 1/m]."""
    return -(1 - 2 * layer.poisson) * (1 + layer.poisson) / layer.young_pa


def _odd_rect(x: np.ndarray, y: np.ndarray, hx: float, hy: float) -> np.ndarray:
    """Integral of u / (u^2 + v^2) over the source rectangle [-hx, hx] x [-hy, hy], u and v
    the offsets of the point (x, y) from the source point."""

    def G(u, v):  # d2G / du dv = u / (u^2 + v^2), up to terms in u or v alone
        r2 = u * u + v * v
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.where(r2 > 0, 0.5 * v * np.log(np.where(r2 > 0, r2, 1.0)), 0.0)
            b = np.where(u != 0, u * np.arctan(v / np.where(u != 0, u, 1.0)), 0.0)
        return a + b

    return G(x + hx, y + hy) - G(x - hx, y + hy) - G(x + hx, y - hy) + G(x - hx, y - hy)


def shear_normal_compliance(
    xy: np.ndarray,
    pitch_m: float,
    stack: Stack,
    pitch_y_m: float | None = None,
    direction: tuple[float, float] = (1.0, 0.0),
) -> np.ndarray:
    """(N, N) D [m/Pa]: the surface deflection into the skin at node i per unit tangential
    traction along ``direction`` (a unit vector in the pad's plane) over node j's patch, on
    ``stack``. Zero for an incompressible half-space; on a layer it is not (the layer's base
    holds it), so friction shifts the contact pressure: ``u = C p + D q``."""
    cx, cy = direction
    hx, hy = pitch_m / 2, (pitch_y_m or pitch_m) / 2
    top = stack.layers[0]
    c = _cerruti_coefficient(top)
    uniform = (
        stack.backing == "halfspace"
        and len(stack.layers) == 1
        and stack.backing_young_pa == top.young_pa
        and stack.backing_poisson == top.poisson
    )
    rem = None  # the stack's remainder over the half-space of its top layer
    if not uniform:
        if stack.backing == "rigid":
            a = -c  # w_s - c / k -> -c / k at long wavelengths: the base holds the surface
        else:
            nu_b = stack.backing_poisson
            a = -(1 - 2 * nu_b) * (1 + nu_b) / stack.backing_young_pa - c
        r_max = float(np.hypot(np.ptp(xy[:, 0]) + 2 * hx, np.ptp(xy[:, 1]) + 2 * hy))
        r_end = max(min(r_max, REACH_LAYERS * stack.thickness_m), 1e-6)

        def f(k):
            return layer_response(stack, k, load="shear")[0] - c / k

        # h(r) = (1/2pi) int f k J1(k r) dk, the remainder's g = -h; f ~ a / k: h ~ a / (2 pi r)
        rem = _hankel_table(stack, f, r_end, _top_length(stack), a / (2 * np.pi), order=1)
    tx, wx, ty, wy = patch_quadrature(stack, hx, hy)
    area = 4 * hx * hy

    def kernel(dx: np.ndarray, dy: np.ndarray) -> np.ndarray:
        """D at receiver-minus-source offsets (dx, dy)."""
        out = np.zeros(np.broadcast(dx, dy).shape)
        if c != 0.0:  # the top layer's half-space, in closed form (zero if incompressible)
            if cx:
                out += (-c / (2 * np.pi)) * cx * _odd_rect(dx, dy, hx, hy)
            if cy:
                out += (-c / (2 * np.pi)) * cy * _odd_rect(dy, dx, hy, hx)
        if rem is None:
            return out
        for ox, wxi in zip(tx, wx, strict=True):
            for oy, wyi in zip(ty, wy, strict=True):
                ux, uy = dx - ox, dy - oy
                r = np.hypot(ux, uy)
                along = np.divide(cx * ux + cy * uy, r, out=np.zeros_like(r), where=r > 0)
                out -= area * wxi * wyi * along * rem(r)
        return out

    lattice = lattice_indices(xy, hx, hy)
    if lattice is not None:
        ix, iy = lattice  # D depends on the signed offset in pitches only: one table, gathered
        nx, ny = int(ix.max()), int(iy.max())
        gx, gy = np.meshgrid(np.arange(-nx, nx + 1), np.arange(-ny, ny + 1), indexing="ij")
        table = kernel(gx * 2 * hx, gy * 2 * hy)
        return table[ix[:, None] - ix[None, :] + nx, iy[:, None] - iy[None, :] + ny]
    d = xy[:, None, :] - xy[None, :, :]
    return kernel(d[..., 0], d[..., 1])


def shear_subsurface_weights(
    node_xy: np.ndarray,
    pitch_m: float,
    taxel_xy: np.ndarray,
    taxel_size: np.ndarray,
    depth_m: np.ndarray,
    stack: Stack,
    pitch_y_m: float | None = None,
    direction: tuple[float, float] = (1.0, 0.0),
) -> np.ndarray:
    """(M, N) weights Wq: the compressive vertical stress each taxel integrates when each
    node carries a unit tangential force along ``direction`` (a unit vector in the pad's
    plane; default +x), spread over its patch, on ``stack`` (a half-space is a stack of one
    material on a half-space of the same). On a half-space it is Cerruti's: compressive
    ahead of the force, tensile behind, zero at the surface."""
    cx, cy = direction
    Wq = np.zeros((len(taxel_xy), len(node_xy)))
    hx, hy = pitch_m / 2, (pitch_y_m or pitch_m) / 2
    for (d, tx, ty), ms in _groups(taxel_size, depth_m).items():
        f = _radial_stress(stack, d, d, "shear")

        def hat(KX, KY, f=f):
            K = np.hypot(KX, KY)
            along = np.divide(cx * KX + cy * KY, K, out=np.zeros_like(K), where=K > 0)
            return 1j * along * f(K)

        Wq[ms] = _fft_taxel_weights(hat, d, node_xy, hx, hy, taxel_xy, tx, ty, ms)
    return Wq
