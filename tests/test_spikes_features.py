"""Spike features (documented finite conventions) and multi-channel distance matrices."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.spikes import (
    FEATURES,
    SpikeFeatures,
    SpikeTrains,
    cross_multichannel,
    pairwise_multichannel,
    spike_features,
)
from sim_tactile.spikes import distances as D

EXACT = 1e-12  # hand-computed values of a few floating-point operations


def _sample():
    return SpikeTrains.from_lists(
        [[0.05, 0.15, 0.17, 0.95], [], [0.5], [0.2, 0.3]], 0.0, 1.0, ["a", "b", "c", "d"]
    )


def test_feature_values_and_conventions():
    m = spike_features([_sample()])
    assert m.shape == (1, 4 * len(FEATURES))
    f = {name: m[0, i :: len(FEATURES)] for i, name in enumerate(FEATURES)}
    assert f["count"].tolist() == [4, 0, 1, 2]
    assert np.allclose(f["rate_hz"], [4, 0, 1, 2], atol=EXACT)
    # 100 ms bins: channel a has bins 0 (1), 1 (2), 9 (1) -> mean of non-zero = 40/3 Hz
    assert f["rate_nonzero_hz"][0] == pytest.approx(40 / 3, abs=EXACT)
    assert f["rate_nonzero_hz"][1] == 0.0
    assert f["mean_isi_s"][0] == pytest.approx(0.3, abs=EXACT)
    assert f["mean_isi_s"][1] == 1.0 and f["mean_isi_s"][2] == 1.0  # window length
    assert f["inv_mean_isi_hz"][3] == pytest.approx(10.0, abs=1e-9)
    assert f["first_latency_s"].tolist() == pytest.approx([0.05, 1.0, 0.5, 0.2], abs=EXACT)
    isis = np.diff([0.05, 0.15, 0.17, 0.95])
    assert f["cv_isi"][0] == pytest.approx(isis.std() / isis.mean(), abs=EXACT)
    assert f["cv_isi"][1:].tolist() == [0.0, 0.0, 0.0]
    assert np.all(np.isfinite(m))


def test_fills_are_parameters_and_spike_at_window_end_counts():
    s = SpikeTrains.from_lists([[1.0], []], 0.0, 1.0)
    m = spike_features([s], ("rate_nonzero_hz", "mean_isi_s"), isi_fill_s=5.0)
    assert m[0].tolist() == [10.0, 5.0, 0.0, 5.0]


def test_transformer_names_and_validation():
    tf = SpikeFeatures(features=("count", "cv_isi")).fit([_sample()])
    assert tf.get_feature_names_out()[:3].tolist() == ["a:count", "a:cv_isi", "b:count"]
    assert tf.transform([_sample()] * 3).shape == (3, 8)
    with pytest.raises(ConfigError, match="features"):
        spike_features([_sample()], ("median",))
    with pytest.raises(ConfigError, match="bin_s"):
        spike_features([_sample()], bin_s=0.0)
    with pytest.raises(ConfigError, match="sorted"):
        SpikeTrains.from_lists([[0.3, 0.1]], 0.0, 1.0)
    with pytest.raises(ConfigError, match="after t_end"):
        SpikeTrains.from_lists([[2.0]], 0.0, 1.0)


def _samples(seed, n=6, n_ch=3):
    rng = np.random.default_rng(seed)
    return [
        SpikeTrains.from_lists(
            [np.sort(rng.uniform(0, 1, rng.integers(0, 12))) for _ in range(n_ch)], 0.0, 1.0
        )
        for _ in range(n)
    ]


@pytest.mark.parametrize("combine", ["sum", "mean", "rms", "max"])
def test_multichannel_combinations(combine):
    samples = _samples(1)
    stack = pairwise_multichannel(samples, "spike_distance", combine="none")
    assert stack.shape == (3, 6, 6)
    for c in range(3):
        single = D.pairwise([s.times[c] for s in samples], "spike", t_start=0.0, t_end=1.0)
        assert np.array_equal(stack[c], single)
    expected = {
        "sum": stack.sum(0),
        "mean": stack.mean(0),
        "rms": np.sqrt((stack**2).mean(0)),
        "max": stack.max(0),
    }[combine]
    m = pairwise_multichannel(samples, "spike_distance", combine=combine)
    assert np.allclose(m, expected, rtol=0, atol=EXACT)
    cross = cross_multichannel(samples[:2], samples, "vp", combine=combine, q=10.0)
    full = pairwise_multichannel(samples, "vp", combine=combine, q=10.0)
    assert np.allclose(cross, full[:2], rtol=0, atol=EXACT)


def test_multichannel_errors():
    with pytest.raises(ConfigError, match="t_start"):
        pairwise_multichannel([[np.array([0.1])], [np.array([0.2])]], "isi_distance")
    with pytest.raises(ConfigError, match="combine"):
        pairwise_multichannel(_samples(2), "vp", combine="median", q=1.0)
    uneven = [_samples(3, n_ch=2)[0], _samples(3, n_ch=3)[0]]
    with pytest.raises(ConfigError, match="channels"):
        pairwise_multichannel(uneven, "vp", q=1.0)
    assert math.isfinite(pairwise_multichannel(_samples(4), "es").sum())
