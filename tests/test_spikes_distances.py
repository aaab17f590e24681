"""Spike-train distances: reference libraries, plain reference, closed forms, validation."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.spikes import _reference as R
from sim_tactile.spikes import distances as D

# Agreement with the reference libraries PySpike and Elephant.
LIB_TOL = 1e-9
# numba kernel vs plain-Python reference: same formulas in a different order; rounding only.
REF_TOL = 1e-12


def _random_cases(seed: int, n: int = 120, t0: float = 0.0, t1: float = 1.0):
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(n):
        a = np.sort(rng.uniform(t0, t1, rng.integers(0, 15)))
        b = np.sort(rng.uniform(t0, t1, rng.integers(0, 15)))
        cases.append((a, b))
    # trains on a coarse grid: many coincident spikes and spikes on both edges
    grid = np.linspace(t0, t1, 11)
    for _ in range(60):
        a = np.unique(rng.choice(grid, rng.integers(0, 8)))
        b = np.unique(rng.choice(grid, rng.integers(0, 8)))
        cases.append((a, b))
    return cases


def _edge_cases(t0: float = 0.0, t1: float = 1.0):
    span = t1 - t0
    a = t0 + span * np.array([0.1, 0.25, 0.6, 0.9])
    one = np.array([t0 + 0.3 * span])
    return [
        (np.empty(0), np.empty(0)),  # both empty
        (np.empty(0), one),  # empty vs one spike
        (one, one.copy()),  # identical single spikes
        (a, a.copy()),  # identical trains
        (a, a[[0, 2]]),  # coincident subset
        (np.array([t0]), np.array([t1])),  # spikes on the interval edges
        (np.array([t0, t1]), np.empty(0)),  # both edges vs empty
        (np.array([t0]), np.empty(0)),
        (np.array([t1]), one),
        (np.array([t0, t0 + 0.5 * span, t1]), np.array([t0 + 0.5 * span])),
    ]


WINDOWS = [(0.0, 1.0), (0.5, 2.0)]


@pytest.mark.parametrize("window", WINDOWS)
def test_isi_and_spike_distance_equal_pyspike(window):
    spk = pytest.importorskip("pyspike", reason="PySpike is a test extra (reference library)")
    t0, t1 = window
    worst_isi = worst_spike = 0.0
    for a, b in _random_cases(1, t0=t0, t1=t1) + _edge_cases(t0, t1):
        sa, sb = spk.SpikeTrain(a, [t0, t1]), spk.SpikeTrain(b, [t0, t1])
        worst_isi = max(worst_isi, abs(D.isi_distance(a, b, t0, t1) - spk.isi_distance(sa, sb)))
        worst_spike = max(
            worst_spike, abs(D.spike_distance(a, b, t0, t1) - spk.spike_distance(sa, sb))
        )
    assert worst_isi <= LIB_TOL
    assert worst_spike <= LIB_TOL


def _elephant_pair(func, a, b, **kw):
    neo = pytest.importorskip("neo")
    pq = pytest.importorskip("quantities")
    t_stop = max([1.0, *a, *b])
    trains = [
        neo.SpikeTrain(a * pq.s, t_stop=t_stop * pq.s),
        neo.SpikeTrain(b * pq.s, t_stop=t_stop * pq.s),
    ]
    return func(trains, **kw)[0, 1]


@pytest.mark.parametrize("q", [0.0, 0.7, 5.0, 24.0, 1e4])
def test_victor_purpura_equals_elephant(q):
    sd = pytest.importorskip(
        "elephant.spike_train_dissimilarity", reason="Elephant is a test extra (reference)"
    )
    pq = pytest.importorskip("quantities")
    worst = 0.0
    for a, b in _random_cases(2, n=60)[:90] + _edge_cases():
        ref = _elephant_pair(sd.victor_purpura_distance, a, b, cost_factor=q * pq.Hz)
        worst = max(worst, abs(D.victor_purpura(a, b, q) - ref))
    assert worst <= LIB_TOL


@pytest.mark.parametrize("tau", [1e-3, 0.02, 0.5, 10.0])
def test_van_rossum_equals_elephant_over_sqrt2(tau):
    sd = pytest.importorskip(
        "elephant.spike_train_dissimilarity", reason="Elephant is a test extra (reference)"
    )
    pq = pytest.importorskip("quantities")
    worst = 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Elephant warns when it clips rounding negatives
        for a, b in _random_cases(3, n=60)[:90] + _edge_cases():
            ref = _elephant_pair(sd.van_rossum_distance, a, b, time_constant=tau * pq.s)
            worst = max(worst, abs(D.van_rossum(a, b, tau) - ref / math.sqrt(2.0)))
    assert worst <= LIB_TOL


def test_victor_purpura_q_inf_counts_unmatched_spikes():
    # Elephant returns len(a) + len(b) at q = inf even for coincident spikes; the limit of the
    # definition is the number of spikes without an exact partner.
    a = np.array([0.1, 0.2, 0.3])
    b = np.array([0.1, 0.25, 0.3, 0.4])
    assert D.victor_purpura(a, b, math.inf) == 3.0
    assert D.victor_purpura(a, a, math.inf) == 0.0
    assert D.victor_purpura(a, b, 1e12) == 3.0


def test_kernels_equal_plain_reference():
    worst = {m: 0.0 for m in D.METRICS}
    for a, b in _random_cases(4, n=80) + _edge_cases():
        la, lb = list(a), list(b)
        pairs = {
            "victor_purpura": (D.victor_purpura(a, b, 7.0), R.victor_purpura(la, lb, 7.0)),
            "van_rossum": (D.van_rossum(a, b, 0.05), R.van_rossum(la, lb, 0.05)),
            "isi_distance": (D.isi_distance(a, b, 0, 1), R.isi_distance(la, lb, 0.0, 1.0)),
            "spike_distance": (D.spike_distance(a, b, 0, 1), R.spike_distance(la, lb, 0.0, 1.0)),
            "event_sync_distance": (D.event_sync_distance(a, b), R.event_sync_distance(la, lb)),
        }
        for name, (fast, ref) in pairs.items():
            # van Rossum's double sum cancels: compare squared values, scaled by the sums
            if name == "van_rossum":
                scale = 1.0 + a.size + b.size
                worst[name] = max(worst[name], abs(fast**2 - ref**2) / scale)
            else:
                worst[name] = max(worst[name], abs(fast - ref))
    for name, value in worst.items():
        assert value <= REF_TOL, name


def test_event_sync_fixed_tau_and_cap_equal_reference():
    for a, b in _random_cases(5, n=60):
        for tau, cap in [(0.01, None), (None, 0.02), (0.2, 0.05)]:
            fast = D.event_sync_distance(a, b, tau=tau, tau_max=cap)
            ref = R.event_sync_distance(list(a), list(b), tau, math.inf if cap is None else cap)
            assert abs(fast - ref) <= REF_TOL


@pytest.mark.parametrize("metric", D.METRICS)
def test_pairwise_and_cross_equal_single_calls(metric):
    rng = np.random.default_rng(6)
    trains = [np.sort(rng.uniform(0, 1, rng.integers(0, 20))) for _ in range(9)]
    params = {
        "victor_purpura": {"q": 10.0},
        "van_rossum": {"tau": 0.03},
        "isi_distance": {"t_start": 0.0, "t_end": 1.0},
        "spike_distance": {"t_start": 0.0, "t_end": 1.0},
        "event_sync_distance": {},
    }[metric]
    func = getattr(D, metric)
    m = D.pairwise(trains, metric, **params)
    c = D.cross(trains[:4], trains, metric, **params)
    assert m.shape == (9, 9) and c.shape == (4, 9)
    assert np.array_equal(m, m.T)
    assert np.all(np.diag(m) == 0.0)
    for i in range(9):
        for j in range(9):
            single = func(trains[i], trains[j], **params) if i != j else 0.0
            assert abs(m[i, j] - single) <= REF_TOL
            if i < 4:
                assert abs(c[i, j] - func(trains[i], trains[j], **params)) <= REF_TOL


def test_closed_forms():
    tau = 0.1
    assert D.van_rossum([0.3], [], tau) == pytest.approx(1 / math.sqrt(2), abs=1e-15)
    # two spikes dt apart: D^2 = 1 - exp(-dt / tau)
    dt = 0.05
    assert D.van_rossum([0.2], [0.2 + dt], tau) == pytest.approx(
        math.sqrt(1 - math.exp(-dt / tau)), rel=1e-14
    )
    a = np.array([0.1, 0.5])
    assert D.van_rossum(a, a, tau) == 0.0
    assert D.victor_purpura([0.1, 0.2, 0.3], [0.5], 0.0) == 2.0
    assert D.victor_purpura([0.1], [0.15], 10.0) == pytest.approx(0.5, abs=1e-15)
    assert D.victor_purpura([0.1], [0.5], 10.0) == 2.0  # shift dearer than delete + insert
    assert D.isi_distance([], [], 0, 1) == 0.0
    assert D.spike_distance(a, a, 0, 1) == 0.0
    # event synchronization: one spike each, within the window -> fully synchronous
    assert D.event_sync_distance([0.1], [0.12]) == 0.0
    assert D.event_sync_distance([0.1, 0.2], [0.1, 0.2]) == 0.0
    assert D.event_sync_distance([], []) == 0.0
    assert D.event_sync_distance([0.1], []) == 1.0
    # spikes further apart than half the local inter-spike intervals: no synchrony
    assert D.event_sync_distance([0.0, 0.1, 0.2], [1.0, 1.1]) == 1.0
    # 2 of 4 spikes of a matched (within tau = 0.5 / 2) by b's 2 spikes: Q = 2 / sqrt(8)
    q = 2 / math.sqrt(8)
    assert D.event_sync_distance([0.0, 1.0, 2.0, 3.0], [1.1, 3.05]) == pytest.approx(1 - q)


@pytest.mark.parametrize(
    ("call", "word"),
    [
        (lambda: D.victor_purpura([0.2, 0.1], [0.1], 1.0), "sorted"),
        (lambda: D.victor_purpura([np.nan], [0.1], 1.0), "finite"),
        (lambda: D.victor_purpura([0.1], [0.1], -1.0), "q"),
        (lambda: D.van_rossum([0.1], [0.1], 0.0), "tau"),
        (lambda: D.isi_distance([0.1], [2.0], 0.0, 1.0), "t_end"),
        (lambda: D.spike_distance([0.1], [0.2], 1.0, 1.0), "t_end"),
        (lambda: D.pairwise([[0.1]], "hamming"), "metric"),
        (lambda: D.pairwise([[0.1]], "victor_purpura", tau=1.0), "q"),
        (lambda: D.pairwise([[0.1]], "isi_distance"), "t_start"),
        (lambda: D.event_sync_distance([0.1], [0.2], tau=-1.0), "tau"),
    ],
)
def test_invalid_inputs_raise_config_error_naming_the_parameter(call, word):
    with pytest.raises(ConfigError, match=word):
        call()
