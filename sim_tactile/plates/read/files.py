"""Plates as parameter files: a plate's parameters in TOML, read as data (no code runs).

::

    format = 1                   # optional; this reader reads format 1
    name = "my/grating-2mm"      # optional: the file's name without .toml
    length_m = 0.108             # the base [m]: length along the slide, width, thickness
    width_m = 0.036
    thickness_m = 0.005
    area_length_m = 0.036        # the textured area, centred on the base
    area_width_m = 0.036

    [texture]                    # kind: flat, ridges, grating, bumps, roughness; then the
    kind = "grating"             # kind's parameters (sim_tactile.plates.spec)
    period_m = 0.002
    height_m = 0.0005

The preset plates are such files (the project's ``assets/plates``, installed as
``sim_tactile.assets``): copy one, edit it and pass its path where a preset's name goes.
Every value is checked (:class:`~.spec.Plate`); an error names the file and the key.
"""

from __future__ import annotations

from pathlib import Path

from ...errors import ConfigError
from ...toml_text import read_file, write_file
from ..define.spec import Plate

FORMAT = 1


def load_plate_file(path: str | Path) -> Plate:
    """The :class:`~.spec.Plate` of a plate parameter file, every value checked."""
    data = read_file(path, "plate file")
    return plate_from_data(data, Path(path).stem, f"plate file {str(path)!r}")


def plate_from_data(data: dict, default_name: str, where: str = "plate") -> Plate:
    """A plate from a plate file's data (see the module)."""
    d = dict(data)
    fmt = d.pop("format", FORMAT)
    if fmt != FORMAT:
        raise ConfigError(f"{where}: format = {fmt!r} is not valid; valid: {FORMAT}")
    name = d.pop("name", default_name)
    d.pop("description", None)
    if not isinstance(name, str) or not name:
        raise ConfigError(f"{where}: name must be a non-empty string, got {name!r}")
    try:
        return Plate.from_params(d, name=name)
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def plate_to_data(plate: Plate) -> dict:
    """A plate as a plate file's data (:func:`plate_from_data` reads it back equal)."""
    d = {"format": FORMAT}
    if plate.name:
        d["name"] = plate.name
    d.update(plate.params())
    return d


def write_plate_file(plate: Plate, path: str | Path, header: str = "") -> Path:
    """Write ``plate`` as a plate file (to a temporary name first)."""
    return write_file(plate_to_data(plate), path, "plate file", header)
