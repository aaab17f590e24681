"""Evaluation protocols of the seed papers: repeated stratified splits, accuracy, confusion
matrices and accuracy over time.

Splits are given as a ratio ``"7:3"`` (stratified, as scikit-learn's
``StratifiedShuffleSplit``) or as per-class counts ``"24/8"`` (exactly 24 training and 8 test
samples drawn from every class). Each repeat draws a new split from one seeded generator.

Accuracy over time (seed paper 000, Figs. 5 and 8): a model is evaluated on the first ``t``
seconds of each test sample. The SVMs and the LSTM are trained anew on the first ``t`` seconds
of the training samples and tested on the first ``t`` seconds of the test samples, as the
paper does. An "anytime" model (the SNN) is trained once on full recordings; its decision at
``t`` is its output spike count up to ``t`` on the encoded test recording (the encoder sees
the whole recording, as in the paper; the network is causal, so its counts up to ``t`` depend
on the input spikes up to ``t`` only). It must offer ``predict_upto(X, t_s)``; in a Pipeline
that is its last step, fed by the other steps' transform of the whole recording.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.metrics import confusion_matrix
from sklearn.model_selection import StratifiedShuffleSplit

from .._validate import check_labels, integer, positive
from ..errors import ConfigError
from .neurobench import neuromorphic_figures

_RATIO = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*:\s*(\d+(?:\.\d+)?)\s*$")
_COUNTS = re.compile(r"^\s*(\d+)\s*/\s*(\d+)\s*$")


@dataclass(frozen=True)
class SplitSpec:
    """A train/test split rule: ``kind`` ``"ratio"`` (``train : test``) or ``"counts"``
    (``train`` and ``test`` samples per class)."""

    kind: str
    train: float
    test: float

    @classmethod
    def parse(cls, text: str | SplitSpec) -> SplitSpec:
        if isinstance(text, SplitSpec):
            return text
        if m := _RATIO.match(str(text)):
            tr, te = float(m.group(1)), float(m.group(2))
            if tr <= 0 or te <= 0:
                raise ConfigError(f"split = {text!r}: both parts of a ratio must be > 0")
            return cls("ratio", tr, te)
        if m := _COUNTS.match(str(text)):
            tr, te = int(m.group(1)), int(m.group(2))
            if tr < 1 or te < 1:
                raise ConfigError(f"split = {text!r}: per-class counts must be >= 1")
            return cls("counts", tr, te)
        raise ConfigError(
            f"split = {text!r} is not valid; give a ratio like '7:3' or per-class counts "
            f"like '24/8' (train/test)"
        )

    def __str__(self) -> str:
        if self.kind == "ratio":
            return f"{self.train:g}:{self.test:g}"
        return f"{int(self.train)}/{int(self.test)} per class"


def _label(c: object) -> str:
    return repr(c.item() if hasattr(c, "item") else c)


def repeated_splits(
    labels: object, split: str | SplitSpec, repeats: int, random_state: int | None = 0
) -> list[tuple[np.ndarray, np.ndarray]]:
    """``repeats`` stratified (train, test) index pairs; errors name a class that is too small."""
    y = np.asarray(labels)
    if y.ndim != 1 or y.size == 0:
        raise ConfigError(f"labels must be a non-empty 1-D array, got shape {y.shape}")
    spec = SplitSpec.parse(split)
    repeats = integer("repeats", repeats, 1, None)
    classes, counts = np.unique(y, return_counts=True)
    if classes.size < 2:
        raise ConfigError(f"labels hold {classes.size} class; a split needs at least 2")
    if spec.kind == "counts":
        need = int(spec.train + spec.test)
        small = counts < need
        if small.any():
            k = int(np.argmax(small))
            raise ConfigError(
                f"class {_label(classes[k])} has {counts[k]} samples but split {spec} needs "
                f"{need} ({int(spec.train)} train + {int(spec.test)} test) of every class"
            )
        rng = np.random.default_rng(random_state)
        out = []
        members = [np.flatnonzero(y == c) for c in classes]
        for _ in range(repeats):
            tr, te = [], []
            for idx in members:
                perm = rng.permutation(idx)
                tr.append(perm[: int(spec.train)])
                te.append(perm[int(spec.train) : need])
            out.append((np.sort(np.concatenate(tr)), np.sort(np.concatenate(te))))
        return out
    test_frac = spec.test / (spec.train + spec.test)
    n_test = int(np.ceil(test_frac * y.size))
    n_train = y.size - n_test
    small = counts < 2
    if small.any() or n_test < classes.size or n_train < classes.size:
        k = int(np.argmin(counts))
        raise ConfigError(
            f"class {_label(classes[k])} has {counts[k]} sample(s): split {spec} of {y.size} samples "
            f"needs at least 2 per class and at least {classes.size} (one per class) on each "
            f"side (train {n_train}, test {n_test})"
        )
    sss = StratifiedShuffleSplit(n_splits=repeats, test_size=n_test, random_state=random_state)
    return [(np.sort(tr), np.sort(te)) for tr, te in sss.split(np.zeros(y.size), y)]


@dataclass
class EvalResult:
    """Outcome of one classifier over the repeats of a protocol."""

    accuracies: list[float]
    confusion: np.ndarray  # (classes, classes), summed over repeats; rows: true class
    classes: np.ndarray
    fit_s: list[float]
    predict_s: list[float]
    over_time: dict[float, list[float]] = field(default_factory=dict)  # t [s] -> accuracies
    epoch_s: list[float] = field(default_factory=list)  # per-epoch times of torch models
    #: the first repeat's neuromorphic figures on its test samples (the encoder's spike rate,
    #: a spiking model's NeuroBench metrics: :mod:`.neurobench`), None where it has none
    neuromorphic: dict | None = None
    #: the last repeat's fitted estimator, where :func:`evaluate` was asked to keep it
    #: (``keep_model``; not in :meth:`to_json`)
    model: Any = field(default=None, repr=False, compare=False)

    @property
    def mean(self) -> float:
        return float(np.mean(self.accuracies))

    @property
    def std(self) -> float:
        """Standard deviation over the repeats (ddof = 0; 0 for a single repeat)."""
        return float(np.std(self.accuracies))

    def to_json(self) -> dict:
        return {
            "accuracy_mean": self.mean,
            "accuracy_std": self.std,
            "accuracies": [float(a) for a in self.accuracies],
            "confusion": self.confusion.tolist(),
            "classes": [c.item() if hasattr(c, "item") else c for c in self.classes],
            "fit_s": [round(t, 4) for t in self.fit_s],
            "predict_s": [round(t, 4) for t in self.predict_s],
            "over_time": {
                f"{t:g}": {
                    "mean": float(np.mean(a)),
                    "std": float(np.std(a)),
                    "accuracies": [float(v) for v in a],
                }
                for t, a in sorted(self.over_time.items())
            },
            "epoch_s_median": float(np.median(self.epoch_s)) if self.epoch_s else None,
            **({"neuromorphic": self.neuromorphic} if self.neuromorphic else {}),
        }


def time_steps(times_s: Sequence[float], rate_hz: float, n_time: int) -> list[tuple[float, int]]:
    """``(t, steps)`` pairs: the first ``steps = round(t * rate_hz)`` samples cover ``t`` s."""
    rate = positive("rate_hz", rate_hz, unit="Hz")
    out = []
    for t in times_s:
        t = positive("time point", t, unit="s")
        n = round(t * rate)
        if n < 1 or n > n_time:
            raise ConfigError(
                f"time point {t:g} s is {n} samples at {rate:g} Hz; valid: 1 to {n_time} "
                f"samples ({1 / rate:g} to {n_time / rate:g} s)"
            )
        out.append((float(t), int(n)))
    return out


def evaluate(
    make_estimator: Callable[[int], BaseEstimator],
    X: object,
    y: object,
    splits: Sequence[tuple[np.ndarray, np.ndarray]],
    *,
    times_s: Sequence[float] = (),
    rate_hz: float | None = None,
    anytime: bool = False,
    time_repeats: int | None = None,
    log: Callable[[str], None] | None = None,
    name: str = "",
    keep_model: bool = False,
) -> EvalResult:
    """Fit and score a fresh estimator on every split.

    Args:
        make_estimator: ``repeat -> estimator`` (a new, unfitted estimator seeded per repeat).
        X: ``(samples, time, channels)`` arrays (or ``(samples, features)`` matrices without
            ``times_s``); ``y``: labels.
        splits: from :func:`repeated_splits`.
        times_s: time points [s] of the accuracy-over-time curve (needs 3-D ``X``, ``rate_hz``).
        anytime: fit once; the decision at ``t`` is ``predict_upto`` (see the module docstring).
        time_repeats: how many of the splits also get the curve (default: all).
        keep_model: keep the last repeat's fitted estimator in ``EvalResult.model``.
    """
    x = np.asarray(X)
    if x.ndim not in (2, 3):
        raise ConfigError(f"X must be 2-D or 3-D, got shape {x.shape}")
    labels = check_labels(y, x.shape[0])
    classes = np.unique(labels)
    points: list[tuple[float, int]] = []
    if times_s:
        if x.ndim != 3 or rate_hz is None:
            raise ConfigError(
                "accuracy over time needs X of shape (samples, time, channels) and rate_hz"
            )
        points = time_steps(times_s, rate_hz, x.shape[1])
    n_curve = len(splits) if time_repeats is None else integer("time_repeats", time_repeats, 0)
    res = EvalResult([], np.zeros((classes.size, classes.size), np.int64), classes, [], [])
    for r, (tr, te) in enumerate(splits):
        est = make_estimator(r)
        t0 = time.perf_counter()
        est.fit(x[tr], labels[tr])
        t1 = time.perf_counter()
        pred = est.predict(x[te])
        res.predict_s.append(time.perf_counter() - t1)
        res.fit_s.append(t1 - t0)
        acc = float(np.mean(pred == labels[te]))
        res.accuracies.append(acc)
        res.confusion += confusion_matrix(labels[te], pred, labels=classes)
        res.epoch_s += _epoch_times(est)
        if r == 0 and x.ndim == 3:
            res.neuromorphic = neuromorphic_figures(est, x[te])
        if keep_model and r == len(splits) - 1:
            res.model = est
        if log and (len(splits) <= 20 or (r + 1) % max(1, len(splits) // 5) == 0):
            log(f"{name} repeat {r + 1}/{len(splits)}: accuracy {acc:.3f} (fit {t1 - t0:.1f} s)")
        if r >= n_curve:
            continue
        upto = _anytime(est, x[te]) if anytime and points else None
        for t, n in points:
            if n == x.shape[1]:
                a = acc
            elif upto is not None:
                a = float(np.mean(upto(t) == labels[te]))
            else:
                est_t = make_estimator(r)
                est_t.fit(x[tr, :n], labels[tr])
                a = float(np.mean(est_t.predict(x[te, :n]) == labels[te]))
            res.over_time.setdefault(t, []).append(a)
        if points and log:
            curve = ", ".join(f"{t:g}s {res.over_time[t][-1]:.2f}" for t, _ in points)
            log(f"{name} repeat {r + 1} over time: {curve}")
    return res


def _anytime(est: BaseEstimator, x_test: np.ndarray) -> Callable[[float], np.ndarray]:
    """``t -> predictions at t`` of an anytime model (a Pipeline's input steps run once)."""
    if hasattr(est, "steps"):
        final = est.steps[-1][1]
        z = est[:-1].transform(x_test)
    else:
        final, z = est, x_test
    if not hasattr(final, "predict_upto"):
        raise ConfigError(
            f"{type(final).__name__} has no predict_upto(X, t_s); it cannot be evaluated as an "
            f"anytime model"
        )
    return lambda t: final.predict_upto(z, t)


def _epoch_times(est: BaseEstimator) -> list[float]:
    """``epoch_times_s_`` of a torch model, also inside a Pipeline."""
    final = est.steps[-1][1] if hasattr(est, "steps") else est
    return list(getattr(final, "epoch_times_s_", []))
