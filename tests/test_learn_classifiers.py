"""The classifier registry on a small synthetic problem with a known answer: three textures
that differ in vibration frequency and mean level, sampled like a 4-taxel sensor."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.base import clone

from sim_tactile.encoders.encodings import range_threshold_encoding
from sim_tactile.encoders.scaling import RangeScaler, SampleStandardizer
from sim_tactile.errors import ConfigError, UnknownNameError
from sim_tactile.learn.classifiers import (
    LearnContext,
    classifier_names,
    get_classifier,
    make_classifier,
)
from sim_tactile.learn.preprocess import SpikeCounts, SpikeRaster, TimeCollapse
from sim_tactile.spikes import SpikeTrains

RATE_HZ = 100.0
#: fraction of samples between two percentiles: off by at most a few of 11520 values
PERCENTILE_ATOL = 0.001
#: the three classes are separable by construction; a correct pipeline scores at least this
#: on held-out samples (one error in 18 allowed for the noisier spike-based ones).
SEPARABLE_ACCURACY = 0.94


def _textures(n_per_class=12, steps=80, channels=4, seed=0):
    """Class k: a sinusoid of 4 + 5 k Hz with random phase, level k, plus noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(steps) / RATE_HZ
    X, y = [], []
    for k in range(3):
        for _ in range(n_per_class):
            phase = rng.uniform(0, 2 * np.pi, size=channels)
            sig = np.sin(2 * np.pi * (4 + 5 * k) * t[:, None] + phase[None, :])
            X.append(sig + k + rng.normal(0, 0.1, size=(steps, channels)))
            y.append(k)
    return np.stack(X).astype(np.float32), np.array(y)


CTX = LearnContext(rate_hz=RATE_HZ, n_channels=4)


@pytest.mark.parametrize("name", ["svm-raw", "svm-spike", "svm", "lda", "knn", "src", "std-knn"])
def test_each_classifier_separates_the_textures(name):
    X, y = _textures()
    Xt, yt = _textures(n_per_class=6, seed=1)
    # 36 training samples: k = 3 neighbours; 8 features: codes of at most 2 atoms (a code of
    # 5 atoms in 8 dimensions can rebuild a sample from other classes' atoms)
    params = {"knn": {"n_neighbors": 3}, "std-knn": {"n_neighbors": 3}, "src": {"sparsity": 2}}
    ctx = LearnContext(rate_hz=RATE_HZ, n_channels=4, params=params)
    clf = make_classifier(name, ctx, random_state=0).fit(X, y)
    assert clf.score(Xt, yt) >= SEPARABLE_ACCURACY


def test_range_encoding_separates_levels():
    X, y = _textures()
    Xt, yt = _textures(n_per_class=6, seed=1)
    ctx = LearnContext(rate_hz=RATE_HZ, n_channels=4, encoder=range_threshold_encoding)
    clf = make_classifier("svm-spike", ctx).fit(X, y)
    assert clf.score(Xt, yt) >= SEPARABLE_ACCURACY
    scaler = clf.named_steps["scale"]
    np.testing.assert_allclose(scaler.low_, np.percentile(X.reshape(-1, 4), 1, axis=0))
    z = scaler.transform(X)
    # the 1st..99th percentile maps to [0, 3]: 98 % of the values, up to interpolation
    assert np.mean((z >= 0) & (z <= 3)) == pytest.approx(0.98, abs=PERCENTILE_ATOL)


def test_registry_names_and_errors():
    assert set(classifier_names()) == {
        "svm-raw",
        "svm-spike",
        "lstm",
        "snn",
        "svm",
        "lda",
        "knn",
        "std-knn",
        "src",
    }
    assert get_classifier("snn").anytime and get_classifier("snn").needs_torch
    assert not get_classifier("svm-raw").needs_torch
    with pytest.raises(UnknownNameError, match="'svn' is not known.*valid: svm-raw"):
        get_classifier("svn")


def test_builders_give_fresh_clonable_estimators_with_task_params():
    pytest.importorskip("torch")
    ctx = LearnContext(
        rate_hz=50.0,
        n_channels=60,
        grid_shape=(6, 10),
        params={"snn": {"hidden": 1200, "target_true": 70}},
    )
    snn = make_classifier("snn", ctx, random_state=7)
    final = snn.steps[-1][1]
    assert final.hidden == 1200 and final.target_true == 70 and final.random_state == 7
    assert final.dt_s == pytest.approx(0.02)
    assert snn.named_steps["raster"].dt_s == pytest.approx(0.02)
    lstm = make_classifier("lstm", ctx, random_state=1)
    assert tuple(lstm.grid_shape) == (6, 10)
    for name in classifier_names():
        est = make_classifier(name, CTX)
        assert clone(est).get_params().keys() == est.get_params().keys()
        assert make_classifier(name, CTX) is not est


@pytest.mark.slow
def test_snn_and_lstm_run_inside_their_pipelines():
    pytest.importorskip("torch")
    X, y = _textures(n_per_class=4, steps=40)
    tiny = {"epochs": 2, "num_threads": 1, "device": "cpu"}
    ctx = LearnContext(
        rate_hz=RATE_HZ,
        n_channels=4,
        params={
            "snn": {"hidden": 4, "target_true": 10, "target_false": 1, **tiny},
            "lstm": {"hidden_size": 4, **tiny},
        },
    )
    for name in ("snn", "lstm"):
        pred = make_classifier(name, ctx, random_state=0).fit(X, y).predict(X[:, :20])
        assert pred.shape == (12,) and set(pred) <= {0, 1, 2}


def test_nan_features_are_rejected_with_their_position():
    X, y = _textures(n_per_class=3)
    X[2, 5, 1] = np.nan
    for name in ("svm-raw", "svm-spike"):
        with pytest.raises(ConfigError, match=r"\(2, 5, 1\)"):
            make_classifier(name, CTX).fit(X, y)


def test_preprocessing_transformers():
    X, _ = _textures(n_per_class=2)
    np.testing.assert_allclose(TimeCollapse().fit_transform(X), X.mean(axis=1), rtol=1e-6)
    np.testing.assert_allclose(TimeCollapse("sum").fit_transform(X), X.sum(axis=1), rtol=1e-5)
    z = SampleStandardizer().fit_transform(X)
    np.testing.assert_allclose(z.mean(axis=1), 0.0, atol=1e-6)
    np.testing.assert_allclose(z.std(axis=1), 1.0, rtol=1e-6)
    assert np.all(SampleStandardizer().fit_transform(np.ones((1, 5, 2))) == 0.0)
    trains = [SpikeTrains.from_lists([[0.0, 0.011, 0.0119, 0.05], [0.049]], 0.0, 0.05)]
    r = SpikeRaster(dt_s=0.01).fit_transform(trains)
    assert r.shape == (1, 5, 2)
    np.testing.assert_array_equal(r[0, :, 0], [1, 1, 0, 0, 1])  # two spikes in a step: one
    np.testing.assert_array_equal(r[0, :, 1], [0, 0, 0, 0, 1])
    np.testing.assert_array_equal(SpikeCounts().fit_transform(trains), [[4, 1]])
    with pytest.raises(ConfigError, match="must be a SpikeTrains"):
        SpikeCounts().fit_transform([np.zeros(3)])
    with pytest.raises(ConfigError, match="hi_pct = 5 must exceed lo_pct = 10"):
        RangeScaler(10, 5).fit(X)
    flat = RangeScaler().fit(np.ones((2, 5, 1)))
    assert np.all(flat.transform(np.full((1, 5, 1), 3.0)) == 2.0)  # constant channel: shifted
