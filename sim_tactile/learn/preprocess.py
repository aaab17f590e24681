"""Small scikit-learn transformers that turn recordings into classifier inputs.

Arrays are ``(samples, time, channels)``; encoded data are ``list[SpikeTrains]``.

(The scalers an encoding starts with live with the encoders: :mod:`sim_tactile.encoders.scaling`.)
- :class:`TimeCollapse`: the mean (or sum) over time -> ``(samples, channels)``: the
  "raw data collapsed in time" input of seed paper 000's SVM.
- :class:`SpikeCounts`: spike count per channel -> ``(samples, channels)``.
- :class:`SpikeRaster`: spike trains -> binary rasters ``(samples, steps, channels)`` at a
  time step ``dt_s``, the input of :class:`~sim_tactile.learn.snn.SNNClassifier`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin

from .._validate import check_array, one_of, positive
from ..errors import ConfigError
from ..records import SpikeTrains

COLLAPSE = ("mean", "sum")


class TimeCollapse(TransformerMixin, BaseEstimator):
    """Collapse the time axis: ``how="mean"`` (default) or ``"sum"`` -> ``(samples, channels)``."""

    def __init__(self, how: str = "mean") -> None:
        self.how = how

    def fit(self, X: object, y: object = None) -> TimeCollapse:
        one_of("how", self.how, COLLAPSE)
        self.n_features_in_ = check_array(X, ndim=(3,)).shape[2]
        return self

    def transform(self, X: object) -> np.ndarray:
        x = check_array(X, ndim=(3,))
        return x.mean(axis=1) if self.how == "mean" else x.sum(axis=1)


def _check_trains(X: Sequence[object]) -> list[SpikeTrains]:
    trains = list(X)
    for k, s in enumerate(trains):
        if not isinstance(s, SpikeTrains):
            raise ConfigError(f"X[{k}] must be a SpikeTrains, got {type(s).__name__}")
    if not trains:
        raise ConfigError("X holds no samples")
    return trains


class SpikeCounts(TransformerMixin, BaseEstimator):
    """Spike count of every channel: ``list[SpikeTrains]`` -> ``(samples, channels)`` float."""

    def fit(self, X: Sequence[object], y: object = None) -> SpikeCounts:
        self.n_channels_ = _check_trains(X)[0].n_channels
        return self

    def transform(self, X: Sequence[object]) -> np.ndarray:
        return np.array([s.counts() for s in _check_trains(X)], dtype=np.float64)


class SpikeRaster(TransformerMixin, BaseEstimator):
    """Bin spike trains at ``dt_s`` [s]: ``(samples, steps, channels)`` float32 of 0 / 1.

    Step ``n`` covers ``[t_start + n dt_s, t_start + (n + 1) dt_s)``; the number of steps is
    ``round(window / dt_s)`` (a spike at the window's end goes to the last step). Two spikes
    of one channel in one step count once (clip at 1), as a binary raster must.
    """

    def __init__(self, dt_s: float = 0.01) -> None:
        self.dt_s = dt_s

    def fit(self, X: Sequence[object], y: object = None) -> SpikeRaster:
        positive("dt_s", self.dt_s, unit="s")
        self.n_channels_ = _check_trains(X)[0].n_channels
        return self

    def transform(self, X: Sequence[object]) -> np.ndarray:
        dt = positive("dt_s", self.dt_s, unit="s")
        trains = _check_trains(X)
        n_steps = max(1, round(trains[0].duration_s / dt))
        out = np.zeros((len(trains), n_steps, trains[0].n_channels), dtype=np.float32)
        for i, s in enumerate(trains):
            if round(s.duration_s / dt) != n_steps or s.n_channels != out.shape[2]:
                raise ConfigError(
                    f"X[{i}] has a {s.duration_s:g} s window and {s.n_channels} channels; "
                    f"X[0] has {trains[0].duration_s:g} s and {out.shape[2]}: all must match"
                )
            for c, t in enumerate(s.times):
                steps = np.minimum(((t - s.t_start) / dt + 1e-9).astype(np.int64), n_steps - 1)
                out[i, steps, c] = 1.0
        return out
