"""Every cache entry proves what it is (sim_tactile/cache.py): an entry altered, truncated,
moved under another key or unreadable is never served; it is made again, with a warning
that names the file. A cache that cannot be written says so in one line."""

from __future__ import annotations

import errno
import io
import shutil

import numpy as np
import pytest

from sim_tactile import cache as cache_module
from sim_tactile.cache import SUM_SUFFIX, ArtefactCache
from sim_tactile.errors import CacheError, CacheWarning
from sim_tactile.plates import build
from sim_tactile.plates.make.build import artefact_key
from sim_tactile.plates.read.presets import get_plate
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.slides import SlideJob, run_slides
from sim_tactile.slides.jobs import SLIDE_EXT

KEY_A, KEY_B = "a" * 64, "b" * 64


def _entry(cache: ArtefactCache, key: str, ext: str = "bin"):
    p = cache.path(key, ext)
    return p, p.with_name(p.name + SUM_SUFFIX)


def test_an_entry_is_served_only_as_it_was_stored(tmp_path):
    cache = ArtefactCache(tmp_path)
    data = bytes(range(256)) * 40
    p = cache.put(KEY_A, "bin", data)
    assert cache.get(KEY_A, "bin") == p and p.read_bytes() == data
    # one flipped bit
    p.write_bytes(data[:100] + bytes([data[100] ^ 0x10]) + data[101:])
    with pytest.warns(CacheWarning, match=str(p)):
        assert cache.get(KEY_A, "bin") is None
    assert not p.exists() and not _entry(cache, KEY_A)[1].exists()  # discarded
    # truncated
    cache.put(KEY_A, "bin", data)
    p.write_bytes(data[:-1])
    with pytest.warns(CacheWarning, match="do not match their checksum"):
        assert cache.get(KEY_A, "bin") is None
    # an unreadable checksum file
    cache.put(KEY_A, "bin", data)
    _entry(cache, KEY_A)[1].write_bytes(b"\x00garbage")
    with pytest.warns(CacheWarning, match="checksum file cannot be read"):
        assert cache.get(KEY_A, "bin") is None


def test_an_entry_moved_under_another_key_is_refused(tmp_path):
    cache = ArtefactCache(tmp_path)
    cache.put(KEY_A, "bin", b"made for a")
    (pa, sa), (pb, sb) = _entry(cache, KEY_A), _entry(cache, KEY_B)
    pb.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy(pa, pb)  # the bytes alone: no checksum for b
    assert cache.get(KEY_B, "bin") is None
    shutil.copy(pa, pb)
    shutil.copy(sa, sb)  # with a's checksum file: it names a's key
    with pytest.warns(CacheWarning, match="another key"):
        assert cache.get(KEY_B, "bin") is None
    assert cache.get(KEY_A, "bin") == pa  # a's own entry is untouched


@pytest.mark.parametrize(
    ("code", "words"),
    [(errno.ENOSPC, "no space left"), (errno.EROFS, "read-only"), (errno.EACCES, "read-only")],
)
def test_a_cache_that_cannot_be_written_is_one_line(tmp_path, monkeypatch, code, words):
    def fail(path, data):
        raise OSError(code, "simulated")

    monkeypatch.setattr(cache_module, "atomic_write", fail)
    with pytest.raises(CacheError, match=words) as info:
        ArtefactCache(tmp_path).put(KEY_A, "bin", b"x")
    assert "\n" not in str(info.value) and "SIM_TACTILE_CACHE" in str(info.value)


def test_a_read_only_cache_whose_entries_are_there_is_read(tmp_path, monkeypatch):
    cache = ArtefactCache(tmp_path)
    p = cache.put(KEY_A, "bin", b"kept")

    def fail(path, data):  # nothing may be written now
        raise OSError(errno.EROFS, "read-only file system")

    monkeypatch.setattr(cache_module, "atomic_write", fail)
    assert cache.get(KEY_A, "bin") == p


def test_an_edited_mjcf_artefact_is_rebuilt_not_simulated(tmp_path):
    cache = ArtefactCache(tmp_path)
    plate = get_plate("finger7/ridges-2")
    path = build(plate, kinds=("mjcf",), cache=cache).files["mjcf"]
    good = path.read_bytes()
    # raise every geom a little: a valid MJCF, another plate
    path.write_bytes(good.replace(b'pos="', b'pos="0.0001 ', 1))
    with pytest.warns(CacheWarning, match=artefact_key(plate, "mjcf")):
        again = build(plate, kinds=("mjcf",), cache=cache)
    assert not again.cached["mjcf"] and again.files["mjcf"].read_bytes() == good
    path.write_bytes(good[: len(good) // 2])  # truncated
    with pytest.warns(CacheWarning):
        assert build(plate, kinds=("mjcf",), cache=cache).files["mjcf"].read_bytes() == good


def _jobs():
    proto = Protocol(duration_s=0.15, rate_hz=100.0, speed_jitter=0.05)
    sensor = get_sensor("grid3x3")
    return [
        SlideJob(get_plate("finger7/ridges-2"), sensor, proto, seed=5, fidelity="L0"),
        SlideJob(get_plate("finger7/flat"), sensor, proto, seed=6, fidelity="L0"),
    ]


@pytest.mark.slow
def test_a_slide_entry_under_another_key_is_simulated_again(tmp_path):
    """The tracker's case: a valid slide entry copied under another job's key (its file and
    its checksum) was served as that job's slide. It is refused and the slide simulated."""
    cache = ArtefactCache(tmp_path)
    jobs = _jobs()
    recs, stats = run_slides(jobs, cache=cache, workers=1)
    assert stats["slides_simulated"] == 2
    (pa, sa), (pb, sb) = (_entry(cache, j.key(), SLIDE_EXT) for j in jobs)
    shutil.copy(pa, pb)
    shutil.copy(sa, sb)
    with pytest.warns(CacheWarning, match=str(pb)):
        again, stats = run_slides(jobs, cache=cache, workers=1)
    assert stats["slides_simulated"] == 1 and stats["slides_cached"] == 1
    for a, b in zip(recs, again, strict=True):
        assert a.data.tobytes() == b.data.tobytes()
    # a truncated entry (the BadZipFile of the tracker) is named and simulated again
    pb.write_bytes(pb.read_bytes()[:200])
    with pytest.warns(CacheWarning, match=str(pb)):
        _, stats = run_slides(jobs, cache=cache, workers=1)
    assert stats["slides_simulated"] == 1


def test_a_tampered_skin_is_computed_again(tmp_path):
    from sim_tactile.cache import forget_process_memos
    from sim_tactile.scene.nodes import skin_grid
    from sim_tactile.sim.skin.models import make_skin

    cache = ArtefactCache(tmp_path)
    finger = get_sensor("grid3x3").finger
    grid = skin_grid(finger, 0.45e-3)
    plain = make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0)
    forget_process_memos()
    make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0, cache=cache)
    (f,) = sorted(tmp_path.rglob("*.skin.npz"))
    with np.load(f) as z:
        arrays = dict(z)
    arrays["C"] = arrays["C"] * 1.01  # a valid npz, a stiffer skin
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    f.write_bytes(buf.getvalue())
    forget_process_memos()
    with pytest.warns(CacheWarning, match=str(f)):
        s = make_skin("L1", grid, finger, winkler_k_pa_per_m=1.0, cache=cache)
    assert s.C.tobytes() == plain.C.tobytes()


def test_a_reader_leaves_a_writers_entry_between_its_two_writes_in_place(tmp_path, monkeypatch):
    """Two workers filling one fresh cache: the reader must not delete the entry whose bytes
    the writer has renamed into place but whose checksum it has not written yet (it did, and
    the writer's next read of its own entry failed: MuJoCo could not open a plate's MJCF)."""
    writer, reader = ArtefactCache(tmp_path), ArtefactCache(tmp_path)
    real = cache_module.atomic_write
    seen = {}

    def write_then_read(path, data):
        real(path, data)
        if not path.name.endswith(cache_module.SUM_SUFFIX):
            seen["reader"] = reader.get(KEY_A, "bin")  # the other worker looks now
            seen["there"] = path.exists()

    monkeypatch.setattr(cache_module, "atomic_write", write_then_read)
    p = writer.put(KEY_A, "bin", b"the plate's bytes")
    monkeypatch.setattr(cache_module, "atomic_write", real)
    assert seen == {"reader": None, "there": True}
    assert p.read_bytes() == b"the plate's bytes"
    assert reader.get(KEY_A, "bin") == p


def test_an_entry_left_without_its_checksum_is_made_again(tmp_path):
    cache = ArtefactCache(tmp_path)
    p, s = _entry(cache, KEY_A)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_bytes(b"cut short")  # a writer that died between its two writes
    assert cache.get(KEY_A, "bin") is None
    assert cache.put(KEY_A, "bin", b"whole") == p
    assert cache.get(KEY_A, "bin") == p and p.read_bytes() == b"whole"
