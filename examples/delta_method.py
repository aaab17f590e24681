"""A user's own encoder and classifier, scored on the benchmark's tasks.

- ``DeltaEncoder``: send-on-delta (level-crossing) encoding. Each channel emits an ON spike
  each time its signal rises by ``delta`` from the level of its last spike, and an OFF spike
  each time it falls by ``delta``; ``delta`` is in units of the channel's typical swing: the
  median, over the samples it is fitted on, of each sample's standard deviation in time (a
  fraction of the range would leave the quiet samples silent where amplitudes span decades,
  as roughness8's do). It returns one :class:`sim_tactile.records.SpikeTrains` per sample
  (ON and OFF channels), so the package's spike features and distances read it.
- ``NearestMean``: a nearest class mean on standardised features, by cosine similarity.

Score them, from the repository's root::

    sim-tactile run finger7-v1 --quick --method delta=examples/delta_method.py:delta_nearest_mean \\
        --method delta-svm=examples/delta_method.py:delta_svm --out out/delta-f7
    sim-tactile run roughness8-v1 --quick --method delta=examples/delta_method.py:delta_nearest_mean \\
        --out out/delta-r8

or in Python: ``sim_tactile.tasks.evaluate("finger7-v1", {"delta": delta_nearest_mean()})``.
Each callable returns an (encoder, estimator) pair; ``rate_hz=None`` takes the task's rate.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, TransformerMixin
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

from sim_tactile.records import SpikeTrains
from sim_tactile.spikes import SpikeFeatures


class DeltaEncoder(TransformerMixin, BaseEstimator):
    """Send-on-delta spikes of ``X`` (samples, time, channels) sampled at ``rate_hz``:
    2 x channels spike trains per sample (ON then OFF for each channel)."""

    def __init__(self, delta: float = 0.25, rate_hz: float | None = None) -> None:
        self.delta = delta
        self.rate_hz = rate_hz

    def fit(self, X, y=None):
        x = np.asarray(X, dtype=np.float64)
        if x.ndim != 3:
            raise ValueError(f"X must be (samples, time, channels), got shape {x.shape}")
        if not self.delta > 0.0:
            raise ValueError(f"delta = {self.delta!r}; valid: > 0 (of the typical swing)")
        swing = np.median(x.std(axis=1), axis=0)  # per channel
        self.step_ = self.delta * np.where(swing > 0, swing, 1.0)
        return self

    def transform(self, X):
        if self.rate_hz is None:
            raise ValueError("rate_hz is None: give the sampling rate (a task fills it in)")
        x = np.asarray(X, dtype=np.float64)
        n, T, C = x.shape
        dt = 1.0 / self.rate_hz
        ref = x[:, 0, :].copy()  # the level of each channel's last spike
        on = [[[] for _ in range(C)] for _ in range(n)]
        off = [[[] for _ in range(C)] for _ in range(n)]
        for t in range(1, T):
            k = np.fix((x[:, t, :] - ref) / self.step_).astype(np.int64)  # levels crossed
            ref += k * self.step_
            for i, c in zip(*np.nonzero(k), strict=True):
                m = int(k[i, c])
                times = t * dt + dt * np.arange(abs(m)) / abs(m)  # spread within the step
                (on if m > 0 else off)[i][c].extend(times.tolist())
        names = [f"ch{c}-{s}" for c in range(C) for s in ("on", "off")]
        t_end = T * dt
        return [
            SpikeTrains.from_lists(
                [tr for c in range(C) for tr in (on[i][c], off[i][c])], 0.0, t_end, names
            )
            for i in range(n)
        ]


class NearestMean(ClassifierMixin, BaseEstimator):
    """The class whose mean (of standardised features) is closest in angle."""

    def fit(self, X, y):
        x = np.asarray(X, dtype=np.float64)
        self.classes_ = np.unique(y)
        self.means_ = np.stack([x[np.asarray(y) == c].mean(axis=0) for c in self.classes_])
        return self

    def predict(self, X):
        x = np.asarray(X, dtype=np.float64)
        a = x / (np.linalg.norm(x, axis=1, keepdims=True) + 1e-12)
        b = self.means_ / (np.linalg.norm(self.means_, axis=1, keepdims=True) + 1e-12)
        return self.classes_[np.argmax(a @ b.T, axis=1)]


def _encoder(delta: float = 0.25) -> Pipeline:
    return Pipeline(
        [
            ("delta", DeltaEncoder(delta=delta)),
            ("features", SpikeFeatures(features=("rate_hz", "mean_isi_s"))),
        ]
    )


def delta_nearest_mean():
    """Send-on-delta spikes -> mean rate and mean ISI per channel -> nearest class mean."""
    return _encoder(), Pipeline([("scale", StandardScaler()), ("clf", NearestMean())])


def delta_svm():
    """The same encoding read by the package's choice of final classifier (a linear SVM)."""
    return _encoder(), Pipeline([("scale", StandardScaler()), ("clf", SVC(kernel="linear"))])
