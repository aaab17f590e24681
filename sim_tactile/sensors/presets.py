"""The preset sensors: files of the project's ``assets/sensors`` (installed as
``sim_tactile.assets``)."""

from __future__ import annotations

from pathlib import Path

from ..toml_text import asset_data, asset_path

#: The preset sensors, in this order.
PRESETS = ("grid3x3", "multilayer3x3x2", "biotac19", "icub60", "pvdf2")


def preset_file(name: str) -> Path:
    """The file that defines the preset sensor ``name``."""
    return asset_path("sensors", f"{name}.toml")


def preset_data(name: str) -> dict:
    """A preset's file as data, read once a process; each sensor is built anew from it."""
    return asset_data("sensors", f"{name}.toml")
