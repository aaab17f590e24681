"""The dense skin's arrays kept in the artefact cache from one slide to the next."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.cache import ArrayMemo, ArtefactCache, forget_process_memos
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.skin import models as skin_module
from sim_tactile.sim.skin.models import CACHE_MIN_NODES, CoupledSkin, make_skin
from sim_tactile.sim.slide import simulate


@pytest.fixture(autouse=True)
def _fresh(fresh_memo):
    """Each test starts with nothing kept in the process (the memo outlives a test)."""


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


def test_a_worker_keeps_the_arrays_read_only_by_their_key_and_drops_the_oldest(tmp_path):
    """The second slide of a scene in a process takes the first's arrays from memory (the
    same objects, read-only, so no slide changes what the next one reads); the memo keeps
    what fits its byte budget, the least recently used dropped first."""
    finger = get_sensor("grid3x3").finger
    grid = skin_grid(finger, 0.43e-3)
    a = make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0, cache=ArtefactCache(tmp_path / "x"))
    b = make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0, cache=ArtefactCache(tmp_path / "y"))
    assert b.C is a.C and b.K is a.K and not a.C.flags.writeable
    assert not _files(ArtefactCache(tmp_path / "y"))  # not even read from disk
    memo = ArrayMemo(max_bytes=2 * 800)
    one, two, three = (np.zeros(100) for _ in range(3))  # 800 bytes each
    memo.put("1", (one, "a"))
    memo.put("2", (two, "b"))
    assert memo.get("1")[0] is one  # now the most recent
    memo.put("3", (three, "c"))
    assert memo.get("2") is None and memo.get("1") is not None and len(memo) == 2
    assert memo.put("big", (np.zeros(1000),)) and memo.get("big") is None  # over the budget


def test_arrays_cached_on_another_blas_kernel_are_not_served(tmp_path, monkeypatch):
    """Another CPU's BLAS kernel computes the arrays bit-different in their last places: the
    key holds the kernel, so a cache written there is not read here."""
    from sim_tactile.hashing import blas_kernel

    cache = ArtefactCache(tmp_path)
    finger = get_sensor("grid3x3").finger
    grid = skin_grid(finger, 0.45e-3)
    assert blas_kernel() != ""
    make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0, cache=cache)
    forget_process_memos()
    monkeypatch.setattr(skin_module, "blas_kernel", lambda: "AnotherCore")
    make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0, cache=cache)
    assert len(_files(cache)) == 2
