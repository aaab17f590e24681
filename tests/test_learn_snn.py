"""The spiking network: SRM kernels and spikes against plain references, learning a spike
pattern, determinism, the sklearn contract and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.base import clone

torch = pytest.importorskip("torch", reason="torch is the optional 'learn' extra")

from sim_tactile.errors import ConfigError  # noqa: E402
from sim_tactile.learn._srm import (  # noqa: E402
    alpha_kernel,
    refractory_constants,
    srm_spikes_numba,
    srm_spikes_torch,
)
from sim_tactile.learn.snn import SNNClassifier, causal_filter  # noqa: E402

#: float32 recursions: the refractory potential of the fast path and of the direct
#: convolution agree to float32 rounding over a few hundred steps.
REFR_RTOL = 1e-4
#: a tiny network on a clean two-pattern problem must classify every test sample.
PATTERN_ACCURACY = 1.0


def _refractory_reference(spikes: np.ndarray, theta, tau_ref, scale_ref) -> np.ndarray:
    """nu * o with nu[m] = -scale_ref theta (m / tau) exp(1 - m / tau), by direct sums."""
    n = spikes.size
    m = np.arange(n)
    nu = -scale_ref * theta * (m / tau_ref) * np.exp(1 - m / tau_ref)
    return np.array([np.sum(nu[1 : k + 1][::-1] * spikes[:k]) for k in range(n)])


def test_alpha_kernel_peaks_at_tau_with_height_one():
    k = alpha_kernel(4.0)
    assert k[0] == 0.0
    assert int(np.argmax(k)) == 4
    assert k[4] == pytest.approx(1.0)
    assert k[-1] < 1e-4  # cut once below 1e-4 of the peak


def test_fast_spike_path_equals_reference_and_refractory_is_the_kernel():
    rng = np.random.default_rng(0)
    u = torch.from_numpy(rng.normal(8.0, 6.0, size=(3, 7, 200)).astype(np.float32))
    theta, tau_ref, scale_ref = 10.0, 1.5, 2.0
    d, c = refractory_constants(theta, tau_ref, scale_ref)
    s_ref, r_ref = srm_spikes_torch(torch, u, theta, d, c)
    s_fast, r_fast = srm_spikes_numba(torch, u, theta, d, c)
    assert torch.equal(s_ref, s_fast)
    torch.testing.assert_close(r_ref, r_fast, rtol=0, atol=0)
    assert 0.05 < float(s_ref.mean()) < 0.6  # the test exercises spiking and refractoriness
    spikes = s_ref[1, 2].numpy().astype(np.float64)
    direct = _refractory_reference(spikes, theta, tau_ref, scale_ref)
    np.testing.assert_allclose(r_ref[1, 2].numpy(), direct, rtol=REFR_RTOL, atol=1e-4)
    # a spike fires exactly when the total potential reaches theta
    total = u + r_ref
    assert torch.equal(s_ref, (total >= theta).float())


def test_causal_filter_is_a_causal_convolution():
    x = torch.zeros(1, 1, 30)
    x[0, 0, 5] = 1.0
    k = torch.from_numpy(alpha_kernel(3.0))
    y = causal_filter(torch, x, k)[0, 0].numpy()
    assert np.all(y[:5] == 0)
    np.testing.assert_allclose(y[5:], k.numpy()[:25], rtol=1e-6)


def _pattern_problem(n_per_class=12, steps=60, channels=8, seed=0):
    """Class 0: channels 0-3 fire every 3rd step; class 1: channels 4-7; plus sparse noise."""
    rng = np.random.default_rng(seed)
    X, y = [], []
    for label in (0, 1):
        for _ in range(n_per_class):
            r = (rng.random((steps, channels)) < 0.02).astype(np.float32)
            phase = rng.integers(0, 3)
            chans = slice(0, 4) if label == 0 else slice(4, 8)
            r[phase::3, chans] = 1.0
            X.append(r)
            y.append(label)
    return np.stack(X), np.array(y)


def _tiny(**kw):
    base = dict(
        hidden=8,
        target_true=20,
        target_false=2,
        dt_s=0.01,
        tau_sr_s=0.02,
        epochs=25,
        batch_size=8,
        lr=0.05,
        weight_scale=20.0,
        random_state=3,
        device="cpu",
        num_threads=1,
    )
    return SNNClassifier(**{**base, **kw})


def test_learns_a_spike_pattern():
    X, y = _pattern_problem()
    Xt, yt = _pattern_problem(seed=1)
    clf = _tiny().fit(X, y)
    assert clf.loss_curve_[-1] < clf.loss_curve_[0]
    assert clf.score(Xt, yt) >= PATTERN_ACCURACY
    counts = clf.output_counts(Xt)
    assert counts.shape == (len(yt), 2)
    # the true class fires more than the other one, and near its target of 20 spikes
    assert np.all(counts[np.arange(len(yt)), yt] > counts[np.arange(len(yt)), 1 - yt])
    # decisions from the counts up to 0.3 s = 30 steps are those on the first 30 steps
    np.testing.assert_array_equal(clf.predict_upto(Xt, 0.3), clf.predict(Xt[:, :30]))


def test_same_seed_same_model_other_seed_other_model():
    X, y = _pattern_problem()
    a = _tiny(epochs=3).fit(X, y)
    b = _tiny(epochs=3).fit(X, y)
    c = _tiny(epochs=3, random_state=4).fit(X, y)
    for pa, pb in zip(a.module_.parameters(), b.module_.parameters(), strict=True):
        assert torch.equal(pa, pb)
    np.testing.assert_array_equal(a.decision_function(X), b.decision_function(X))
    assert not torch.equal(a.module_.fc1.weight, c.module_.fc1.weight)


def test_sklearn_contract():
    clf = _tiny(hidden=5)
    params = clf.get_params()
    assert params["hidden"] == 5 and params["target_true"] == 20
    twin = clone(clf)
    assert twin.get_params() == params and not hasattr(twin, "module_")
    from sklearn.exceptions import NotFittedError

    with pytest.raises(NotFittedError):
        clf.predict(np.zeros((2, 10, 8), np.float32))


@pytest.mark.parametrize(
    ("kwargs", "X", "y", "needle"),
    [
        ({}, np.zeros((4, 10, 3)), [0, 1, 0], "3 labels but X has 4 samples"),
        ({}, np.full((4, 10, 3), np.nan), [0, 1, 0, 1], "must be finite"),
        ({}, np.zeros((4, 10)), [0, 1, 0, 1], "shape \\(samples, time, channels\\)"),
        ({}, np.zeros((4, 10, 3)), [0, 0, 0, 0], "at least 2"),
        ({"target_true": 2, "target_false": 5}, np.zeros((4, 10, 3)), [0, 1, 0, 1], "exceed"),
        ({"tau_sr_s": -1.0}, np.zeros((4, 10, 3)), [0, 1, 0, 1], "tau_sr_s"),
        ({"device": "tpu"}, np.zeros((4, 10, 3)), [0, 1, 0, 1], "device"),
    ],
)
def test_bad_input_is_named(kwargs, X, y, needle):
    with pytest.raises(ConfigError, match=needle):
        _tiny(epochs=1, **kwargs).fit(X, y)


def test_surrogate_gradient_reaches_both_layers():
    X, y = _pattern_problem(n_per_class=4)
    clf = _tiny(epochs=1)
    clf.fit(X, y)
    net = clf.module_
    net.train()
    xf = clf._prepare(torch, X, torch.device("cpu"))
    out, _ = net(xf)
    out.sum().backward()
    assert net.fc1.weight.grad.abs().sum() > 0
    assert net.fc2.weight.grad.abs().sum() > 0


def test_counts_on_a_prefix_are_the_counts_up_to_that_step():
    """Causality: what the accuracy-over-time curve relies on."""
    X, y = _pattern_problem(n_per_class=3)
    clf = _tiny(epochs=2).fit(X, y)
    dev = torch.device("cpu")
    with torch.no_grad():
        full, _ = clf.module_(clf._prepare(torch, X, dev))
        for n in (1, 17, 45):
            part, _ = clf.module_(clf._prepare(torch, X[:, :n], dev))
            assert torch.equal(part.sum(-1), full[..., :n].sum(-1))
