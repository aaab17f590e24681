"""Distances between multi-channel samples, and a transformer for precomputed-metric kNN.

A sample is a :class:`~sim_tactile.records.SpikeTrains` (or any sequence of per-channel
spike-time arrays [s]). The distance between two samples combines the per-channel distances
``d_c`` (channel ``c`` of one sample against channel ``c`` of the other):

- ``"sum"``: ``sum_c d_c`` (the default)
- ``"mean"``: ``mean_c d_c``
- ``"rms"``: ``sqrt(mean_c d_c^2)``
- ``"max"``: ``max_c d_c``
- ``"none"``: no combination; the per-channel matrices are stacked, shape ``(C, n_a, n_b)``

Sum, mean, rms and max of metrics are metrics again, so kNN on them is well posed.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin

from .._validate import one_of
from ..errors import ConfigError
from ..records import SpikeTrains
from . import distances as D

#: How the per-channel distances of two samples combine into one: their sum, mean, root mean
#: square or maximum, or ``"none"`` (one distance per channel).
COMBINE = ("sum", "mean", "rms", "max", "none")


def _per_channel(samples: Sequence[object], what: str) -> list[Sequence[np.ndarray]]:
    out = [s.times if isinstance(s, SpikeTrains) else list(s) for s in samples]
    if out:
        n = len(out[0])
        for k, s in enumerate(out):
            if len(s) != n:
                raise ConfigError(
                    f"{what}[{k}] has {len(s)} channels but {what}[0] has {n}; all samples "
                    f"must have the same channels"
                )
    return out


def _window(samples: Sequence[object], params: dict) -> dict:
    """Fill t_start / t_end for ISI and SPIKE from the samples' common window."""
    if "t_start" in params and "t_end" in params:
        return params
    windows = {(s.t_start, s.t_end) for s in samples if isinstance(s, SpikeTrains)}
    if len(windows) != 1 or not all(isinstance(s, SpikeTrains) for s in samples):
        raise ConfigError(
            "isi_distance and spike_distance need t_start and t_end [s]: pass them, or pass "
            f"SpikeTrains samples that share one window (found {len(windows)} windows)"
        )
    t0, t1 = windows.pop()
    return {"t_start": t0, "t_end": t1, **params}


def _combine(stack: np.ndarray, combine: str) -> np.ndarray:
    if combine == "none":
        return stack
    if stack.shape[0] == 0:
        return np.zeros(stack.shape[1:])
    if combine == "sum":
        return stack.sum(axis=0)
    if combine == "mean":
        return stack.mean(axis=0)
    if combine == "rms":
        return np.sqrt(np.mean(stack * stack, axis=0))
    return stack.max(axis=0)


def cross_multichannel(
    samples_a: Sequence[object],
    samples_b: Sequence[object] | None,
    metric: str,
    *,
    combine: str = "sum",
    **params: float,
) -> np.ndarray:
    """Distances between multi-channel samples, shape ``(n_a, n_b)`` (``(C, n_a, n_b)`` for
    ``combine="none"``). ``samples_b=None`` means ``samples_a`` against itself (symmetric,
    zero diagonal). ``metric`` and ``params`` as in :func:`sim_tactile.spikes.distances.cross`;
    for ISI and SPIKE the window defaults to the samples' common ``[t_start, t_end]``.
    """
    combine = one_of("combine", combine, COMBINE)
    name = D.metric_name(metric)
    if name in ("isi_distance", "spike_distance"):
        both = list(samples_a) + ([] if samples_b is None else list(samples_b))
        params = _window(both, params)
    a = _per_channel(samples_a, "samples_a")
    b = None if samples_b is None else _per_channel(samples_b, "samples_b")
    n_ch = len(a[0]) if a else (len(b[0]) if b else 0)
    if b is not None and a and b and len(b[0]) != n_ch:
        raise ConfigError(
            f"samples_b have {len(b[0])} channels but samples_a have {n_ch}; they must match"
        )
    mats = []
    for c in range(n_ch):
        ta = [s[c] for s in a]
        if b is None:
            mats.append(D.pairwise(ta, name, **params))
        else:
            mats.append(D.cross(ta, [s[c] for s in b], name, **params))
    shape = (len(a), len(a) if b is None else len(b))
    stack = np.stack(mats) if mats else np.zeros((0, *shape))
    return _combine(stack, combine)


def pairwise_multichannel(
    samples: Sequence[object], metric: str, *, combine: str = "sum", **params: float
) -> np.ndarray:
    """Symmetric ``(n, n)`` matrix between multi-channel samples; see :func:`cross_multichannel`."""
    return cross_multichannel(samples, None, metric, combine=combine, **params)


class SpikeTrainDistances(TransformerMixin, BaseEstimator):
    """Turn samples into distances to the training samples, for precomputed-metric estimators.

    ``fit(X)`` stores the training samples; ``transform(X)`` returns the ``(len(X), n_train)``
    distances to them, and ``fit_transform`` the symmetric training matrix, which is what
    ``Pipeline([("d", SpikeTrainDistances(...)), ("knn", KNeighborsClassifier(
    metric="precomputed"))])`` needs.

    Parameters:
        metric: a name of :data:`sim_tactile.spikes.distances.METRICS`.
        metric_params: keyword parameters of the metric (e.g. ``{"q": 24.0}``).
        combine: how channels combine, one of ``sum``, ``mean``, ``rms``, ``max``.
    """

    def __init__(
        self,
        metric: str = "victor_purpura",
        metric_params: dict | None = None,
        combine: str = "sum",
    ) -> None:
        self.metric = metric
        self.metric_params = metric_params
        self.combine = combine

    def _check(self) -> dict:
        D.metric_name(self.metric)
        one_of("combine", self.combine, tuple(c for c in COMBINE if c != "none"))
        return dict(self.metric_params or {})

    def fit(self, X: Sequence[object], y: object = None) -> SpikeTrainDistances:
        self._check()
        self.train_ = list(X)
        self.n_train_ = len(self.train_)
        return self

    def transform(self, X: Sequence[object]) -> np.ndarray:
        params = self._check()
        if not hasattr(self, "train_"):
            raise ConfigError("SpikeTrainDistances is not fitted; call fit first")
        return cross_multichannel(list(X), self.train_, self.metric, combine=self.combine, **params)

    def fit_transform(self, X: Sequence[object], y: object = None, **fit_params) -> np.ndarray:
        self.fit(X)
        params = self._check()
        return pairwise_multichannel(self.train_, self.metric, combine=self.combine, **params)
