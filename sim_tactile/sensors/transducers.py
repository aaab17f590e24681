"""Transducers: from the ideal normal load on each taxel [N] to what the hardware reports,
with seeded imperfections. All act on sampled arrays (T, N) at the sensor's rate.

| transducer | hardware (seed paper) | output |
|---|---|---|
| :class:`PiezoResistive` | fabric arrays (002, 003): R(F) = R0 / (1 + F / F_c) in a divider with R_fix | volts, ADC-quantised |
| :class:`Capacitive` | iCub RoboSkin (000): foam dielectric, saturating | counts 0-255, baseline-compensated |
| :class:`Impedance` | BioTac electrodes (000): fluid thinning under load | counts, baseline-subtracted |
| :class:`Piezoelectric` | PVDF films (001): charge amplifier, first-order high-pass | volts, averages to zero |

:class:`Imperfections` adds, in this order and from one seeded generator: crosstalk (a share
of each neighbour's signal), a multiplexed readout (a channel's signal on one sample in P),
dead taxels (read a constant), drift (a random walk), noise (white Gaussian), quantisation. Defaults are chosen so that simulated BioTac and iCub streams
match the real data in order of magnitude, noise and rate (tested).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .. import _validate as v

#: A parameter given once for every channel, or per channel (a tuple, in channel order).
PerChannel = float | tuple[float, ...]


def per_channel(name: str, value, check) -> None:
    """Validate a :data:`PerChannel` value with ``check(name, x)`` on each entry."""
    if isinstance(value, tuple):
        if not value:
            raise v.ConfigError(f"{name} = () is empty; give one value or one per channel")
        for k, x in enumerate(value):
            check(f"{name}[{k}]", x)
    else:
        check(name, value)


def _arr(value) -> np.ndarray | float:
    return np.asarray(value, dtype=float) if isinstance(value, tuple) else value


@dataclass(frozen=True)
class PiezoResistive:
    """Voltage across R_fix of a divider R_fix + R(F), R(F) = R0 / (1 + F / F_c)."""

    vcc_v: float = 5.0
    r_fix_ohm: float = 10e3
    r0_ohm: float = 200e3
    f_c_n: float = 0.05
    units: str = "V"

    def __post_init__(self) -> None:
        for k in ("vcc_v", "r_fix_ohm", "r0_ohm", "f_c_n"):
            v.positive(f"piezoresistive.{k}", getattr(self, k))

    def apply(self, load_n: np.ndarray, rate_hz: float) -> np.ndarray:
        r = self.r0_ohm / (1.0 + np.maximum(load_n, 0.0) / self.f_c_n)
        return self.vcc_v * self.r_fix_ohm / (self.r_fix_ohm + r)


@dataclass(frozen=True)
class Capacitive:
    """Baseline-compensated counts: gain * F / (1 + F / F_sat), clipped to [0, full scale].
    ``gain_counts_per_n``: one gain, or one per channel (a calibration's)."""

    gain_counts_per_n: PerChannel = 300.0
    f_sat_n: float = 0.5
    full_scale: float = 255.0
    units: str = "counts"

    def __post_init__(self) -> None:
        per_channel("capacitive.gain_counts_per_n", self.gain_counts_per_n, v.positive)
        for k in ("f_sat_n", "full_scale"):
            v.positive(f"capacitive.{k}", getattr(self, k))

    def apply(self, load_n: np.ndarray, rate_hz: float) -> np.ndarray:
        f = np.maximum(load_n, 0.0)
        gain = _arr(self.gain_counts_per_n)
        return np.minimum(gain * f / (1.0 + f / self.f_sat_n), self.full_scale)


@dataclass(frozen=True)
class Impedance:
    """Baseline-subtracted electrode counts, linear in the load over the electrode.
    ``gain_counts_per_n``: one gain, or one per channel (a calibration's)."""

    gain_counts_per_n: PerChannel = 250.0
    full_scale: float = 4095.0
    units: str = "counts"

    def __post_init__(self) -> None:
        per_channel("impedance.gain_counts_per_n", self.gain_counts_per_n, v.positive)
        v.positive("impedance.full_scale", self.full_scale)

    def apply(self, load_n: np.ndarray, rate_hz: float) -> np.ndarray:
        gain = _arr(self.gain_counts_per_n)
        return np.minimum(gain * np.maximum(load_n, 0.0), self.full_scale)


@dataclass(frozen=True)
class Piezoelectric:
    """Charge amplifier: sensitivity * (load high-passed at cutoff_hz, first order). It
    responds to the rate of stress, so a steady load reads zero."""

    sensitivity_v_per_n: float = 10.0
    cutoff_hz: float = 2.0
    units: str = "V"

    def __post_init__(self) -> None:
        v.positive("piezoelectric.sensitivity_v_per_n", self.sensitivity_v_per_n)
        v.positive("piezoelectric.cutoff_hz", self.cutoff_hz)

    def apply(self, load_n: np.ndarray, rate_hz: float) -> np.ndarray:
        rc = 1.0 / (2 * np.pi * self.cutoff_hz)
        a = rc / (rc + 1.0 / rate_hz)
        x = np.asarray(load_n, float)
        # y[n] = a (y[n-1] + x[n] - x[n-1]), started at rest on the first sample
        return self.sensitivity_v_per_n * high_pass(x - x[:1], a)


#: Samples up to which :func:`high_pass` runs its own loop; longer recordings go to
#: ``scipy.signal.lfilter``, whose import (0.6 s: scipy.stats and scipy.interpolate come
#: with it) is then small beside the recording
HIGH_PASS_LOOP_MAX = 20_000
#: Channels up to which :func:`high_pass` runs each channel in Python's floats (a row of
#: more in numpy's operations)
HIGH_PASS_BY_CHANNEL_MAX = 16


def high_pass(x: np.ndarray, a: float) -> np.ndarray:
    """The first-order high-pass ``y[n] = a (y[n-1] + x[n] - x[n-1])`` along axis 0 of ``x``,
    from rest: ``scipy.signal.lfilter([a, -a], [1, -a], x, axis=0)`` bit for bit (its
    transposed direct form, ``y = z + a x; z = -a x + a y``, in the same order of operations),
    without loading scipy.signal for the short recordings of a data set's slides."""
    if len(x) > HIGH_PASS_LOOP_MAX:
        from scipy.signal import lfilter

        return lfilter([a, -a], [1.0, -a], x, axis=0)
    if x.dtype != np.float64 or math.prod(x.shape[1:]) > HIGH_PASS_BY_CHANNEL_MAX:
        y = np.empty_like(x)
        z = np.zeros(x.shape[1:])
        for n in range(len(x)):
            y[n] = z + a * x[n]
            z = x[n] * -a - y[n] * -a
        return y
    # a few channels: each in Python's floats (the same IEEE operations, in the same order),
    # without numpy's cost per call on a row of two (0.5 ms of a pvdf2 slide)
    cols = x.reshape(len(x), math.prod(x.shape[1:])).T.tolist()
    out = []
    for col in cols:
        z, ys = 0.0, []
        for xn in col:
            yn = z + a * xn
            z = xn * -a - yn * -a
            ys.append(yn)
        out.append(ys)
    return np.array(out, dtype=np.float64).T.reshape(x.shape)


Transducer = PiezoResistive | Capacitive | Impedance | Piezoelectric


@dataclass(frozen=True)
class Imperfections:
    """Seeded imperfections, in output units. ``noise_std`` white Gaussian; ``quant_step``
    ADC step (0: none); ``drift_std_per_sqrt_s`` random-walk drift; ``dead_fraction`` share
    of taxels stuck at ``dead_value``; ``crosstalk`` share of each neighbour's signal (within
    ``crosstalk_radius_m``) added to a taxel; ``offset_max`` per-taxel baseline in [0, max);
    ``offset`` a fixed baseline. ``noise_std``, ``drift_std_per_sqrt_s`` and ``offset`` take
    one value or one per channel (a calibration's).

    A multiplexed readout (``readout_period`` P > 1): channel k delivers its signal on one
    sample in P, at phase ``(shift + readout_phase[k]) % P``, and ``readout_leak`` of it on
    the others; ``shift`` is drawn once per slide (where the window starts in the readout
    cycle is arbitrary). Noise, drift and the clip act on every sample, as in the iCub's
    compiled clips (see ``docs/real_data.md``). P = 1 (the default) draws nothing and leaves the
    signal as it is.

    The baselines and the dead taxels belong to the sensor, not to a slide: they are drawn
    from ``unit_seed`` (which physical unit) and are the same in every recording of that unit;
    noise and drift are drawn anew for every slide from the slide's generator."""

    noise_std: PerChannel = 0.0
    quant_step: float = 0.0
    drift_std_per_sqrt_s: PerChannel = 0.0
    dead_fraction: float = 0.0
    dead_value: float = 0.0
    crosstalk: float = 0.0
    crosstalk_radius_m: float = 3e-3
    offset_max: float = 0.0
    clip_min: float | None = None
    unit_seed: int = 0
    offset: PerChannel = 0.0
    readout_period: int = 1
    readout_phase: tuple[int, ...] = ()
    readout_leak: float = 0.0

    def __post_init__(self) -> None:
        v.integer("readout_period", self.readout_period, 1, 64)
        for k, ph in enumerate(self.readout_phase):
            v.integer(f"readout_phase[{k}]", ph, 0, self.readout_period - 1)
        v.in_range("readout_leak", self.readout_leak, 0.0, 1.0)
        per_channel("noise_std", self.noise_std, v.non_negative)
        v.non_negative("quant_step", self.quant_step)
        per_channel("drift_std_per_sqrt_s", self.drift_std_per_sqrt_s, v.non_negative)
        per_channel("offset", self.offset, v.finite)
        v.in_range("dead_fraction", self.dead_fraction, 0.0, 1.0)
        v.in_range("crosstalk", self.crosstalk, 0.0, 0.5)
        v.non_negative("crosstalk_radius_m", self.crosstalk_radius_m, unit="m")
        v.non_negative("offset_max", self.offset_max)
        v.integer("unit_seed", self.unit_seed, 0, None)

    def apply(
        self, y: np.ndarray, positions: np.ndarray, rate_hz: float, rng: np.random.Generator
    ) -> np.ndarray:
        T, N = y.shape
        for name in ("noise_std", "drift_std_per_sqrt_s", "offset"):
            val = getattr(self, name)
            if isinstance(val, tuple) and len(val) != N:
                raise v.ConfigError(
                    f"imperfections.{name} has {len(val)} values; valid: one, or one per channel ({N})"
                )
        y = np.array(y, dtype=float)
        if self.crosstalk > 0 and N > 1:
            d = np.linalg.norm(positions[:, None, :] - positions[None, :, :], axis=-1)
            M = np.eye(N) + self.crosstalk * ((d > 0) & (d <= self.crosstalk_radius_m))
            y = y @ M.T
        if self.readout_period > 1:
            y *= self.readout_gate(T, N, rng)
        unit = np.random.default_rng([self.unit_seed, N])  # this sensor unit's own defects
        offsets = unit.uniform(0, self.offset_max, N)
        dead = unit.random(N) < self.dead_fraction
        if self.offset_max > 0:
            y += offsets
        if np.any(_arr(self.offset)):
            y += _arr(self.offset)
        drift = _arr(self.drift_std_per_sqrt_s)
        if np.any(drift):
            steps = rng.standard_normal((T, N)) * drift / np.sqrt(rate_hz)
            y += np.cumsum(steps, axis=0)
        noise = _arr(self.noise_std)
        if np.any(noise):
            y += noise * rng.standard_normal((T, N))
        y[:, dead] = self.dead_value
        if self.quant_step > 0:
            y = np.round(y / self.quant_step) * self.quant_step
        if self.clip_min is not None:
            y = np.maximum(y, self.clip_min)
        return y

    def readout_gate(self, T: int, N: int, rng: np.random.Generator) -> np.ndarray:
        """(T, N): 1 where a channel's sample carries its signal, ``readout_leak`` elsewhere
        (one draw from ``rng``: the slide's shift in the readout cycle)."""
        P = self.readout_period
        phase = np.zeros(N, dtype=np.int64)
        if self.readout_phase:
            if len(self.readout_phase) != N:
                raise v.ConfigError(
                    f"imperfections.readout_phase has {len(self.readout_phase)} values; "
                    f"valid: one per channel ({N})"
                )
            phase[:] = self.readout_phase
        shift = int(rng.integers(P))
        on = (np.arange(T)[:, None] - shift - phase[None, :]) % P == 0
        return np.where(on, 1.0, self.readout_leak)

    def to_json(self) -> dict:
        d = asdict(self)
        if d["offset"] == 0.0:  # a fixed baseline came later: without one, the definition
            del d["offset"]  # (and every key made from it) stays as it was
        if d["readout_period"] == 1:  # so did the multiplexed readout
            for k in ("readout_period", "readout_phase", "readout_leak"):
                del d[k]
        return d
