"""A Recording's metadata is JSON data, normalised as a JSON round trip gives it back: the
copy it keeps (records.json_copy) against the round trip itself, on data that is JSON-shaped
already and on data that is not."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sim_tactile.errors import ConfigError
from sim_tactile.records import Recording, json_copy

_json = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=5),
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.tuples(inner, inner)
        | st.dictionaries(st.text(max_size=3) | st.integers(), inner, max_size=4)
    ),
    max_leaves=20,
)


def _same(a, b) -> bool:
    """Equal as JSON data and of the same types throughout (NaN equal to NaN)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and math.isnan(a):
        return math.isnan(b)
    return a == b


@settings(max_examples=150, deadline=None)
@given(_json)
def test_the_kept_metadata_is_what_a_json_round_trip_gives(obj):
    want = json.loads(json.dumps(obj))
    got = json_copy(obj)
    assert _same(got, want)


def test_the_kept_metadata_is_a_copy_and_what_is_not_json_is_refused():
    meta = {"x_pad_m": [0.1, 0.2], "fidelity": {"level": "L1", "warnings": ["a"]}}
    rec = Recording(np.zeros((2, 1)), np.arange(2.0), np.zeros((1, 3)), meta=meta)
    meta["x_pad_m"].append(9.0)
    meta["fidelity"]["warnings"].append("b")
    assert rec.meta == {"x_pad_m": [0.1, 0.2], "fidelity": {"level": "L1", "warnings": ["a"]}}
    kept = Recording(np.zeros((1, 1)), np.zeros(1), np.zeros((1, 3)), meta={"a": (1, 2.5)})
    assert kept.meta == {"a": [1, 2.5]}
    assert type(json_copy({"f": np.float64(0.5)})["f"]) is float
    for bad in ({"n": np.int64(3)}, {"s": {1, 2}}):
        with pytest.raises(ConfigError, match="JSON data"):
            Recording(np.zeros((1, 1)), np.zeros(1), np.zeros((1, 3)), meta=bad)
    loop: dict = {}
    loop["self"] = loop
    with pytest.raises(ConfigError, match="JSON data"):
        Recording(np.zeros((1, 1)), np.zeros(1), np.zeros((1, 3)), meta=loop)
