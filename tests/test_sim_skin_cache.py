"""The dense skin's arrays kept in the artefact cache from one slide to the next."""

from __future__ import annotations

import numpy as np

from sim_tactile.cache import ArtefactCache
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.protocol import Protocol
from sim_tactile.sim.simulate import simulate
from sim_tactile.sim.skin import CACHE_MIN_NODES, CoupledSkin, make_skin


def _files(cache: ArtefactCache) -> list:
    return sorted(cache.root.rglob("*.skin.npz"))


def test_the_cached_arrays_are_the_computed_ones_and_their_key_holds_the_skin(tmp_path):
    cache = ArtefactCache(tmp_path)
    finger = get_sensor("grid3x3").finger
    grid = skin_grid(finger, 0.45e-3)
    assert grid.n >= CACHE_MIN_NODES
    plain = make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0)
    first = make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0, cache=cache)
    again = make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0, cache=cache)
    assert isinstance(again, CoupledSkin) and len(_files(cache)) == 1
    for s in (first, again):
        assert s.C.tobytes() == plain.C.tobytes() and s.K.tobytes() == plain.K.tobytes()
        assert s.describe() == plain.describe() and s.symmetric
    # another skin (softer), another grid: other keys, never the stored arrays
    soft = finger.__class__(**{**finger.__dict__, "young_pa": finger.young_pa / 2})
    other = make_skin("L1", grid, soft, winkler_k_pa_per_m=1.0, cache=cache)
    np.testing.assert_allclose(other.C, 2 * plain.C, rtol=1e-12)
    make_skin("L1", skin_grid(finger, 0.44e-3), finger, winkler_k_pa_per_m=1.0, cache=cache)
    assert len(_files(cache)) == 3
    # an unreadable entry is computed again and stored over
    _files(cache)[0].write_bytes(b"not an npz")
    for f in (finger, soft):
        s = make_skin("L1", grid, f, winkler_k_pa_per_m=1.0, cache=cache)
        ref = make_skin("L1", grid, f, winkler_k_pa_per_m=1.0)
        assert s.C.tobytes() == ref.C.tobytes()


def test_a_slide_is_the_same_bit_for_bit_whether_its_skin_came_from_the_cache(tmp_path):
    cache = ArtefactCache(tmp_path)
    kw = dict(
        protocol=Protocol(duration_s=0.3),
        ideal=True,
        pitch_m=0.45e-3,
    )
    a = simulate("finger7/bumps-3x3", "grid3x3", **kw).recording
    b = simulate("finger7/bumps-3x3", "grid3x3", cache=cache, **kw).recording
    c = simulate("finger7/bumps-3x3", "grid3x3", cache=cache, **kw).recording
    assert len(_files(cache)) == 1
    assert a.data.max() > 0
    for r in (b, c):
        assert r.data.tobytes() == a.data.tobytes()
        assert r.meta["normal_force_n"] == a.meta["normal_force_n"]
