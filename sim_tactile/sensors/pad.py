"""A sensor's pad: the finger's rigid bone carrying a soft skin, in physical units.

The pad's undeformed surface is ``z = surface(x, y) >= 0`` above its lowest point, in the pad
frame (x along the slide, y across, z out of the skin, i.e. up from the plate). Shapes:

- ``flat``: a flat ``size_m`` rectangle whose edges roll off with radius ``edge_radius_m``
  (a fillet, so a feature entering the pad meets a slope, not a step);
- ``sphere``: a spherical cap of radius ``radius_m``;
- ``ellipsoid``: an ellipsoidal cap of semi-axes ``radii_m`` (x, y, z).

The skin is an elastic half-space of Young's modulus ``young_pa`` and Poisson ratio
``poisson`` (0.5: incompressible silicone), ``thickness_m`` thick over the bone: pressing
deeper than that bottoms out and stops the run. With a ``stack``
(:class:`~sim_tactile.sensors.stack.Stack`) the skin is that stack of bonded layers on its
backing instead (:meth:`Finger.layered` sets the top layer's modulus and the stack's
thickness to match).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import Literal

import numpy as np

from .. import _validate as v
from ..errors import ConfigError
from .stack import Stack

PadShape = Literal["flat", "sphere", "ellipsoid"]
PAD_SHAPES = ("flat", "sphere", "ellipsoid")


@dataclass(frozen=True)
class Finger:
    """A soft finger. Lengths in m, modulus in Pa, mass in kg."""

    shape: PadShape = "flat"
    size_m: tuple[float, float] = (0.012, 0.012)
    edge_radius_m: float = 0.002
    radius_m: float = 0.008
    radii_m: tuple[float, float, float] = (0.010, 0.008, 0.006)
    thickness_m: float = 0.004
    young_pa: float = 0.3e6
    poisson: float = 0.5
    bone_mass_kg: float = 0.1
    friction: float = 0.8
    #: the skin's layers on their backing; None: a half-space of ``young_pa``, ``poisson``
    stack: Stack | None = None
    #: the skin carries the sliding friction as tractions ``q = friction * p`` against the
    #: slide, and buried taxels read their stress (Cerruti's on a half-space); False: the
    #: skin is frictionless and the friction acts only as the bone's drag
    skin_tractions: bool = False

    def __post_init__(self) -> None:
        v.one_of("finger.shape", self.shape, PAD_SHAPES)
        if len(self.size_m) != 2:
            raise ConfigError(f"finger.size_m must be (x, y), got {self.size_m!r}")
        for i, s in enumerate(self.size_m):
            v.in_range(f"finger.size_m[{i}]", s, 1e-3, 0.1, unit="m")
        v.in_range("finger.edge_radius_m", self.edge_radius_m, 0.0, 0.02, unit="m")
        v.in_range("finger.radius_m", self.radius_m, 1e-3, 0.1, unit="m")
        for i, r in enumerate(self.radii_m):
            v.in_range(f"finger.radii_m[{i}]", r, 1e-3, 0.1, unit="m")
        v.in_range("finger.thickness_m", self.thickness_m, 10e-6, 0.05, unit="m")
        v.in_range("finger.young_pa", self.young_pa, 1e3, 1e9, unit="Pa")
        v.in_range("finger.poisson", self.poisson, 0.0, 0.5, unit="")
        v.in_range("finger.bone_mass_kg", self.bone_mass_kg, 1e-3, 10.0, unit="kg")
        v.in_range("finger.friction", self.friction, 0.0, 3.0, unit="")
        if self.stack is not None:
            top = self.stack.layers[0]
            if (
                abs(self.stack.thickness_m - self.thickness_m) > 1e-12
                or top.young_pa != self.young_pa
                or top.poisson != self.poisson
            ):
                raise ConfigError(
                    f"finger.stack (thickness {self.stack.thickness_m:g} m, top layer E "
                    f"{top.young_pa:g} Pa, nu {top.poisson:g}) disagrees with finger.thickness_m "
                    f"= {self.thickness_m:g} m, young_pa = {self.young_pa:g} Pa, poisson = "
                    f"{self.poisson:g}; valid: equal (Finger.layered sets them)"
                )
        if self.shape == "sphere" and max(self.size_m) > 2 * self.radius_m:
            raise ConfigError(
                f"finger.size_m = {self.size_m} is wider than the sphere (radius_m = "
                f"{self.radius_m:g} m); valid: size_m <= 2 * radius_m"
            )

    def layered(self, stack: Stack) -> Finger:
        """This finger with ``stack`` as its skin: the thickness and the (top layer's)
        modulus and Poisson ratio follow the stack."""
        top = stack.layers[0]
        return replace(
            self,
            stack=stack,
            thickness_m=stack.thickness_m,
            young_pa=top.young_pa,
            poisson=top.poisson,
        )

    @property
    def e_star_pa(self) -> float:
        """Plane-strain modulus E / (1 - nu^2) [Pa] (of the top layer, with a stack)."""
        return self.young_pa / (1.0 - self.poisson**2)

    @property
    def patch_m(self) -> tuple[float, float]:
        """Extent of the skin nodes (x, y) [m]: the flat pad plus its edge roll-off."""
        if self.shape == "flat":
            return (
                self.size_m[0] + 2 * self.edge_radius_m,
                self.size_m[1] + 2 * self.edge_radius_m,
            )
        return self.size_m

    def surface(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Undeformed skin height above the pad's lowest point [m] at pad coordinates."""
        x, y = np.asarray(x, float), np.asarray(y, float)
        if self.shape == "flat":
            hx, hy = self.size_m[0] / 2, self.size_m[1] / 2
            r = self.edge_radius_m
            ex = np.clip(np.abs(x) - hx, 0, None)
            ey = np.clip(np.abs(y) - hy, 0, None)
            e = np.minimum(np.hypot(ex, ey), r)
            return (
                r - np.sqrt(np.maximum(r * r - e * e, 0.0))
                if r > 0
                else np.zeros(np.broadcast(x, y).shape)
            )
        if self.shape == "sphere":
            R = self.radius_m
            return R - np.sqrt(np.maximum(R * R - x * x - y * y, 0.0))
        rx, ry, rz = self.radii_m
        return rz * (1 - np.sqrt(np.maximum(1 - (x / rx) ** 2 - (y / ry) ** 2, 0.0)))

    def to_json(self) -> dict:
        d = asdict(self)
        if self.stack is None:
            del d["stack"]  # a half-space skin keeps the definition (and hashes) it had
        else:
            d["stack"] = self.stack.to_json()
        if not self.skin_tractions:
            del d["skin_tractions"]  # likewise a frictionless skin
        return d
