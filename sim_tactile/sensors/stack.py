"""A skin's layers: the stack of bonded elastic layers between the contact surface and the
backing that carries it (a rigid bone or circuit board, or a softer half-space).

The elasticity of a stack is solved in :mod:`sim_tactile.scene.layered`; this module is its
definition, as data on a sensor's pad.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

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
        v.in_range("layer.thickness_m", self.thickness_m, 10e-6, 1.0, unit="m")
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

    @classmethod
    def half_space(cls, thickness_m: float, young_pa: float, poisson: float) -> Stack:
        """An elastic half-space as a stack: a layer on a half-space of its own material."""
        return cls((Layer(thickness_m, young_pa, poisson),), "halfspace", young_pa, poisson)

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

    @classmethod
    def from_json(cls, d: dict) -> Stack:
        """The stack of :meth:`to_json` (or of a user's file: keys as there)."""
        layers = tuple(Layer(**layer) for layer in d["layers"])
        rest = {k: d[k] for k in ("backing", "backing_young_pa", "backing_poisson") if k in d}
        return cls(layers, **rest)
