"""Threshold encoding, LIF / ALIF, the sklearn transformers and the raster plot."""

from __future__ import annotations

import math

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.neighbors import KNeighborsClassifier
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import LinearSVC

from sim_tactile.encoders import (
    IzhikevichEncoder,
    LIFEncoder,
    LIFParams,
    ThresholdEncoder,
    alif_params,
    izhikevich_spike_times,
    simulate_lif,
    threshold_encode,
)
from sim_tactile.encoders.lif import simulate_reference as lif_reference
from sim_tactile.errors import ConfigError
from sim_tactile.spikes import SpikeFeatures, SpikeTrainDistances, SpikeTrains

REF_TOL_S = 1e-12  # fast path vs plain reference (same arithmetic)
# LIF is exact between events; crossings are bisected to 1e-10 of the 0.1 ms step.
LIF_EXACT_TOL_S = 1e-9
# The calibrated rate is a spike count over 1 s: it may exceed the target by one spike.
RATE_TOL_HZ = 1.0


def test_threshold_encoding_up_down_and_max():
    y = np.array([0.0, 0.6, 1.2, 0.8, 0.3, 1.5, 0.1])
    out = threshold_encode(y, 10.0, [0.5, 1.0])
    assert len(out) == 5  # 2K + 1
    up0, up1, down0, down1, peak = (np.round(t * 10).astype(int) for t in out)
    assert up0.tolist() == [1, 5] and down0.tolist() == [4, 6]
    assert up1.tolist() == [2, 5] and down1.tolist() == [3, 6]
    assert peak.tolist() == [5]  # global maximum
    local = threshold_encode(y, 10.0, [0.5, 1.0], extra="local_max")[-1]
    assert np.round(local * 10).astype(int).tolist() == [2, 5]


def test_threshold_up_and_down_alternate_on_random_signals():
    rng = np.random.default_rng(0)
    y = rng.normal(size=(500, 3))
    enc = ThresholdEncoder(rate_hz=100.0, n_thresholds=3).fit(y[None])
    (trains,) = enc.transform(y[None])
    assert trains.n_channels == 3 * 7
    for c in range(3):
        for k in range(3):
            up, down = trains.times[c * 7 + k], trains.times[c * 7 + 3 + k]
            merged = np.sort(np.r_[up, down])
            kinds = np.isin(merged, up)
            assert abs(up.size - down.size) <= 1
            assert np.all(kinds[1:] != kinds[:-1])  # strictly alternating


def test_threshold_encoder_fixed_and_fitted_thresholds():
    x = np.linspace(0, 1, 101)[None, :, None] * np.array([1.0, 10.0])
    enc = ThresholdEncoder(rate_hz=100.0, n_thresholds=2).fit(x)
    assert np.allclose(enc.thresholds_, [[1 / 3, 2 / 3], [10 / 3, 20 / 3]])
    fixed = ThresholdEncoder(rate_hz=100.0, thresholds=[0.5]).fit(x)
    assert fixed.thresholds_.shape == (2, 1)
    assert fixed.channel_names_[:3] == ["ch0:up0", "ch0:down0", "ch0:max"]
    with pytest.raises(ConfigError, match="extra"):
        ThresholdEncoder(extra="mean").fit(x)


def test_lif_matches_closed_form_isi_and_reference():
    p = LIFParams(tau_m_s=0.02, v_th=1.0, refractory_s=0.002)
    drive = 1.5
    isi = p.refractory_s + p.tau_m_s * math.log(drive / (drive - p.v_th))
    t = simulate_lif(np.full(50, drive), 100.0, p)[0]  # 0.5 s
    assert t.size == int((0.5 - t[0]) / isi) + 1
    assert np.max(np.abs(np.diff(t) - isi)) <= LIF_EXACT_TOL_S
    for params in (p, alif_params(tau_m_s=0.01, refractory_s=0.001)):
        cur = np.random.default_rng(3).uniform(0, 4, 40)
        fast = simulate_lif(cur, 100.0, params)[0]
        ref = lif_reference(cur, 100.0, params)
        assert fast.size == ref.size > 0
        assert np.max(np.abs(fast - ref)) <= REF_TOL_S


def test_adaptive_lif_slows_down():
    cur = np.full(100, 2.0)
    plain = simulate_lif(cur, 100.0, LIFParams())[0]
    adaptive = simulate_lif(cur, 100.0, alif_params())[0]
    assert adaptive.size < plain.size
    isis = np.diff(adaptive)
    assert isis[-1] > isis[0]


def _dataset(seed=0, n_per_class=6, n_t=100, n_ch=3):
    rng = np.random.default_rng(seed)
    t = np.arange(n_t) / 100.0
    X, y = [], []
    for label, freq in enumerate((2.0, 6.0)):
        for _ in range(n_per_class):
            phase = rng.uniform(0, 2 * np.pi)
            base = 0.5 + 0.5 * np.sin(2 * np.pi * freq * t + phase)
            X.append(base[:, None] + 0.05 * rng.normal(size=(n_t, n_ch)))
            y.append(label)
    return np.asarray(X), np.asarray(y)


def test_izhikevich_encoder_gain_modes_and_calibration():
    X, _ = _dataset()
    enc = IzhikevichEncoder(
        rate_hz=100.0,
        preset=["RS", "FS", "RS"],
        normalize="minmax",
        max_rate_hz=[100.0, 200.0, 100.0],
    ).fit(X)
    level = 1.0  # minmax: the largest normalised training value
    for c, (preset, target) in enumerate([("RS", 100.0), ("FS", 200.0), ("RS", 100.0)]):
        spikes = izhikevich_spike_times(np.full(100, enc.gain_[c] * level), 100.0, preset)
        assert target <= spikes.size <= target + RATE_TOL_HZ
    trains = enc.transform(X)
    assert len(trains) == len(X) and isinstance(trains[0], SpikeTrains)
    assert trains[0].t_end == pytest.approx(1.0)
    paper002 = IzhikevichEncoder(rate_hz=100.0, normalize="minmax", gain=15.0).fit(X)
    assert np.allclose(paper002.gain_, 15.0)
    assert paper002.currents(X).max() == pytest.approx(15.0)


def test_pipelines_are_deterministic_and_classify():
    X, y = _dataset()
    pipe = make_pipeline(
        IzhikevichEncoder(rate_hz=100.0, normalize="minmax", gain=15.0),
        SpikeFeatures(features=("rate_hz", "mean_isi_s")),
        StandardScaler(),
        LinearSVC(),
    )
    a = clone(pipe).fit(X, y).predict(X)
    b = clone(pipe).fit(X, y).predict(X)
    assert np.array_equal(a, b)
    knn = make_pipeline(
        ThresholdEncoder(rate_hz=100.0),
        SpikeTrainDistances(metric="victor_purpura", metric_params={"q": 20.0}),
        KNeighborsClassifier(n_neighbors=1, metric="precomputed"),
    )
    knn.fit(X, y)
    assert knn.score(X, y) == 1.0  # each sample is its own nearest neighbour (distance 0)
    lif = make_pipeline(
        LIFEncoder(rate_hz=100.0, gain=3.0), SpikeFeatures(), StandardScaler(), LinearSVC()
    )
    assert lif.fit(X, y).predict(X).shape == y.shape


def test_encoders_reject_bad_input():
    X, _ = _dataset()
    bad = X.copy()
    bad[0, 3, 1] = np.nan
    with pytest.raises(ConfigError, match="X must be finite"):
        IzhikevichEncoder().fit(bad)
    with pytest.raises(ConfigError, match="shape"):
        ThresholdEncoder().fit(np.zeros((2, 3, 4, 5)))
    enc = IzhikevichEncoder().fit(X)
    with pytest.raises(ConfigError, match="channels"):
        enc.transform(X[:, :, :2])


def test_raster_plot_writes_png(tmp_path):
    from sim_tactile.spikes.plot import raster

    X, _ = _dataset(n_per_class=1)
    trains = ThresholdEncoder(rate_hz=100.0).fit(X).transform(X)[0]
    out = tmp_path / "raster.png"
    fig = raster(trains, signal=X[0], rate_hz=100.0, title="threshold", out=out)
    assert out.stat().st_size > 1000
    assert len(fig.axes) == 2
