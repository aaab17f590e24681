"""The papers' sensors: taxel layout and rate, the pad it sits on, its transducer and
imperfections. A :class:`Sensor` is the whole definition; everything else reads it from there.

| sensor | layout | pad | transducer | rate |
|---|---|---|---|---|
| ``grid3x3`` | 3x3, 2 mm at 2.5 mm (seed 002) | flat 12 mm, 2 mm roll-off | piezoresistive, 10 kOhm divider, 10-bit ADC | 100 Hz |
| ``multilayer3x3x2`` | 2 x 3x3, 3 mm at 5 mm, 0.5 / 2 mm deep (seed 003) | flat 16 mm | piezoresistive, 100 Ohm divider; top layer 4x more sensitive | 100 Hz |
| ``biotac19`` | 19 electrodes, 2.5 mm deep (seed 000) | ellipsoid fingertip | impedance, counts | 100 Hz |
| ``icub60`` | 6 triangles x 10 taxels (seed 000) | flat patch 32 x 22 mm | capacitive, 8-bit counts | 50 Hz |
| ``pvdf2`` | 2 films, across and along the slide (seed 001) | spherical fingertip R 10 mm | piezoelectric, charge amplifier | 1 kHz |

Each pad's skin is an elastic half-space (E 0.3 MPa, incompressible). The stacks of layers
the papers describe, on their backings, are in :mod:`~sim_tactile.sensors.paper_stacks`
(``Sensor.with_paper_stack()``), with the source of every number.
"""

from __future__ import annotations

from pathlib import Path

from .._names import did_you_mean
from ..errors import UnknownNameError
from .layouts import Layout, dense_layout, get_layout, grid_layout
from .pad import Finger
from .presets import PRESETS, preset_data, preset_file
from .sensor import Sensor, check_pad
from .transducers import (
    Capacitive,
    Impedance,
    Imperfections,
    Piezoelectric,
    PiezoResistive,
)


def sensor_names() -> list[str]:
    """The names of the preset sensors (:func:`get_sensor` takes them)."""
    return list(PRESETS)


def get_sensor(name: str) -> Sensor:
    """The preset sensor ``name``, read from its file (:func:`preset_file`)."""
    if name not in PRESETS:
        raise UnknownNameError(
            f"sensor {name!r} is not known{did_you_mean(name, PRESETS)}; valid: "
            f"{', '.join(PRESETS)}"
        )
    from .files import sensor_from_data

    return sensor_from_data(preset_data(name), where=f"preset sensor file {preset_file(name)}")


def resolve_sensor(sensor: Sensor | Layout | str) -> Sensor:
    """A :class:`Sensor` from a sensor, a sensor name, a sensor file (``.toml``,
    :mod:`~sim_tactile.sensors.files`), a bare layout or a layout name (``dense-<pitch>mm``):
    the last two report the ideal normal loads on a default pad."""
    if isinstance(sensor, Sensor):
        return sensor
    if isinstance(sensor, Layout):
        return Sensor.bare(sensor)
    if sensor in PRESETS:
        return get_sensor(sensor)
    if isinstance(sensor, str | Path) and str(sensor).lower().endswith(".toml"):
        from .files import load_sensor_file

        return load_sensor_file(sensor)
    try:
        return Sensor.bare(get_layout(sensor))
    except UnknownNameError:
        raise UnknownNameError(
            f"sensor {sensor!r} is not known{did_you_mean(sensor, PRESETS)}; valid: "
            f"{', '.join(PRESETS)}, a sensor file "
            "(.toml), or a layout dense-<pitch>mm (e.g. dense-0.25mm)"
        ) from None


__all__ = [
    "Capacitive",
    "Finger",
    "Imperfections",
    "Impedance",
    "Layout",
    "Piezoelectric",
    "PiezoResistive",
    "Sensor",
    "check_pad",
    "dense_layout",
    "get_layout",
    "get_sensor",
    "grid_layout",
    "preset_file",
    "resolve_sensor",
    "sensor_names",
]
