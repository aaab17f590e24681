"""The LSTM classifier: a separable sequence problem, the convolutional front, determinism,
the sklearn contract, bad input and the missing-torch error."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from sklearn.base import clone

torch = pytest.importorskip("torch", reason="torch is the optional 'learn' extra")

from sim_tactile.errors import ConfigError, MissingDependencyError  # noqa: E402
from sim_tactile.learn.lstm import LSTMClassifier  # noqa: E402

#: a clean problem (class = sign of a slow trend, plus noise) that a tiny LSTM must solve.
TREND_ACCURACY = 0.95


def _trend_problem(n=40, steps=20, channels=6, seed=0):
    rng = np.random.default_rng(seed)
    y = np.arange(n) % 2
    t = np.linspace(0, 1, steps)
    X = rng.normal(0, 0.3, size=(n, steps, channels))
    X[:, :, 0] += np.where(y[:, None] == 1, 1.0, -1.0) * t[None, :]
    return X.astype(np.float32) + 100.0, y  # an offset the standardisation must remove


def _tiny(**kw):
    base = dict(
        hidden_size=8, epochs=40, batch_size=8, lr=0.02, random_state=0, device="cpu", num_threads=1
    )
    return LSTMClassifier(**{**base, **kw})


def test_learns_a_separable_sequence_problem():
    X, y = _trend_problem()
    Xt, yt = _trend_problem(seed=1)
    clf = _tiny().fit(X, y)
    assert clf.score(Xt, yt) >= TREND_ACCURACY
    proba = clf.decision_function(Xt)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0, rtol=1e-5)


def test_convolutional_front_on_a_taxel_grid():
    X, y = _trend_problem(channels=6)
    Xt, yt = _trend_problem(channels=6, seed=1)
    clf = _tiny(grid_shape=(2, 3), conv_channels=4).fit(X, y)
    assert clf.module_.front is not None
    assert clf.score(Xt, yt) >= TREND_ACCURACY
    with pytest.raises(ConfigError, match="rows \\* cols = 6"):
        _tiny(grid_shape=(4, 4), epochs=1).fit(X, y)


def test_same_seed_same_predictions():
    X, y = _trend_problem()
    a = _tiny(epochs=3).fit(X, y)
    b = _tiny(epochs=3).fit(X, y)
    c = _tiny(epochs=3, random_state=1).fit(X, y)
    np.testing.assert_array_equal(a.decision_function(X), b.decision_function(X))
    assert not np.array_equal(a.decision_function(X), c.decision_function(X))


def test_sklearn_contract_and_string_labels():
    X, y = _trend_problem()
    labels = np.where(y == 1, "rough", "smooth")
    clf = _tiny(epochs=2)
    assert clone(clf).get_params() == clf.get_params()
    clf.fit(X, labels)
    assert set(clf.predict(X)) <= {"rough", "smooth"}
    assert len(clf.loss_curve_) == len(clf.epoch_times_s_) == 2
    with pytest.raises(ConfigError, match="fitted on 6"):
        clf.predict(X[:, :, :4])


@pytest.mark.parametrize(
    ("X", "y", "needle"),
    [
        (np.zeros((4, 5, 2)), [0, 1], "2 labels but X has 4 samples"),
        (np.where(np.eye(5)[None, :, :2] > 0, np.nan, 0.0).repeat(4, 0), [0, 1, 0, 1], "finite"),
    ],
)
def test_bad_input_is_named(X, y, needle):
    with pytest.raises(ConfigError, match=needle):
        _tiny(epochs=1).fit(X, y)


def test_missing_torch_gives_the_install_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "torch", None)  # makes `import torch` fail
    X, y = _trend_problem(n=4)
    with pytest.raises(MissingDependencyError, match=r"pip install 'sim-tactile\[learn\]'"):
        _tiny(epochs=1).fit(X, y)


def test_dropout_is_seeded_and_leaves_torch_global_generator_alone():
    X, y = _trend_problem()
    torch.manual_seed(123)
    before = torch.get_rng_state()
    a = _tiny(epochs=2, dropout=0.5).fit(X, y)
    assert torch.equal(torch.get_rng_state(), before)
    b = _tiny(epochs=2, dropout=0.5).fit(X, y)
    np.testing.assert_array_equal(a.decision_function(X), b.decision_function(X))
