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

from dataclasses import dataclass
from typing import Literal

import numpy as np

from .. import _validate as v
from ..errors import ConfigError

Backing = Literal["rigid", "halfspace"]
BACKINGS = ("rigid", "halfspace")


@dataclass(frozen=True)
class Layer:
    """One bonded layer: thickness [m], Young's modulus [Pa], Poisson's ratio (0.5:
    incompressible)."""

    thickness_m: float
    young_pa: float
    poisson: float = 0.5

    def __post_init__(self) -> None:
        v.in_range("layer.thickness_m", self.thickness_m, 1e-6, 1.0, unit="m")
        v.in_range("layer.young_pa", self.young_pa, 1e3, 1e12, unit="Pa")
        v.in_range("layer.poisson", self.poisson, 0.0, 0.5, unit="")


@dataclass(frozen=True)
class Stack:
    """Layers from the surface down, on a backing: ``rigid`` (bonded to an undeformable base)
    or ``halfspace`` (of ``backing_young_pa`` and ``backing_poisson``)."""

    layers: tuple[Layer, ...]
    backing: Backing = "rigid"
    backing_young_pa: float | None = None
    backing_poisson: float = 0.5

    def __post_init__(self) -> None:
        if not self.layers:
            raise ConfigError("stack.layers is empty; valid: at least one layer")
        v.one_of("stack.backing", self.backing, BACKINGS)
        if self.backing == "halfspace":
            if self.backing_young_pa is None:
                raise ConfigError(
                    "stack.backing_young_pa is None with backing 'halfspace'; valid: a modulus "
                    "in [1e3, 1e12] Pa"
                )
            v.in_range("stack.backing_young_pa", self.backing_young_pa, 1e3, 1e12, unit="Pa")
            v.in_range("stack.backing_poisson", self.backing_poisson, 0.0, 0.5, unit="")

    @property
    def thickness_m(self) -> float:
        return float(sum(layer.thickness_m for layer in self.layers))

    @property
    def top_e_star_pa(self) -> float:
        """Plane-strain modulus of the top layer: the stack's response at short wavelengths."""
        top = self.layers[0]
        return top.young_pa / (1 - top.poisson**2)

    def to_json(self) -> dict:
        return {
            "layers": [
                {"thickness_m": la.thickness_m, "young_pa": la.young_pa, "poisson": la.poisson}
                for la in self.layers
            ],
            "backing": self.backing,
            "backing_young_pa": self.backing_young_pa,
            "backing_poisson": self.backing_poisson,
        }


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
    stack: Stack, k: np.ndarray, depths_m: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Response of ``stack`` to a unit normal pressure ``exp(i k x)`` at wave numbers ``k``
    [1/m] (all > 0).

    Returns ``w`` (nk,): the surface deflection into the skin [m/Pa], and ``s`` (nk, nd): the
    compressive vertical stress at ``depths_m`` [Pa/Pa] (1 at the surface; a depth at or
    below the backing's top is not allowed on a rigid backing).
    """
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

    # surface: S = -1 (a unit pressure), T = 0
    top = state(0, 0.0)
    A[:, 0:2, 0:4] = top[:, 2:4, :]
    b[:, 0] = -scale
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
