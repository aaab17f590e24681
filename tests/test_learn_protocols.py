"""Evaluation protocols: split rules, repeats, confusion matrices, accuracy over time."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin

from sim_tactile.errors import ConfigError
from sim_tactile.learn.protocols import SplitSpec, evaluate, repeated_splits, time_steps


def test_split_spec_parsing():
    assert SplitSpec.parse("7:3") == SplitSpec("ratio", 7, 3)
    assert SplitSpec.parse(" 9 : 1 ") == SplitSpec("ratio", 9, 1)
    assert SplitSpec.parse("24/8") == SplitSpec("counts", 24, 8)
    assert str(SplitSpec.parse("10/200")) == "10/200 per class"
    for bad in ("7-3", "0:3", "10/0", "", "a:b"):
        with pytest.raises(ConfigError, match="split"):
            SplitSpec.parse(bad)


def test_ratio_splits_are_stratified_disjoint_and_seeded():
    y = np.repeat(np.arange(20), 50)
    splits = repeated_splits(y, "7:3", 5, random_state=1)
    assert len(splits) == 5
    for tr, te in splits:
        assert len(tr) == 700 and len(te) == 300
        assert not set(tr) & set(te)
        np.testing.assert_array_equal(np.bincount(y[te]), np.full(20, 15))
    assert not np.array_equal(splits[0][1], splits[1][1])
    again = repeated_splits(y, "7:3", 5, random_state=1)
    for (a, b), (c, d) in zip(splits, again, strict=True):
        np.testing.assert_array_equal(a, c)
        np.testing.assert_array_equal(b, d)


def test_per_class_count_splits():
    y = np.repeat(np.arange(7), 32)
    for tr, te in repeated_splits(y, "24/8", 3, random_state=0):
        np.testing.assert_array_equal(np.bincount(y[tr]), np.full(7, 24))
        np.testing.assert_array_equal(np.bincount(y[te]), np.full(7, 8))
        assert not set(tr) & set(te)


@pytest.mark.parametrize(
    ("y", "split", "needle"),
    [
        (np.array([0] * 32 + [1] * 20), "24/8", "class 1 has 20 samples but split 24/8"),
        (np.array([0] * 10 + [1]), "7:3", "class 1 has 1 sample"),
        (np.zeros(10, int), "7:3", "at least 2"),
        (np.array([0, 1] * 2), "9:1", "at least 2 per class"),
    ],
)
def test_too_small_classes_are_named(y, split, needle):
    with pytest.raises(ConfigError, match=needle):
        repeated_splits(y, split, 2)


class _FirstStepSign(ClassifierMixin, BaseEstimator):
    """Predicts 1 when the last sample of channel 0 is positive; counts its fits."""

    fits = 0

    def fit(self, X, y):
        _FirstStepSign.fits += 1
        self.classes_ = np.unique(y)
        return self

    def predict(self, X):
        return (np.asarray(X)[:, -1, 0] > 0).astype(int)


class _Anytime(_FirstStepSign):
    """A causal model at 10 Hz: its decision at t reads the first round(10 t) steps."""

    def predict_upto(self, X, t_s):
        return self.predict(np.asarray(X)[:, : round(t_s * 10)])


def test_evaluate_accuracy_confusion_and_over_time():
    rng = np.random.default_rng(0)
    y = np.repeat([0, 1], 20)
    X = rng.normal(size=(40, 10, 2))
    X[:, 5:, 0] = np.where(y == 1, 1.0, -1.0)[:, None]  # informative from step 5 on
    splits = repeated_splits(y, "5:5", 3, random_state=0)
    _FirstStepSign.fits = 0
    res = evaluate(lambda r: _FirstStepSign(), X, y, splits, times_s=(0.3, 1.0), rate_hz=10.0)
    assert res.accuracies == [1.0, 1.0, 1.0]
    assert res.confusion.sum() == 3 * 20 and np.trace(res.confusion) == 60
    assert res.over_time[1.0] == [1.0] * 3
    assert all(0.0 <= a <= 1.0 for a in res.over_time[0.3])
    assert _FirstStepSign.fits == 3 + 3  # retrained for the 0.3 s prefix of each repeat
    _FirstStepSign.fits = 0
    res = evaluate(
        lambda r: _Anytime(),
        X,
        y,
        splits,
        times_s=(0.3, 0.6),
        rate_hz=10.0,
        anytime=True,
        time_repeats=1,
    )
    assert _FirstStepSign.fits == 3 and len(res.over_time[0.3]) == 1  # no refits
    assert res.over_time[0.6] == [1.0]  # step 5 (informative) is within the first 0.6 s
    with pytest.raises(ConfigError, match="no predict_upto"):
        evaluate(
            lambda r: _FirstStepSign(), X, y, splits, times_s=(0.3,), rate_hz=10.0, anytime=True
        )
    doc = res.to_json()
    assert doc["accuracy_mean"] == 1.0 and doc["accuracy_std"] == 0.0


def test_evaluate_and_time_points_reject_bad_input():
    y = np.array([0, 1] * 5)
    splits = repeated_splits(y, "5:5", 1)
    with pytest.raises(ConfigError, match="9 labels but X has 10 samples"):
        evaluate(lambda r: _FirstStepSign(), np.zeros((10, 4, 1)), y[:9], splits)
    with pytest.raises(ConfigError, match="time point 2 s"):
        time_steps([2.0], 10.0, 10)
    with pytest.raises(ConfigError, match="needs X of shape"):
        evaluate(lambda r: _FirstStepSign(), np.zeros((10, 4)), y, splits, times_s=(0.1,))
