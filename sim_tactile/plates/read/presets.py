"""The preset plates, by their released names (``sim-tactile plates list``): each a plate
file of the project's ``assets/plates`` (:mod:`~sim_tactile.plates.read.files`; installed as ``sim_tactile.assets``),
in the order of its ``index.toml``. Every dimension a paper leaves open was chosen as this
module says, once, and is listed in the manual's plate table; the files hold the numbers.

Choices where the papers are silent (all plates: base 108 x 36 x 5 mm, textured area
36 x 36 mm centred; the base length gives 36 mm of flat run-in and run-out on each side):

- ``finger7/*`` (soft-finger paper, seed 002): "2.5 mm raised ridges and bumps" is read as
  features 2.5 mm high and 2.5 mm wide (square bumps of 2.5 x 2.5 mm), spread evenly over
  the 36 mm: ridge pitch 18 / 9 / 4.5 mm, bump pitch 12 / 9 / 6 mm.
- ``multilayer3/*`` (multilayer paper, seed 003): "9 ridges spaced by 2 mm with a 30 degree
  draft": ridges 2 mm wide at the base with 2 mm gaps (4 mm period, 9 x 4 = 36 mm), 1 mm
  high, sides drafted 30 degrees from vertical (top 0.85 mm wide). Hemispheres of 4 mm
  diameter, 2 mm edge to edge (6 mm pitch), 2 mm high.
- ``roughness8/ra-*`` (roughness paper, seed 001; standards made by cylindrical turning):
  the profile varies along the slide with its lay along y. Correlation length from the
  turning relation Ra = f^2 / (32 r) with a 0.8 mm tool nose radius r: the feed f =
  sqrt(32 r Ra), correlation length f / 2 (0.57 mm at Ra 50 um, 0.05 mm at Ra 0.4 um).
- ``textures20/*`` (our set for the first paper's protocol): gratings over periods 1.5-6 mm
  and heights 0.25-1 mm, drafted and narrow variants, boxes, cylinders and hemispheres at
  three pitches, and two random roughnesses. Hard pairs on purpose: grating periods 2.0 vs
  2.5 mm, boxes vs cylinders at 3 mm pitch, grating duty 0.5 vs 0.25.
- ``textures20-long/*``: the same 20 textures on a long plate (base 196 x 36 x 5 mm,
  textured area 156 x 36 mm), for slides that stay on the texture the whole window, as seed
  000's BioTac slid 20 cm over each material strip. The area is the short one plus 120 mm,
  a whole even number of every grating period and bump pitch, so each long plate is its
  short plate extended: the same features at the same places over the short plate's area
  (tested); the grids of bumps keep their rows and take the most columns of the same parity
  that fit. The roughness fields are new draws of the same statistics.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..._names import did_you_mean
from ...errors import UnknownNameError
from ...toml_text import asset_data, asset_path
from ..define.spec import Plate
from .files import plate_from_data

MM = 1e-3

#: Tool nose radius for the turned roughness standards [m] (a common finishing insert).
TURNING_NOSE_RADIUS_M = 0.8 * MM
#: Ra values of the roughness paper's eight nickel standards [um], roughest first.
ROUGHNESS8_RA_UM = (50, 25, 12.5, 6.3, 3.2, 1.6, 0.8, 0.4)
#: The long plates' family, textured area and base length [m] (see the module docstring).
LONG_FAMILY = "textures20-long/"
LONG_AREA_M = 0.156
LONG_PLATE_M = 0.196


def turned_corr_length_m(ra_m: float) -> float:
    """Correlation length of a turned profile of roughness ``ra_m``: half the feed."""
    return 0.5 * math.sqrt(32 * TURNING_NOSE_RADIUS_M * ra_m)


def assets_dir() -> Path:
    """The folder of the preset plates' files."""
    return asset_path("plates")


def preset_file(name: str) -> Path:
    """The file of the preset plate ``name`` (``family/plate`` -> ``family/plate.toml``)."""
    return assets_dir() / f"{name}.toml"


def preset_names() -> list[str]:
    """All preset names, in a fixed order."""
    return list(asset_data("plates", "index.toml")["names"])


def is_plate_file(ref: str | Path) -> bool:
    """Whether ``ref`` names a file (a plate file, ``.toml``, or a user's CAD, script or
    height map, :mod:`.user`) rather than a preset."""
    from ..parts.user import is_user_plate

    return str(ref).lower().endswith(".toml") or is_user_plate(ref)


def get_plate(name: str | Path) -> Plate:
    """The preset plate called ``name`` (e.g. ``"finger7/ridges-4"``), the plate of a plate
    file (a path ending in ``.toml``, :mod:`~sim_tactile.plates.read.files`), or of a user's STEP, STL, CadQuery
    script or height map (a reference of :mod:`.user`, e.g. ``"knurl.py:make"``)."""
    if str(name).lower().endswith(".toml"):
        from .files import load_plate_file

        return load_plate_file(name)
    from ..parts.user import is_user_plate, load_user_plate

    if is_user_plate(name):
        return load_user_plate(str(name))
    names = asset_data("plates", "index.toml")["names"]
    if name not in names:
        fams = sorted({n.split("/")[0] for n in names})
        raise UnknownNameError(
            f"plate {name!r} is not a preset{did_you_mean(name, names)}; valid: one of the "
            f"{len(names)} names of "
            f"`sim-tactile plates list` (families {', '.join(fams)}), a plate file (.toml), or "
            "a part (.step, .stp, .stl, a CadQuery script .py[:function]) or height map "
            "(.npy, .png)"
        )
    data = asset_data("plates", f"{name}.toml")
    return plate_from_data(data, name, where=f"preset plate file {preset_file(name)}")
