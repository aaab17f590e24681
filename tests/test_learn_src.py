"""Sparse representation classification: a planted sparse code, separable classes, and
scikit-learn's estimator checks."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.utils.estimator_checks import parametrize_with_checks

from sim_tactile.errors import ConfigError
from sim_tactile.learn.src import SRCClassifier

#: OMP recovers an exact sparse code up to floating-point rounding.
CODE_ATOL = 1e-8


def _dictionary(rng, n_features=40, per_class=10, n_classes=3):
    atoms = rng.normal(size=(n_classes * per_class, n_features))
    labels = np.repeat(np.arange(n_classes), per_class)
    return atoms, labels


def test_planted_sparse_code_is_recovered_and_classified():
    rng = np.random.default_rng(0)
    atoms, labels = _dictionary(rng)
    clf = SRCClassifier(sparsity=3).fit(atoms, labels)
    unit = atoms / np.linalg.norm(atoms, axis=1, keepdims=True)
    support = np.array([21, 24, 28])  # three atoms of class 2
    weights = np.array([1.0, -0.5, 0.25])
    y = weights @ unit[support]
    code = clf.codes(y[None])[0]
    scale = np.linalg.norm(y)  # the test sample is normalised before coding
    np.testing.assert_array_equal(np.flatnonzero(np.abs(code) > CODE_ATOL), support)
    np.testing.assert_allclose(code[support] * scale, weights, atol=CODE_ATOL)
    assert clf.predict(y[None])[0] == 2
    res = clf.residuals(y[None])[0]
    assert res[2] < CODE_ATOL and res[0] > 0.5 and res[1] > 0.5


def test_separable_classes_and_string_labels():
    rng = np.random.default_rng(1)
    centres = rng.normal(scale=5.0, size=(4, 12))
    X = np.concatenate([c + rng.normal(scale=0.3, size=(30, 12)) for c in centres])
    y = np.repeat(np.array(["a", "b", "c", "d"]), 30)
    idx = rng.permutation(len(y))
    tr, te = idx[:80], idx[80:]
    clf = SRCClassifier(sparsity=5).fit(X[tr], y[tr])
    assert clf.score(X[te], y[te]) == 1.0
    assert set(clf.classes_) == {"a", "b", "c", "d"}


def test_bad_input_names_the_problem():
    X = np.ones((4, 3))
    with pytest.raises(ConfigError, match="inconsistent numbers of samples"):
        SRCClassifier().fit(X, [0, 1, 0])
    X_nan = X.copy()
    X_nan[1, 2] = np.nan
    with pytest.raises(ConfigError, match="NaN"):
        SRCClassifier().fit(X_nan, [0, 1, 0, 1])
    with pytest.raises(ConfigError, match="sparsity"):
        SRCClassifier(sparsity=0).fit(X, [0, 1, 0, 1])
    clf = SRCClassifier().fit(np.eye(4), [0, 1, 0, 1])
    with pytest.raises(ConfigError, match="4 features"):
        clf.predict(np.ones((2, 3)))


@parametrize_with_checks([SRCClassifier()])
def test_sklearn_estimator_checks(estimator, check):
    check(estimator)
