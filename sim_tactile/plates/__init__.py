"""Parametric textured plates: what a plate is, plate files and presets, a user's own parts,
and the artefacts made of a plate (CAD, MuJoCo geometry, previews).

Four folders, each answering one question, each importing only those below it
(``pyproject.toml``'s plates contract):

- :mod:`.make`: a plate's artefacts, cached: STL and STEP, MJCF, the preview, their checks;
- :mod:`.read`: plates read from plate files, and the presets;
- :mod:`.parts`: a user's STEP, STL or CadQuery part, or height-map file, as a plate;
- :mod:`.define`: what a plate is, and its surface (:class:`Surface`, the one place that
  tells the kinds of texture apart).

Importing this package never imports cadquery; only a cache miss on an STL or STEP does.
The modules' old names (``sim_tactile.plates.spec`` and the rest) still import for one
release, with a DeprecationWarning (:mod:`._moved`).
"""

from __future__ import annotations

from . import _moved
from .define.geometry import Feature
from .define.spec import Bumps, Flat, Grating, HeightMap, Plate, Ridges, Roughness
from .define.surface import Surface, surface_of
from .features import features, height_at, roughness_profile  # noqa: F401  (deprecated)
from .make.build import KINDS, BuildResult, build, load_heightmap
from .parts.user import load_user_plate
from .read.presets import get_plate, is_plate_file, preset_names

_moved.register(__name__)

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
    "Surface",
    "build",
    "get_plate",
    "is_plate_file",
    "load_heightmap",
    "load_user_plate",
    "preset_names",
    "surface_of",
]


def __getattr__(name: str):
    return _moved.old_name(__name__, name)
