"""The preset sensors: files of the project's ``assets/sensors`` (installed as
``sim_tactile.assets``)."""

from __future__ import annotations

from functools import cache
from pathlib import Path

#: The preset sensors, in this order.
PRESETS = ("grid3x3", "multilayer3x3x2", "biotac19", "icub60", "pvdf2")


def preset_file(name: str) -> Path:
    """The file that defines the preset sensor ``name``."""
    from importlib.resources import files

    return Path(str(files("sim_tactile.assets").joinpath("sensors", f"{name}.toml")))


@cache
def preset_data(name: str) -> dict:
    """A preset's file as data, read once a process (the package's own files); each sensor
    is built anew from it."""
    import tomllib

    return tomllib.loads(preset_file(name).read_text(encoding="utf-8"))
