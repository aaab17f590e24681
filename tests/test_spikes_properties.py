"""Metric axioms of the spike-train distances, as hypothesis property tests."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from sim_tactile.spikes import distances as D

# Rounding slack for the axioms: the distances are sums of O(50) terms of size <= O(50).
AXIOM_TOL = 1e-9

T0, T1 = 0.0, 1.0
# spike times on a 1 ms grid (many exact coincidences) or anywhere in the window
times = st.one_of(
    st.integers(0, 1000).map(lambda k: k / 1000.0),
    st.floats(T0, T1, allow_nan=False, allow_infinity=False),
)
trains = st.lists(times, max_size=25).map(lambda xs: np.sort(np.asarray(xs, dtype=float)))

CALLS = {
    "victor_purpura": lambda a, b: D.victor_purpura(a, b, 15.0),
    "van_rossum": lambda a, b: D.van_rossum(a, b, 0.02),
    "isi_distance": lambda a, b: D.isi_distance(a, b, T0, T1),
    "spike_distance": lambda a, b: D.spike_distance(a, b, T0, T1),
    "event_sync_distance": lambda a, b: D.event_sync_distance(a, b),
}
METRICS_PROPER = ("victor_purpura", "van_rossum")
SETTINGS = settings(max_examples=150, deadline=None)


@SETTINGS
@given(a=trains, b=trains)
def test_non_negative_and_symmetric(a, b):
    for name, f in CALLS.items():
        ab, ba = f(a, b), f(b, a)
        assert ab >= 0.0, name
        assert abs(ab - ba) <= AXIOM_TOL, name


@SETTINGS
@given(a=trains)
def test_zero_on_identical_trains(a):
    for name, f in CALLS.items():
        assert f(a, a.copy()) <= AXIOM_TOL, name


@SETTINGS
@given(a=trains, b=trains, c=trains)
def test_triangle_inequality_of_the_metrics(a, b, c):
    for name in METRICS_PROPER:
        f = CALLS[name]
        assert f(a, c) <= f(a, b) + f(b, c) + AXIOM_TOL, name


@SETTINGS
@given(a=trains, b=trains)
def test_bounded_distances_stay_in_unit_interval(a, b):
    for name in ("isi_distance", "spike_distance", "event_sync_distance"):
        assert CALLS[name](a, b) <= 1.0 + AXIOM_TOL, name
