"""scikit-learn transformers: arrays ``(samples, time, channels)`` -> ``list[SpikeTrains]``.

Real and synthetic recordings go through the same code: ``X`` is any array of shape
``(n_samples, n_time, n_channels)`` sampled at ``rate_hz``; ``transform`` returns one
:class:`~sim_tactile.records.SpikeTrains` per sample with window ``[0, n_time / rate_hz]``
s. Chain with :class:`~sim_tactile.spikes.features.SpikeFeatures` or
:class:`~sim_tactile.spikes.multichannel.SpikeTrainDistances` in a ``Pipeline``.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin

from .._validate import finite, one_of, positive
from ..cache import memoized
from ..errors import ConfigError
from ..records import SpikeTrains
from ._common import check_current
from .izhikevich import simulate_izhikevich
from .lif import DEFAULT_LIF_DT_S, simulate_lif
from .neurons import DEFAULT_DT_S, SCHEMES, IzhikevichParams, LIFParams, izhikevich_preset
from .threshold import EXTRA, SPACING, threshold_channel_names, threshold_encode
from .threshold import thresholds_from_data as _thresholds_from_data

NORMALIZE = ("none", "minmax", "maxabs")


def _check_X(X: object) -> np.ndarray:
    x = check_current(X, "X")
    if x.ndim == 2:
        x = x[None]
    if x.ndim != 3 or x.shape[1] < 1:
        raise ConfigError(f"X must have shape (samples, time, channels), got {np.shape(X)}")
    return x


def _names(channel_names: Sequence[str] | None, n: int) -> list[str]:
    if channel_names is None:
        return [f"ch{k}" for k in range(n)]
    names = [str(c) for c in channel_names]
    if len(names) != n:
        raise ConfigError(f"channel_names has {len(names)} entries but X has {n} channels")
    return names


def _per_channel(value: object, n: int, name: str) -> list:
    if isinstance(value, str | IzhikevichParams | int | float) or value is None:
        return [value] * n
    values = list(value)  # type: ignore[arg-type]
    if len(values) != n:
        raise ConfigError(f"{name} has {len(values)} entries but X has {n} channels")
    return values


class _Normalizer:
    """Per-channel affine normalisation learned from training data."""

    @staticmethod
    def fit(x: np.ndarray, mode: str) -> tuple[np.ndarray, np.ndarray]:
        mode = one_of("normalize", mode, NORMALIZE)
        c = x.shape[2]
        if mode == "none":
            return np.zeros(c), np.ones(c)
        flat = x.reshape(-1, c)
        if mode == "minmax":
            lo, span = flat.min(axis=0), np.ptp(flat, axis=0)
        else:
            lo, span = np.zeros(c), np.abs(flat).max(axis=0)
        return lo, np.where(span > 0, 1.0 / np.where(span > 0, span, 1.0), 1.0)


def _window_trains(times: list[np.ndarray], n_samples: int, n_ch: int, t_end: float, names):
    out = []
    for s in range(n_samples):
        chunk = times[s * n_ch : (s + 1) * n_ch]
        out.append(SpikeTrains(tuple(chunk), 0.0, t_end, tuple(names)))
    return out


@memoized("calibrated currents", maxsize=128)
def calibrate_current(
    params: IzhikevichParams,
    target_rate_hz: float,
    dt_s: float,
    scheme: str,
    window_s: float = 1.0,
) -> float:
    """Smallest constant input ``I`` (model units) at which the neuron, starting at rest, fires
    at least ``target_rate_hz`` on average over ``window_s`` seconds (bisection, 1e-9 relative).
    """
    target = positive("max_rate_hz", target_rate_hz, unit="Hz")
    n_samples = 10

    def rate(current: float) -> float:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            spikes = simulate_izhikevich(
                np.full(n_samples, current), n_samples / window_s, params, dt_s=dt_s, scheme=scheme
            )[0]
        return spikes.size / window_s

    lo, hi = 0.0, 1.0
    while rate(hi) < target:
        lo, hi = hi, 2.0 * hi
        if hi > 1e7:
            raise ConfigError(
                f"max_rate_hz = {target:g} Hz is not reachable by this neuron with the "
                f"{scheme} step of dt_s = {dt_s:g} s"
            )
    while hi - lo > 1e-9 * hi:
        mid = 0.5 * (lo + hi)
        if rate(mid) >= target:
            hi = mid
        else:
            lo = mid
    return hi


class IzhikevichEncoder(TransformerMixin, BaseEstimator):
    """One Izhikevich neuron per channel, driven by ``I = gain * normalised(x)``.

    The input scalings of the papers:

    - paper 001: ``I = G V`` -> ``normalize="none", gain=G`` (e.g. 0.4);
    - paper 002: normalised signal times ``k = 15`` -> ``normalize="minmax", gain=15``;
    - paper 003: gain chosen so that the maximum rate is 100 Hz (SA / RS) or 200 Hz (RA / FS)
      -> ``normalize="minmax", max_rate_hz=[...]``: for each channel, the gain makes a constant
      input equal to the channel's largest normalised training value fire at ``max_rate_hz``
      (mean rate over ``calib_window_s``, starting at rest).

    Parameters:
        rate_hz: sampling rate of ``X`` [Hz]; the neuron holds each sample (zero-order hold).
        preset: preset name (RS, SA, FS, RA) or :class:`IzhikevichParams`, or one per channel.
        gain: input gain (model current units per normalised unit); one value or per channel.
        max_rate_hz: if given (one value or per channel), the gain is calibrated in ``fit``.
        normalize: ``none``, ``minmax`` (per channel to [0, 1] over the training data) or
            ``maxabs`` (per channel divided by the largest magnitude).
        dt_s: neuron step [s]; ``None`` = 1e-4 for rk4, 1e-3 for the papers' schemes.
        scheme: ``rk4`` (accurate), ``euler`` or ``izhikevich2003`` (the papers' 1 ms schemes).
        calib_window_s: window of the rate calibration [s].
        channel_names: names of the input channels (default ch0, ch1, ...).
    """

    def __init__(
        self,
        rate_hz: float = 100.0,
        preset: str | IzhikevichParams | Sequence[str | IzhikevichParams] = "RS",
        gain: float | Sequence[float] = 1.0,
        max_rate_hz: float | Sequence[float] | None = None,
        normalize: str = "none",
        dt_s: float | None = None,
        scheme: str = "rk4",
        calib_window_s: float = 1.0,
        channel_names: Sequence[str] | None = None,
    ) -> None:
        self.rate_hz = rate_hz
        self.preset = preset
        self.gain = gain
        self.max_rate_hz = max_rate_hz
        self.normalize = normalize
        self.dt_s = dt_s
        self.scheme = scheme
        self.calib_window_s = calib_window_s
        self.channel_names = channel_names

    def fit(self, X: np.ndarray, y: object = None) -> IzhikevichEncoder:
        x = _check_X(X)
        positive("rate_hz", self.rate_hz, unit="Hz")
        scheme = one_of("scheme", self.scheme, SCHEMES)
        dt_s = DEFAULT_DT_S[scheme] if self.dt_s is None else positive("dt_s", self.dt_s)
        n_ch = x.shape[2]
        self.channel_names_ = _names(self.channel_names, n_ch)
        self.params_ = [izhikevich_preset(p) for p in _per_channel(self.preset, n_ch, "preset")]
        self.offset_, self.scale_ = _Normalizer.fit(x, self.normalize)
        if self.max_rate_hz is None:
            gains = [finite("gain", g) for g in _per_channel(self.gain, n_ch, "gain")]
        else:
            targets = _per_channel(self.max_rate_hz, n_ch, "max_rate_hz")
            level = ((x - self.offset_) * self.scale_).reshape(-1, n_ch).max(axis=0)
            gains = []
            for c in range(n_ch):
                if not level[c] > 0:
                    raise ConfigError(
                        f"channel {self.channel_names_[c]} has no positive (normalised) "
                        f"training signal, so max_rate_hz cannot set its gain"
                    )
                current = calibrate_current(
                    self.params_[c], float(targets[c]), dt_s, scheme, float(self.calib_window_s)
                )
                gains.append(current / level[c])
        self.gain_ = np.asarray(gains, dtype=np.float64)
        self.dt_s_ = dt_s
        self.n_features_in_ = n_ch
        return self

    def currents(self, X: np.ndarray) -> np.ndarray:
        """The neuron input ``I`` for ``X``, same shape (model current units)."""
        x = _check_X(X)
        if x.shape[2] != self.n_features_in_:
            raise ConfigError(f"X has {x.shape[2]} channels, fit saw {self.n_features_in_}")
        return (x - self.offset_) * self.scale_ * self.gain_

    def transform(self, X: np.ndarray) -> list[SpikeTrains]:
        cur = self.currents(X)
        n, n_t, n_ch = cur.shape
        rows = np.ascontiguousarray(cur.transpose(0, 2, 1).reshape(n * n_ch, n_t))
        times = simulate_izhikevich(
            rows, self.rate_hz, self.params_ * n, dt_s=self.dt_s_, scheme=self.scheme
        )
        return _window_trains(times, n, n_ch, n_t / self.rate_hz, self.channel_names_)


class LIFEncoder(TransformerMixin, BaseEstimator):
    """One (adaptive) LIF neuron per channel, input ``gain * normalised(x)`` (units of v).

    ``params`` is a :class:`LIFParams` (``beta > 0`` for the adaptive LIF, see
    :func:`~sim_tactile.encoders.neurons.alif_params`); the other parameters as in
    :class:`IzhikevichEncoder`.
    """

    def __init__(
        self,
        rate_hz: float = 100.0,
        params: LIFParams | None = None,
        gain: float = 1.0,
        normalize: str = "none",
        dt_s: float = DEFAULT_LIF_DT_S,
        channel_names: Sequence[str] | None = None,
    ) -> None:
        self.rate_hz = rate_hz
        self.params = params
        self.gain = gain
        self.normalize = normalize
        self.dt_s = dt_s
        self.channel_names = channel_names

    def fit(self, X: np.ndarray, y: object = None) -> LIFEncoder:
        x = _check_X(X)
        positive("rate_hz", self.rate_hz, unit="Hz")
        self.channel_names_ = _names(self.channel_names, x.shape[2])
        self.offset_, self.scale_ = _Normalizer.fit(x, self.normalize)
        self.gain_ = finite("gain", self.gain)
        self.params_ = LIFParams() if self.params is None else self.params
        self.n_features_in_ = x.shape[2]
        return self

    def transform(self, X: np.ndarray) -> list[SpikeTrains]:
        x = _check_X(X)
        if x.shape[2] != self.n_features_in_:
            raise ConfigError(f"X has {x.shape[2]} channels, fit saw {self.n_features_in_}")
        cur = (x - self.offset_) * self.scale_ * self.gain_
        n, n_t, n_ch = cur.shape
        rows = np.ascontiguousarray(cur.transpose(0, 2, 1).reshape(n * n_ch, n_t))
        times = simulate_lif(rows, self.rate_hz, self.params_, dt_s=self.dt_s)
        return _window_trains(times, n, n_ch, n_t / self.rate_hz, self.channel_names_)


class ThresholdEncoder(TransformerMixin, BaseEstimator):
    """Threshold encoding (paper 000): ``2K + 1`` spike channels per input channel.

    Parameters:
        rate_hz: sampling rate of ``X`` [Hz].
        n_thresholds: K (2 in the paper).
        thresholds: fixed thresholds, shape ``(K,)`` or ``(channels, K)`` in signal units; if
            ``None`` they are derived per channel from the training data in ``fit``.
        spacing: how thresholds are derived: ``linspace`` (evenly inside [min, max]) or
            ``quantile``.
        extra: reading of the ``2K + 1``-th channel: ``global_max`` or ``local_max``
            (see :mod:`sim_tactile.encoders.threshold`).
        channel_names: names of the input channels.
    """

    def __init__(
        self,
        rate_hz: float = 100.0,
        n_thresholds: int = 2,
        thresholds: np.ndarray | None = None,
        spacing: str = "linspace",
        extra: str = "global_max",
        channel_names: Sequence[str] | None = None,
    ) -> None:
        self.rate_hz = rate_hz
        self.n_thresholds = n_thresholds
        self.thresholds = thresholds
        self.spacing = spacing
        self.extra = extra
        self.channel_names = channel_names

    def fit(self, X: np.ndarray, y: object = None) -> ThresholdEncoder:
        x = _check_X(X)
        positive("rate_hz", self.rate_hz, unit="Hz")
        one_of("extra", self.extra, EXTRA)
        one_of("spacing", self.spacing, SPACING)
        n_ch = x.shape[2]
        if self.thresholds is None:
            th = _thresholds_from_data(x, self.n_thresholds, self.spacing)
        else:
            th = check_current(self.thresholds, "thresholds")
            if th.ndim == 1:
                th = np.broadcast_to(th, (n_ch, th.size)).copy()
            if th.ndim != 2 or th.shape[0] != n_ch:
                raise ConfigError(
                    f"thresholds must have shape (K,) or (channels={n_ch}, K), got {th.shape}"
                )
        self.thresholds_ = np.sort(th, axis=1)
        self.input_names_ = _names(self.channel_names, n_ch)
        self.channel_names_ = threshold_channel_names(self.input_names_, th.shape[1])
        self.n_features_in_ = n_ch
        return self

    def transform(self, X: np.ndarray) -> list[SpikeTrains]:
        x = _check_X(X)
        if x.shape[2] != self.n_features_in_:
            raise ConfigError(f"X has {x.shape[2]} channels, fit saw {self.n_features_in_}")
        t_end = x.shape[1] / self.rate_hz
        out = []
        for sample in x:
            trains = threshold_encode(sample, self.rate_hz, self.thresholds_, extra=self.extra)
            out.append(SpikeTrains(tuple(trains), 0.0, t_end, tuple(self.channel_names_)))
        return out
