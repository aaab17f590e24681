"""Deprecated: the plate's surface is asked of its :class:`~.define.surface.Surface`
(:func:`~.define.surface.surface_of`), the one surface API; these three functions go in the
next release (CHANGELOG, "Breaking").

- ``features(plate)``: ``surface_of(plate).features`` (a tuple);
- ``height_at(plate, x, y)``: ``surface_of(plate).height(x, y)``;
- ``roughness_profile(plate)``: ``surface_of(plate).profile`` (None on a plate that has no
  roughness, where this function raised ConfigError).
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import ConfigError
from .define.geometry import Feature
from .define.spec import Plate
from .define.surface import map_height, surface_of

__all__ = ["features", "height_at", "map_height", "roughness_profile"]


def _deprecated(old: str, new: str) -> None:
    warnings.warn(
        f"sim_tactile.plates.{old} is deprecated: use {new} (it goes in the next release)",
        DeprecationWarning,
        stacklevel=3,
    )


def features(plate: Plate) -> list[Feature]:
    """Deprecated: ``list(surface_of(plate).features)``, the raised features (x-major)."""
    _deprecated("features(plate)", "surface_of(plate).features")
    return list(surface_of(plate).features)


def roughness_profile(plate: Plate) -> tuple[np.ndarray, np.ndarray]:
    """Deprecated: ``surface_of(plate).profile``, the roughness profile ``(x, z)`` [m]."""
    _deprecated("roughness_profile(plate)", "surface_of(plate).profile")
    profile = surface_of(plate).profile
    if profile is None:
        raise ConfigError(f"plate {plate.name or plate.hash} has no roughness texture")
    return profile


def height_at(plate: Plate, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray:
    """Deprecated: ``surface_of(plate).height(x, y)``, the top surface's height [m]."""
    _deprecated("height_at(plate, x, y)", "surface_of(plate).height(x, y)")
    return surface_of(plate).height(x, y)
