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

from dataclasses import asdict, dataclass, replace

import numpy as np

from ..errors import ConfigError, UnknownNameError
from .layouts import Layout, dense_layout, get_layout, grid_layout
from .pad import Finger
from .transducers import (
    Capacitive,
    Impedance,
    Imperfections,
    Piezoelectric,
    PiezoResistive,
    Transducer,
)


@dataclass(frozen=True)
class Sensor:
    """A tactile sensor: its taxels (``layout``, with the hardware's rate), the pad that
    carries them (``finger``), the transducer from load to output (one per layer, or None
    for a bare layout that reports the ideal normal load [N]) and its imperfections."""

    name: str
    layout: Layout
    finger: Finger
    transducer: Transducer | tuple[Transducer, ...] | None
    imperfections: Imperfections | None = None

    @classmethod
    def bare(cls, layout: Layout, finger: Finger | None = None) -> Sensor:
        """Taxels without hardware: the ideal normal loads [N] on a default pad."""
        return cls(layout.name, layout, finger or Finger(), None, None)

    @property
    def rate_hz(self) -> float:
        return self.layout.rate_hz

    def with_paper_stack(self) -> Sensor:
        """This preset with the skin its paper describes (layers on their backing, from
        :mod:`~sim_tactile.sensors.paper_stacks`, most numbers assumptions) instead of the
        half-space."""
        from .paper_stacks import paper_stack

        return replace(self, finger=self.finger.layered(paper_stack(self.name).stack()))

    @property
    def grid_shape(self) -> tuple[int, int] | None:
        return self.layout.grid_shape

    def transduce(
        self, loads_n: np.ndarray, rate_hz: float, rng: np.random.Generator
    ) -> np.ndarray:
        """(T, N) ideal loads [N] -> (T, N) hardware output, with seeded imperfections."""
        layout = self.layout
        tr = self.transducer
        if tr is None:
            return loads_n
        if isinstance(tr, tuple):  # one transducer per layer
            out = np.empty(loads_n.shape)
            for lay, t in enumerate(tr):
                cols = layout.layer == lay
                out[:, cols] = t.apply(loads_n[:, cols], rate_hz)
        else:
            out = tr.apply(loads_n, rate_hz)
        if self.imperfections is None:
            return out
        return self.imperfections.apply(out, layout.positions, rate_hz, rng)

    @property
    def units(self) -> str:
        tr = self.transducer
        if tr is None:
            return "N"
        return (tr[0] if isinstance(tr, tuple) else tr).units

    def transducer_json(self) -> dict | str:
        """The transducer and imperfections as JSON data ("ideal" for a bare layout)."""
        tr = self.transducer
        if tr is None:
            return "ideal"
        trs = [
            asdict(t) | {"kind": type(t).__name__} for t in (tr if isinstance(tr, tuple) else (tr,))
        ]
        imp = self.imperfections.to_json() if self.imperfections is not None else None
        return {"name": self.name, "transducer": trs, "imperfections": imp}

    def to_json(self) -> dict:
        """The whole definition as JSON data: everything a recording of it depends on."""
        return {
            "name": self.name,
            "layout": self.layout.to_json(),
            "pad": self.finger.to_json(),
            "transducer": self.transducer_json(),
        }


_SENSORS = {
    "grid3x3": lambda: Sensor(
        "grid3x3",
        get_layout("grid3x3"),
        Finger(),
        PiezoResistive(),
        Imperfections(
            noise_std=5e-3,
            quant_step=5.0 / 1024,
            drift_std_per_sqrt_s=1e-3,
            crosstalk=0.02,
            crosstalk_radius_m=2.6e-3,
        ),
    ),
    "multilayer3x3x2": lambda: Sensor(
        "multilayer3x3x2",
        get_layout("multilayer3x3x2"),
        Finger(shape="flat", size_m=(0.016, 0.016), edge_radius_m=0.002),
        (
            PiezoResistive(r_fix_ohm=100.0, r0_ohm=2e3, f_c_n=0.05),
            PiezoResistive(r_fix_ohm=100.0, r0_ohm=2e3, f_c_n=0.2),
        ),
        Imperfections(
            noise_std=5e-3,
            quant_step=5.0 / 1024,
            drift_std_per_sqrt_s=1e-3,
            crosstalk=0.02,
            crosstalk_radius_m=5.1e-3,
        ),
    ),
    "biotac19": lambda: Sensor(
        "biotac19",
        get_layout("biotac19"),
        Finger(
            shape="ellipsoid",
            radii_m=(0.014, 0.010, 0.008),
            size_m=(0.022, 0.016),
            thickness_m=0.004,
        ),
        Impedance(),
        Imperfections(
            noise_std=0.9, quant_step=1.0, drift_std_per_sqrt_s=0.3, offset_max=4.0, clip_min=0.0
        ),
    ),
    "icub60": lambda: Sensor(
        "icub60",
        get_layout("icub60"),
        Finger(shape="flat", size_m=(0.032, 0.022), edge_radius_m=0.002),
        Capacitive(),
        Imperfections(noise_std=1.4, drift_std_per_sqrt_s=0.3, clip_min=0.0),
    ),
    "pvdf2": lambda: Sensor(
        "pvdf2",
        get_layout("pvdf2"),
        Finger(shape="sphere", radius_m=0.010, size_m=(0.014, 0.014)),
        Piezoelectric(),
        Imperfections(noise_std=2e-3, quant_step=20.0 / 65536),
    ),
}


def sensor_names() -> list[str]:
    return list(_SENSORS)


def get_sensor(name: str) -> Sensor:
    try:
        return _SENSORS[name]()
    except KeyError:
        raise UnknownNameError(
            f"sensor {name!r} is not known; valid: {', '.join(_SENSORS)}"
        ) from None


def check_pad(layout: Layout, finger: Finger) -> None:
    """Raise a ConfigError unless ``finger``'s pad carries every taxel of ``layout``."""
    ex, ey = layout.extent_m
    px, py = finger.patch_m
    if ex > px / 2 + 1e-9 or ey > py / 2 + 1e-9:
        raise ConfigError(
            f"the {layout.name} layout spans +-({ex:g}, {ey:g}) m, beyond the pad's "
            f"+-({px / 2:g}, {py / 2:g}) m: the pad is smaller than the {layout.name} layout; "
            "valid: a pad that carries the taxels"
        )


def resolve_sensor(sensor: Sensor | Layout | str) -> Sensor:
    """A :class:`Sensor` from a sensor, a sensor name, a bare layout or a layout name
    (``dense-<pitch>mm``): the last two report the ideal normal loads on a default pad."""
    if isinstance(sensor, Sensor):
        return sensor
    if isinstance(sensor, Layout):
        return Sensor.bare(sensor)
    if sensor in _SENSORS:
        return get_sensor(sensor)
    try:
        return Sensor.bare(get_layout(sensor))
    except UnknownNameError:
        raise UnknownNameError(
            f"sensor {sensor!r} is not known; valid: {', '.join(_SENSORS)}, or a layout "
            "dense-<pitch>mm (e.g. dense-0.25mm)"
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
    "resolve_sensor",
    "sensor_names",
]
