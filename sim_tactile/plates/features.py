"""A plate's surface: its raised features and its analytic height.

This is the plate's *definition*: the CAD solid, the MuJoCo collision geometry and the
preview are all generated from :func:`features` (and :func:`roughness_profile`), and the
tests check that each of them agrees with :func:`height_at`. Each answer is its
:func:`~.surface.surface_of`'s, kept per plate in the process.
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from .geometry import Feature
from .spec import Plate
from .surface import map_height, surface_of

__all__ = ["features", "height_at", "map_height", "roughness_profile"]


def features(plate: Plate) -> list[Feature]:
    """The plate's raised features, in a fixed order (x-major). Raises ConfigError if they
    overlap or leave the textured area. Roughness plates have none (see
    :func:`roughness_profile`)."""
    return list(surface_of(plate).features)


def roughness_profile(plate: Plate) -> tuple[np.ndarray, np.ndarray]:
    """The sampled roughness profile ``(x, z)`` [m], shape (n,) each, read-only.

    Deterministic: the same parameters give the same bytes in any process (numpy's PCG64
    and pocketfft are deterministic on one platform).
    """
    profile = surface_of(plate).profile
    if profile is None:
        raise ConfigError(f"plate {plate.name or plate.hash} has no roughness texture")
    return profile


def height_at(plate: Plate, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray:
    """Analytic top-surface height z(x, y) [m] of the plate; broadcasts ``x`` and ``y``.

    Outside the plate's footprint the result is NaN. The base top is z = 0.
    """
    return surface_of(plate).height(x, y)
