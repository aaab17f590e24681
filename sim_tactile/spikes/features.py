"""Spike features per channel, as feature matrices (seed papers 001, 002, 003).

For a channel with ``n`` spikes at ``t_1 <= ... <= t_n`` in the window ``[t_start, t_end]`` of
length ``T`` (s):

==================== ======================================================================
``count``            ``n``
``rate_hz``          mean firing rate over bins: the window is cut into
                     ``max(1, round(T / bin_s))`` equal bins (100 ms by default, paper 002),
                     each bin's rate is its count / width; the mean of all bins (= ``n / T``)
``rate_nonzero_hz``  mean of the non-zero bin rates (paper 003); 0 when there is no spike
``mean_isi_s``       mean inter-spike interval ``(t_n - t_1) / (n - 1)``; with fewer than two
                     spikes it is ``isi_fill_s`` (default: ``T``, as if the next spike came
                     one window later)
``inv_mean_isi_hz``  ``1 / mean_isi_s`` (paper 001), with the same fill (``1 / T``)
``first_latency_s``  ``t_1 - t_start``; without spikes ``latency_fill_s`` (default: ``T``)
``cv_isi``           standard deviation (ddof = 0) / mean of the intervals; 0 with fewer than
                     three spikes (one interval has no spread) or when all intervals are 0
==================== ======================================================================

Every value is finite: no NaN reaches a classifier. A spike exactly at ``t_end`` belongs to the
last bin.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin

from .._validate import positive
from ..errors import ConfigError
from ..records import SpikeTrains

#: The spike features :class:`SpikeFeatures` computes per channel, by name.
FEATURES = (
    "count",
    "rate_hz",
    "rate_nonzero_hz",
    "mean_isi_s",
    "inv_mean_isi_hz",
    "first_latency_s",
    "cv_isi",
)


def _check_features(features: Sequence[str]) -> tuple[str, ...]:
    if isinstance(features, str):
        features = (features,)
    feats = tuple(features)
    bad = [f for f in feats if f not in FEATURES]
    if bad or not feats:
        raise ConfigError(
            f"features = {list(feats)} is not valid; choose from: {', '.join(FEATURES)}"
        )
    return feats


def channel_features(
    times: np.ndarray,
    t_start: float,
    t_end: float,
    *,
    bin_s: float = 0.1,
    isi_fill_s: float | None = None,
    latency_fill_s: float | None = None,
) -> dict[str, float]:
    """All :data:`FEATURES` of one spike train (times [s]) in the window ``[t_start, t_end]``."""
    t = np.asarray(times, dtype=np.float64)
    span = t_end - t_start
    n = int(t.size)
    n_bins = max(1, round(span / bin_s))
    width = span / n_bins
    if n:
        idx = np.minimum(((t - t_start) / width).astype(np.int64), n_bins - 1)
        counts = np.bincount(idx, minlength=n_bins)
        nonzero = counts[counts > 0]
        rate_nonzero = float(nonzero.mean() / width)
    else:
        rate_nonzero = 0.0
    isi_fill = span if isi_fill_s is None else isi_fill_s
    if n >= 2:
        isis = np.diff(t)
        mean_isi = float((t[-1] - t[0]) / (n - 1))
        if mean_isi <= 0.0:
            raise ConfigError(
                f"a spike train has all its {n} spikes at t = {t[0]:g} s; the mean "
                f"inter-spike interval is 0 and its inverse is undefined"
            )
        cv = float(isis.std() / isis.mean()) if n >= 3 else 0.0
    else:
        mean_isi = float(isi_fill)
        cv = 0.0
    latency = (
        float(t[0] - t_start) if n else float(span if latency_fill_s is None else latency_fill_s)
    )
    return {
        "count": float(n),
        "rate_hz": n / span,
        "rate_nonzero_hz": rate_nonzero,
        "mean_isi_s": mean_isi,
        "inv_mean_isi_hz": 1.0 / mean_isi,
        "first_latency_s": latency,
        "cv_isi": cv,
    }


def spike_features(
    samples: Sequence[SpikeTrains],
    features: Sequence[str] = FEATURES,
    *,
    bin_s: float = 0.1,
    isi_fill_s: float | None = None,
    latency_fill_s: float | None = None,
) -> np.ndarray:
    """Feature matrix of shape ``(n_samples, n_channels * n_features)``, float64.

    Columns are channel-major: all requested features of channel 0, then channel 1, ...
    (names from :func:`feature_names`). ``bin_s`` [s] is the rate bin width; the fills are the
    values used when a channel has too few spikes (see the module docstring).
    """
    feats = _check_features(features)
    bin_s = positive("bin_s", bin_s, unit="s")
    if isi_fill_s is not None:
        isi_fill_s = positive("isi_fill_s", isi_fill_s, unit="s")
    if latency_fill_s is not None:
        latency_fill_s = positive("latency_fill_s", latency_fill_s, unit="s")
    rows = []
    n_ch = None
    for k, s in enumerate(samples):
        if not isinstance(s, SpikeTrains):
            raise ConfigError(f"samples[{k}] must be a SpikeTrains, got {type(s).__name__}")
        if n_ch is None:
            n_ch = s.n_channels
        elif s.n_channels != n_ch:
            raise ConfigError(f"samples[{k}] has {s.n_channels} channels, samples[0] has {n_ch}")
        row = []
        for tr in s.times:
            f = channel_features(
                tr,
                s.t_start,
                s.t_end,
                bin_s=bin_s,
                isi_fill_s=isi_fill_s,
                latency_fill_s=latency_fill_s,
            )
            row.extend(f[name] for name in feats)
        rows.append(row)
    if not rows:
        return np.zeros((0, 0))
    return np.asarray(rows, dtype=np.float64)


def feature_names(channel_names: Sequence[str], features: Sequence[str] = FEATURES) -> list[str]:
    """Column names ``"<channel>:<feature>"`` in the order of :func:`spike_features`."""
    feats = _check_features(features)
    return [f"{c}:{f}" for c in channel_names for f in feats]


class SpikeFeatures(TransformerMixin, BaseEstimator):
    """scikit-learn transformer: ``list[SpikeTrains]`` -> feature matrix (see
    :func:`spike_features`). Stateless apart from remembering the channel names."""

    def __init__(
        self,
        features: Sequence[str] = FEATURES,
        bin_s: float = 0.1,
        isi_fill_s: float | None = None,
        latency_fill_s: float | None = None,
    ) -> None:
        self.features = features
        self.bin_s = bin_s
        self.isi_fill_s = isi_fill_s
        self.latency_fill_s = latency_fill_s

    def fit(self, X: Sequence[SpikeTrains], y: object = None) -> SpikeFeatures:
        _check_features(self.features)
        X = list(X)
        self.channel_names_ = list(X[0].channel_names) if X else []
        self.n_features_out_ = len(self.channel_names_) * len(_check_features(self.features))
        return self

    def transform(self, X: Sequence[SpikeTrains]) -> np.ndarray:
        return spike_features(
            list(X),
            self.features,
            bin_s=self.bin_s,
            isi_fill_s=self.isi_fill_s,
            latency_fill_s=self.latency_fill_s,
        )

    def get_feature_names_out(self, input_features: object = None) -> np.ndarray:
        return np.asarray(feature_names(self.channel_names_, self.features), dtype=object)
