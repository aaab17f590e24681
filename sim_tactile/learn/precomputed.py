"""Classifiers on per-sample quantities computed once: feature rows or a distance matrix.

When the encoding is unsupervised and fitted once on all samples (the papers that encode
their recordings offline, before any split), the spike features and the spike-train
distances do not depend on the split. Computing them once and letting every repeat of a
protocol index into them turns 1000 repeats from 1000 encodings into 1000 small fits.

The estimators here take sample indices as ``X`` (shape ``(n, 1)`` or ``(n,)``, integers into
the table they hold) so that :func:`sim_tactile.learn.protocols.evaluate` can split them like
any data.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.neighbors import KNeighborsClassifier

from .._validate import integer
from ..errors import ConfigError


def _indices(X: object, n: int) -> np.ndarray:
    idx = np.asarray(X)
    if idx.ndim == 2 and idx.shape[1] == 1:
        idx = idx[:, 0]
    if idx.ndim != 1 or idx.dtype.kind not in "iu":
        raise ConfigError(f"X must be sample indices, shape (n,) or (n, 1), got {idx.shape}")
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise ConfigError(f"sample indices must lie in [0, {n - 1}]")
    return idx


def sample_index(n: int) -> np.ndarray:
    """The ``X`` that addresses ``n`` precomputed samples: shape ``(n, 1)``."""
    return np.arange(n, dtype=np.int64)[:, None]


class OnFeatures(ClassifierMixin, BaseEstimator):
    """``estimator`` fitted on the rows ``features[X]`` of a feature matrix computed once."""

    def __init__(self, estimator: BaseEstimator, features: np.ndarray) -> None:
        self.estimator = estimator
        self.features = features

    def fit(self, X: object, y: object) -> OnFeatures:
        f = np.asarray(self.features, dtype=np.float64)
        if f.ndim != 2 or not np.isfinite(f).all():
            raise ConfigError(f"features must be a finite 2-D matrix, got shape {f.shape}")
        idx = _indices(X, f.shape[0])
        self.estimator_ = clone(self.estimator).fit(f[idx], y)
        self.classes_ = self.estimator_.classes_
        return self

    def predict(self, X: object) -> np.ndarray:
        f = np.asarray(self.features, dtype=np.float64)
        return self.estimator_.predict(f[_indices(X, f.shape[0])])


class OnDistances(ClassifierMixin, BaseEstimator):
    """k nearest neighbours on a precomputed ``(n, n)`` distance matrix: training uses the
    distances among ``X``, prediction the distances from the test samples to the training
    ones (scikit-learn's ``KNeighborsClassifier(metric="precomputed")``)."""

    def __init__(self, distances: np.ndarray, n_neighbors: int = 5) -> None:
        self.distances = distances
        self.n_neighbors = n_neighbors

    def _d(self) -> np.ndarray:
        d = np.asarray(self.distances, dtype=np.float64)
        if d.ndim != 2 or d.shape[0] != d.shape[1] or not np.isfinite(d).all():
            raise ConfigError(f"distances must be a finite square matrix, got shape {d.shape}")
        return d

    def fit(self, X: object, y: object) -> OnDistances:
        d = self._d()
        idx = _indices(X, d.shape[0])
        k = integer("n_neighbors", self.n_neighbors, 1, None)
        if k > idx.size:
            raise ConfigError(
                f"n_neighbors = {k} exceeds the {idx.size} training samples; valid: 1..{idx.size}"
            )
        self.train_ = idx
        self.knn_ = KNeighborsClassifier(n_neighbors=k, metric="precomputed")
        self.knn_.fit(d[np.ix_(idx, idx)], y)
        self.classes_ = self.knn_.classes_
        return self

    def predict(self, X: object) -> np.ndarray:
        d = self._d()
        idx = _indices(X, d.shape[0])
        return self.knn_.predict(d[np.ix_(idx, self.train_)])
