"""A sensor model fitted to real recordings of that sensor: the calibration file.

``sim-tactile calibrate SENSOR --data PATH --out FILE.toml`` fits, per channel, what real
recordings and the simulation share (:mod:`sim_tactile.calibrate`): each channel's change per
newton of normal force, its rest level (offset), its noise floor and drift on quiet
stretches, and the ADC step. This module holds the result, writes and reads it as TOML (read as data with
:mod:`tomllib`: no code runs, every value is checked and named in its error), and applies it
to a sensor (:func:`calibrated`): the transducer takes one gain per channel, and the
imperfections take the fitted noise, drift, offset and step.

The gain that the simulation needs is per newton of the *taxel's* load; the data give it per
newton of the *whole* normal force. The two meet through ``force_share``: the taxel's load
per newton of normal force when the simulated sensor presses a flat plate with the data's
typical force, so ``gain = counts_per_n / force_share``. A channel that carries no load in
that press (share below :data:`MIN_SHARE`) takes the median gain of the others, and the file
says which.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

from .. import _validate as v
from ..errors import ConfigError
from ..toml_text import value as toml_value

#: The file format's version (a reader refuses others).
FORMAT = 1
#: Calibrations that ship with the package, fitted on public data sets: ``--sensor-config
#: NAME`` takes one by its sensor's name.
SHIPPED = Path(__file__).with_name("calibrations")


def calibration_names() -> list[str]:
    """The shipped calibrations (each named by its sensor)."""
    return sorted(p.stem for p in SHIPPED.glob("*.toml"))


#: Smallest simulated load share for which a channel's gain is fitted rather than borrowed.
MIN_SHARE = 1e-3

_LISTS = ("counts_per_n", "offset", "noise_std", "drift_per_s", "r2", "force_share", "gain")


@dataclass(frozen=True)
class Calibration:
    """What a calibration fitted, per channel (lists in channel order), and what the
    simulated sensor takes from it.

    - ``counts_per_n``: change of the channel per newton of normal force (data units / N);
    - ``offset``: the channel's level at rest, at zero force (data units), found on the
      recordings' quiet stretches;
    - ``noise_std``: standard deviation of its noise on quiet stretches (data units) as the
      ADC records it where not clipped, quantisation included; ``noise_model``: the white
      noise to add before the simulated ADC step, sqrt(noise_std^2 - step^2 / 12) (the
      fit's Gaussian noise: :mod:`sim_tactile.calibrate.rest`);
    - ``drift_per_s``: the drift as a random walk, its rate: the standard deviation of its
      change over one second (units; the simulation's ``drift_std_per_sqrt_s``), fitted to
      the slopes of the quiet stretches beyond what the noise gives them;
    - ``quant_step``: the ADC step (0: not quantised); ``crosstalk``: None where the data
      cannot separate it from the channels' common response (the reason in ``notes``);
    - ``r2``: the share of each channel's variance that the force explains;
    - ``force_share`` and ``gain``: see the module's docstring;
    - ``readout_period``, ``readout_phase`` and ``readout_leak``: a multiplexed readout, where
      each channel delivers its signal on one sample in ``readout_period`` at its own phase
      (relative to the others) and ``readout_leak`` of it in between (period 1: none).
    """

    sensor: str
    channels: tuple[str, ...]
    n_recordings: int
    force_n: float
    counts_per_n: tuple[float, ...]
    offset: tuple[float, ...]
    noise_std: tuple[float, ...]
    drift_per_s: tuple[float, ...]
    r2: tuple[float, ...]
    force_share: tuple[float, ...]
    gain: tuple[float, ...]
    quant_step: float = 0.0
    stretch_s: float = 1.0
    crosstalk: float | None = None
    source: str = ""
    notes: tuple[str, ...] = field(default=())
    readout_period: int = 1
    readout_phase: tuple[int, ...] = ()
    readout_leak: float = 0.0

    def __post_init__(self) -> None:
        n = len(self.channels)
        if n == 0:
            raise ConfigError("calibration.channels is empty; give one name per channel")
        v.integer("calibration.n_recordings", self.n_recordings, 1, None)
        v.in_range("calibration.force_n", self.force_n, 1e-4, 100.0, unit="N")
        for name in _LISTS:
            vals = getattr(self, name)
            if len(vals) != n:
                raise ConfigError(
                    f"calibration.{name} has {len(vals)} values; valid: one per channel ({n})"
                )
            for k, x in enumerate(vals):
                v.finite(f"calibration.{name}[{k}]", x)
        for name in ("noise_std", "drift_per_s", "force_share"):
            for k, x in enumerate(getattr(self, name)):
                v.non_negative(f"calibration.{name}[{k}]", x)
        for k, x in enumerate(self.gain):
            v.positive(f"calibration.gain[{k}]", x)
        v.non_negative("calibration.quant_step", self.quant_step)
        v.positive("calibration.stretch_s", self.stretch_s, unit="s")
        if self.crosstalk is not None:
            v.in_range("calibration.crosstalk", self.crosstalk, 0.0, 0.5)
        v.integer("calibration.readout_period", self.readout_period, 1, 64)
        if self.readout_phase and len(self.readout_phase) != n:
            raise ConfigError(
                f"calibration.readout_phase has {len(self.readout_phase)} values; valid: none, "
                f"or one per channel ({n})"
            )
        for k, ph in enumerate(self.readout_phase):
            v.integer(f"calibration.readout_phase[{k}]", ph, 0, self.readout_period - 1)
        v.in_range("calibration.readout_leak", self.readout_leak, 0.0, 1.0)

    @property
    def noise_model(self) -> tuple[float, ...]:
        q2 = self.quant_step**2 / 12
        return tuple(math.sqrt(max(s * s - q2, 0.0)) for s in self.noise_std)

    @property
    def drift_model(self) -> tuple[float, ...]:
        return tuple(self.drift_per_s)

    def to_json(self) -> dict:
        d = {k: getattr(self, k) for k in self.__dataclass_fields__}
        return {k: (list(x) if isinstance(x, tuple) else x) for k, x in d.items()}

    # ---------------------------------------------------------------- the file
    def to_toml(self) -> str:
        """The calibration as TOML text (what :func:`load_calibration` reads)."""
        lines = [
            "# sim_tactile sensor calibration: fitted by `sim-tactile calibrate`",
            f"format = {FORMAT}",
        ]
        for k, x in self.to_json().items():
            if x is None or (k.startswith("readout_") and self.readout_period == 1):
                continue
            lines.append(f"{k} = {toml_value(x)}")
        return "\n".join(lines) + "\n"

    def write(self, path: Path | str) -> Path:
        """Write the file (to a temporary name first, so a failed write loses nothing)."""
        path = Path(path)
        if path.suffix != ".toml":
            raise ConfigError(f"calibration file {str(path)!r}: valid: a name ending in .toml")
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(self.to_toml(), encoding="utf-8")
        tmp.replace(path)
        return path


def load_calibration(path: Path | str) -> Calibration:
    """Read a calibration file as data (TOML), check every value, and name what is wrong.
    ``path`` may also name a shipped calibration (:func:`calibration_names`)."""
    if str(path) in calibration_names():
        path = SHIPPED / f"{path}.toml"
    path = Path(path)
    if not path.is_file():
        raise ConfigError(
            f"sensor config {str(path)!r} does not exist; valid: a .toml file or a shipped "
            f"calibration {calibration_names()}"
        )
    try:
        d = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"sensor config {str(path)!r} is not valid TOML: {exc}") from None
    fmt = d.pop("format", None)
    if fmt != FORMAT:
        raise ConfigError(f"sensor config {str(path)!r}: format = {fmt!r}; valid: {FORMAT}")
    d.pop("noise_model", None)
    d.pop("drift_model", None)
    known = set(Calibration.__dataclass_fields__)
    v.known_keys(f"sensor config {str(path)!r}", d, sorted(known))
    missing = sorted(
        k for k, f in Calibration.__dataclass_fields__.items() if k not in d and _required(f)
    )
    if missing:
        raise ConfigError(f"sensor config {str(path)!r}: missing key(s) {missing}")
    for k in (*_LISTS, "channels", "notes", "readout_phase"):
        if k in d:
            if not isinstance(d[k], list):
                raise ConfigError(f"sensor config {str(path)!r}: {k} must be a list, got {d[k]!r}")
            d[k] = tuple(d[k])
    for k in ("sensor", "source"):
        if k in d and not isinstance(d[k], str):
            raise ConfigError(f"sensor config {str(path)!r}: {k} must be a string, got {d[k]!r}")
    return Calibration(**d)


def _required(f) -> bool:
    from dataclasses import MISSING

    return f.default is MISSING and f.default_factory is MISSING


def calibrated(sensor, cal: Calibration):
    """``sensor`` with the calibration's per-channel gains, offsets, noise, drift and step.
    The sensor must be the one calibrated (same name and channel count) and have a
    transducer with a per-channel gain (impedance or capacitive)."""
    from .transducers import Capacitive, Impedance, Imperfections

    if cal.sensor != sensor.name:
        raise ConfigError(
            f"the calibration is of sensor {cal.sensor!r}; it cannot calibrate {sensor.name!r}"
        )
    if len(cal.channels) != sensor.layout.n:
        raise ConfigError(
            f"the calibration has {len(cal.channels)} channels; sensor {sensor.name!r} has "
            f"{sensor.layout.n}"
        )
    tr = sensor.transducer
    if not isinstance(tr, Impedance | Capacitive):
        raise ConfigError(
            f"sensor {sensor.name!r} has a {type(tr).__name__} transducer; calibration "
            "fits impedance and capacitive transducers (a gain per newton)"
        )
    imp = sensor.imperfections or Imperfections()
    return replace(
        sensor,
        transducer=replace(tr, gain_counts_per_n=tuple(float(g) for g in cal.gain)),
        imperfections=replace(
            imp,
            noise_std=cal.noise_model,
            drift_std_per_sqrt_s=cal.drift_model,
            offset=tuple(float(o) for o in cal.offset),
            offset_max=0.0,
            quant_step=cal.quant_step,
            readout_period=cal.readout_period,
            readout_phase=tuple(int(p) for p in cal.readout_phase),
            readout_leak=cal.readout_leak,
        ),
    )
