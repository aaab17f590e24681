"""Parametric textured plates: definitions, presets, CAD, MuJoCo geometry and previews.

Importing this package never imports cadquery; only a cache miss on an STL or STEP does.
"""

from __future__ import annotations

from .build import KINDS, BuildResult, build, load_heightmap
from .features import features, height_at, roughness_profile
from .geometry import Feature
from .presets import get_plate, is_plate_file, preset_names
from .spec import Bumps, Flat, Grating, HeightMap, Plate, Ridges, Roughness
from .surface import Surface, surface_of
from .user import load_user_plate

__all__ = [
    "KINDS",
    "BuildResult",
    "Bumps",
    "Feature",
    "Flat",
    "Grating",
    "HeightMap",
    "Plate",
    "Ridges",
    "Roughness",
    "build",
    "features",
    "get_plate",
    "is_plate_file",
    "load_user_plate",
    "height_at",
    "load_heightmap",
    "preset_names",
    "roughness_profile",
    "Surface",
    "surface_of",
]
