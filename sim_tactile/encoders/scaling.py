"""Scalers that prepare sampled signals for an encoder (arrays ``(samples, time, channels)``).

- :class:`SampleStandardizer`: each channel of each sample to zero mean and unit standard
  deviation over its own window (stateless: a sample's encoding does not depend on others).
- :class:`RangeScaler`: each channel mapped so that a robust range of the training data
  (by default its 1st to 99th percentile) becomes ``[0, span]``.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin

from .._validate import check_array, in_range, positive
from ..errors import ConfigError


class SampleStandardizer(TransformerMixin, BaseEstimator):
    """``(x - mean_t x) / std_t x`` per sample and channel; a constant channel becomes 0."""

    def fit(self, X: object, y: object = None) -> SampleStandardizer:
        self.n_features_in_ = check_array(X, ndim=(3,)).shape[2]
        return self

    def transform(self, X: object) -> np.ndarray:
        x = check_array(X, ndim=(3,))
        mean = x.mean(axis=1, keepdims=True)
        std = x.std(axis=1, keepdims=True)
        return (x - mean) / np.where(std > 0, std, 1.0)


class RangeScaler(TransformerMixin, BaseEstimator):
    """Per channel ``span * (x - p_lo) / (p_hi - p_lo)`` with the ``lo_pct`` and ``hi_pct``
    percentiles of the training data over all samples and steps (learned in ``fit`` as
    ``low_`` and ``high_``); a channel with ``p_hi == p_lo`` is only shifted. Values outside
    the range are kept (not clipped)."""

    def __init__(self, lo_pct: float = 1.0, hi_pct: float = 99.0, span: float = 1.0) -> None:
        self.lo_pct = lo_pct
        self.hi_pct = hi_pct
        self.span = span

    def fit(self, X: object, y: object = None) -> RangeScaler:
        lo = in_range("lo_pct", self.lo_pct, 0.0, 100.0)
        hi = in_range("hi_pct", self.hi_pct, 0.0, 100.0)
        if not hi > lo:
            raise ConfigError(f"hi_pct = {hi:g} must exceed lo_pct = {lo:g}")
        positive("span", self.span)
        x = check_array(X, ndim=(3,))
        flat = x.reshape(-1, x.shape[2])
        self.low_, self.high_ = np.percentile(flat, [lo, hi], axis=0)
        self.n_features_in_ = x.shape[2]
        return self

    def transform(self, X: object) -> np.ndarray:
        x = check_array(X, ndim=(3,))
        if x.shape[2] != self.n_features_in_:
            raise ConfigError(f"X has {x.shape[2]} channels, fit saw {self.n_features_in_}")
        width = self.high_ - self.low_
        return (x - self.low_) / np.where(width > 0, width, 1.0) * float(self.span)
