"""Izhikevich neurons: accuracy against a tight ODE solution, fast path = reference, hard inputs."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sim_tactile.encoders import (
    IZHIKEVICH_PRESETS,
    NeuronStepWarning,
    izhikevich_spike_times,
    simulate_izhikevich,
)
from sim_tactile.encoders.izhikevich import simulate_reference
from sim_tactile.errors import ConfigError, PhysicsError

# Issue 5: first spike times within 0.5 ms of the ODE solution at the default step.
FIRST_SPIKE_TOL_S = 0.5e-3
# Measured worst error of all spike times at the default 0.1 ms rk4 step is ~0.005 ms
# (docs/spikes.md); 0.05 ms leaves a 10x margin and still fails a 1 ms-class scheme.
ALL_SPIKES_TOL_S = 0.05e-3
# Fast path vs plain reference: identical arithmetic, so equal up to rounding.
REF_TOL_S = 1e-12


def ode_spike_times(current, rate_hz, preset):
    """Spike times [s] from solve_ivp (DOP853, rtol = atol = 1e-12) with a terminal event at
    v = 30, restarted from the reset state; each held sample is its own integration interval."""
    p = IZHIKEVICH_PRESETS[preset]
    v, u = -65.0, p.b * -65.0
    h = 1000.0 / rate_hz
    spikes = []

    def at_peak(t, y, current_k):
        return y[0] - p.v_peak

    at_peak.terminal = True
    at_peak.direction = 1

    def rhs(t, y, current_k):
        return [0.04 * y[0] ** 2 + 5 * y[0] + 140 - y[1] + current_k, p.a * (p.b * y[0] - y[1])]

    for i, current_k in enumerate(current):
        t0, t1 = i * h, (i + 1) * h
        while t0 < t1:
            sol = solve_ivp(
                rhs,
                (t0, t1),
                [v, u],
                method="DOP853",
                rtol=1e-12,
                atol=1e-12,
                events=at_peak,
                args=(float(current_k),),
            )
            if sol.status == 1:
                t0 = float(sol.t_events[0][0])
                spikes.append(t0)
                v, u = p.c, float(sol.y_events[0][0][1]) + p.d
            else:
                v, u = float(sol.y[0, -1]), float(sol.y[1, -1])
                break
    return np.asarray(spikes) * 1e-3


def _sampled_input(seed, n, rate_hz):
    rng = np.random.default_rng(seed)
    return np.clip(15 + np.cumsum(rng.normal(0, 3, n)), 0, 40), rate_hz


CASES = {
    "constant": (np.full(30, 10.0), 100.0),  # 300 ms
    "strong": (np.full(20, 35.0), 100.0),  # 200 ms, FS at ~500 Hz
    "sampled": _sampled_input(0, 40, 100.0),  # 400 ms random walk, 10 ms hold
}


@pytest.mark.parametrize("preset", ["RS", "FS"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_spike_times_match_tight_ode_solution(preset, case):
    current, rate = CASES[case]
    ref = ode_spike_times(current, rate, preset)
    got = izhikevich_spike_times(current, rate, preset)
    assert ref.size > 3
    assert got.size == ref.size
    assert abs(got[0] - ref[0]) <= FIRST_SPIKE_TOL_S
    assert np.max(np.abs(got - ref)) <= ALL_SPIKES_TOL_S


def test_papers_one_ms_euler_is_available_and_less_accurate():
    current, rate = CASES["strong"]
    ref = ode_spike_times(current, rate, "FS")
    euler = izhikevich_spike_times(current, rate, "FS", 1e-3, scheme="euler")
    # docs/physics.md: forward Euler at 1 ms loses a large share of the fast-spiking spikes
    assert euler.size < 0.9 * ref.size


@pytest.mark.parametrize("scheme", ["rk4", "euler", "izhikevich2003"])
def test_fast_path_equals_plain_reference(scheme):
    current, rate = _sampled_input(1, 30, 100.0)
    for preset in ("RS", "FS"):
        fast = izhikevich_spike_times(current, rate, preset, scheme=scheme)
        ref = simulate_reference(current, rate, preset, scheme=scheme)
        assert fast.size == ref.size and fast.size > 0
        assert np.max(np.abs(fast - ref)) <= REF_TOL_S


def test_batch_equals_single_and_mixed_presets():
    rng = np.random.default_rng(2)
    cur = rng.uniform(0, 30, (4, 25))
    presets = ["RS", "FS", "SA", "RA"]
    batch = simulate_izhikevich(cur, 100.0, presets)
    for row, p, got in zip(cur, presets, batch, strict=True):
        assert np.array_equal(got, izhikevich_spike_times(row, 100.0, p))
    assert IZHIKEVICH_PRESETS["RS"] == IZHIKEVICH_PRESETS["SA"]
    assert IZHIKEVICH_PRESETS["FS"] == IZHIKEVICH_PRESETS["RA"]


@pytest.mark.parametrize("scheme", ["rk4", "euler", "izhikevich2003"])
def test_a_large_batch_equals_its_neurons_one_at_a_time(scheme):
    """The batch kernel (one pass over the neurons per step, the spikes regrouped by neuron
    at the end) against each neuron alone: the same spikes, bit for bit."""
    rng = np.random.default_rng(3)
    cur = rng.uniform(-2.0, 40.0, (60, 80))
    presets = [("RS", "FS")[i % 2] for i in range(60)]
    batch = simulate_izhikevich(cur, 100.0, presets, scheme=scheme)
    assert sum(b.size for b in batch) > 500
    for row, p, got in zip(cur, presets, batch, strict=True):
        assert np.array_equal(got, simulate_izhikevich(row, 100.0, p, scheme=scheme)[0])


def test_spikes_are_regrouped_by_neuron_in_time_order():
    """The counting sort of the kernels against numpy's stable argsort."""
    from sim_tactile.encoders._kernels import group_by_neuron

    rng = np.random.default_rng(4)
    who = rng.integers(0, 37, 2000)
    times = np.sort(rng.uniform(0, 10, 2000))
    got, counts = group_by_neuron(times, who, 1500, 40)
    order = np.argsort(who[:1500], kind="stable")
    assert np.array_equal(got, times[:1500][order])
    assert np.array_equal(counts, np.bincount(who[:1500], minlength=40))


def test_rest_gives_no_spikes_and_time_axis_is_zero_order_hold():
    assert izhikevich_spike_times(np.zeros(50), 100.0, "RS").size == 0
    # input switched on at sample 5 of 10 ms: no spike may come before 50 ms
    current = np.r_[np.zeros(5), np.full(15, 20.0)]
    t = izhikevich_spike_times(current, 100.0, "RS")
    assert t.size > 0 and t[0] > 0.05 and t[-1] <= 0.2


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_input_raises_config_error(bad):
    current = np.full(10, 5.0)
    current[3] = bad
    with pytest.raises(ConfigError, match="current"):
        izhikevich_spike_times(current, 100.0)


def test_bad_parameters_raise_config_error():
    with pytest.raises(ConfigError, match="preset"):
        izhikevich_spike_times(np.ones(5), 100.0, "XX")
    with pytest.raises(ConfigError, match="rate_hz"):
        izhikevich_spike_times(np.ones(5), -1.0)
    with pytest.raises(ConfigError, match="dt_s"):
        izhikevich_spike_times(np.ones(5), 100.0, "RS", 0.0)
    with pytest.raises(ConfigError, match="scheme"):
        izhikevich_spike_times(np.ones(5), 100.0, scheme="rk2")


def test_too_strong_input_warns_with_the_rate_limit():
    # a rate above 1/dt_s = 10 kHz needs several spikes per 0.1 ms step
    with pytest.warns(NeuronStepWarning, match="10000 Hz"):
        t = izhikevich_spike_times(np.full(5, 2e5), 100.0, "FS")
    assert t.size > 0.05 / 1e-4  # spikes are all reported, not capped at one per step
    with pytest.warns(NeuronStepWarning, match="1000 Hz"):
        izhikevich_spike_times(np.full(5, 3e3), 100.0, "FS", 1e-3, scheme="euler")


def test_strongly_negative_input_warns_with_the_stability_limit():
    with pytest.warns(NeuronStepWarning, match="stable for input >="):
        izhikevich_spike_times(np.full(20, -100.0), 100.0, "RS", 1e-3, scheme="euler")
    with warnings.catch_warnings():
        warnings.simplefilter("error", NeuronStepWarning)
        # the accurate default step is stable there and gives no spurious spikes
        assert izhikevich_spike_times(np.full(20, -100.0), 100.0, "RS").size == 0


def test_overflowing_input_raises_physics_error():
    with pytest.raises(PhysicsError, match="overflow"), warnings.catch_warnings():
        warnings.simplefilter("ignore", NeuronStepWarning)
        izhikevich_spike_times(np.full(3, 1e300), 100.0, "RS")
