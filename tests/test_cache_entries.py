"""Every cache entry proves what it is (sim_tactile/cache.py): an entry altered, truncated,
moved under another key or unreadable is never served; it is made again, with a warning
that names the file. A cache that cannot be written says so in one line."""

from __future__ import annotations

import errno
import hashlib
import io
import json
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from sim_tactile import cache as cache_module
from sim_tactile.cache import SUM_SUFFIX, ArtefactCache, npz_bytes
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
    with pytest.warns(CacheWarning, match="no checksum"):
        assert cache.get(KEY_B, "bin") is None
    pb.parent.mkdir(parents=True, exist_ok=True)
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
    """An entry is renamed into place whole, artefact and checksum together: one without its
    checksum was damaged (nobody is between two writes), so it is discarded and made again."""
    cache = ArtefactCache(tmp_path)
    p, s = _entry(cache, KEY_A)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_bytes(b"cut short")
    with pytest.warns(CacheWarning, match="no checksum beside it"):
        assert cache.get(KEY_A, "bin") is None
    assert cache.put(KEY_A, "bin", b"whole") == p
    assert cache.get(KEY_A, "bin") == p and p.read_bytes() == b"whole"


def test_two_writers_of_one_entry_leave_one_whole_entry(tmp_path, monkeypatch):
    """Two processes making the same artefact at once, their writes interleaved: A writes its
    bytes, B writes its entry whole, then A writes its checksum. The entry and its checksum
    were two files replaced one at a time, so A's checksum sat beside B's bytes and the next
    reader warned of corruption and made the entry again; now each writer's pair is renamed
    into place as one, and the entry the reader finds is whole (B's, the first in place)."""
    a, b = ArtefactCache(tmp_path), ArtefactCache(tmp_path)
    real = cache_module.atomic_write
    order = []

    def interleaved(path, data):
        real(path, data)
        if not order:  # A's first file is written: B runs whole now
            order.append("a bytes")
            b.put(KEY_A, "bin", b"made by b, with b's wall time")
            order.append("b whole")

    monkeypatch.setattr(cache_module, "atomic_write", interleaved)
    a.put(KEY_A, "bin", b"made by a, with a's wall time")
    monkeypatch.setattr(cache_module, "atomic_write", real)
    assert order == ["a bytes", "b whole"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        p = a.get(KEY_A, "bin")
    assert p is not None and p.read_bytes() == b"made by b, with b's wall time"
    assert not [q for q in tmp_path.rglob("*") if q.name.startswith(".")]  # no temporaries


def test_npz_bytes_are_a_function_of_the_arrays(monkeypatch):
    """numpy.savez stamps each member with the wall clock (two writes a few seconds apart
    differ); the cache's .npz does not, and reads back as numpy's does."""
    import time

    arrays = {"x": np.arange(6.0).reshape(2, 3), "s": np.array("text")}
    first = npz_bytes(arrays)
    later = time.time() + 3600
    monkeypatch.setattr(time, "time", lambda: later)
    monkeypatch.setattr(time, "localtime", lambda t=None: time.gmtime(later))
    assert npz_bytes(arrays) == first
    with np.load(io.BytesIO(first), allow_pickle=False) as z:
        assert z["x"].tolist() == arrays["x"].tolist() and str(z["s"]) == "text"


def _forge_checksum(cache: ArtefactCache, src_key: str, key: str, ext: str) -> Path:
    """Copy the entry ``src_key`` under ``key`` with a checksum file made valid for it, as a
    forger would; returns the copy's path."""
    (pa, _), (pb, sb) = _entry(cache, src_key, ext), _entry(cache, key, ext)
    pb.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy(pa, pb)
    data = pb.read_bytes()
    record = {"key": key, "sha256": hashlib.sha256(data).hexdigest(), "size": len(data)}
    sb.write_text(json.dumps(record))
    return pb


@pytest.mark.slow
def test_a_slide_entry_with_a_forged_checksum_is_simulated_again(tmp_path):
    """An entry copied under another job's key with its checksum file made valid for that key
    passed every check of the cache and was served as the other job's slide. The entry names
    its own key, plate and seed: it is refused, with a warning naming the file, and the slide
    simulated again."""
    cache = ArtefactCache(tmp_path)
    jobs = _jobs()
    recs, _ = run_slides(jobs, cache=cache, workers=1)
    forged = _forge_checksum(cache, jobs[0].key(), jobs[1].key(), SLIDE_EXT)
    with pytest.warns(CacheWarning, match=str(forged)):
        again, stats = run_slides(jobs, cache=cache, workers=1)
    assert stats["slides_simulated"] == 1 and stats["slides_cached"] == 1
    assert again[1].data.tobytes() == recs[1].data.tobytes()


def _fake_entry(job: SlideJob, **meta) -> bytes:
    """A cached slide's bytes for ``job`` (no physics), its meta as the simulation writes it,
    changed by ``meta``."""
    from sim_tactile.records import Recording
    from sim_tactile.slides.jobs import entry_bytes

    taxels = job.sensor.layout.positions
    own = {"plate": job.plate.name, "plate_hash": job.plate.hash, "seed": job.seed}
    rec = Recording(np.zeros((3, len(taxels))), np.arange(3.0), taxels, meta={**own, **meta})
    return entry_bytes(rec, job.key())


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({}, None),
        ({"seed": 99}, "holds the slide of seed 99, not 5"),
        ({"plate_hash": "0" * 16, "plate": "other"}, "holds a slide of another plate"),
    ],
)
def test_a_cached_slide_names_its_own_plate_and_seed(tmp_path, change, words):
    from sim_tactile.slides.jobs import cached_slide

    cache = ArtefactCache(tmp_path)
    job = _jobs()[0]
    cache.put(job.key(), SLIDE_EXT, _fake_entry(job, **change))
    if words is None:
        assert cache.get(job.key(), SLIDE_EXT) is not None
        assert cached_slide(cache, job).meta["slide_key"] == job.key()
        return
    with pytest.warns(CacheWarning, match=words):
        assert cached_slide(cache, job) is None
    assert cache.get(job.key(), SLIDE_EXT) is None  # discarded


def test_a_cached_slide_holds_no_wall_time():
    from sim_tactile.records import Recording
    from sim_tactile.slides.jobs import TIMING_KEYS, entry_bytes

    job = _jobs()[0]
    taxels = job.sensor.layout.positions
    rec = Recording(np.zeros((2, 9)), np.arange(2.0), taxels, meta={"wall_s": 1.5})
    timed = Recording(rec.data, rec.times, taxels, meta={"wall_s": 2.5, "slide_wall_s": 1.0})
    assert entry_bytes(rec, job.key()) == entry_bytes(timed, job.key())
    with np.load(io.BytesIO(entry_bytes(rec, job.key()))) as z:
        assert not set(TIMING_KEYS) & set(json.loads(str(z["meta_json"])))


#: One process of the concurrent-writers test: simulates the first job of :func:`_jobs` into
#: its own cache (argv[2]) and prints the entry's path, then, once the other process is
#: ready too (files in argv[3]), simulates it again into the shared cache (argv[1]).
_WRITER = """
import sys, time
from pathlib import Path
from sim_tactile.cache import ArtefactCache
from sim_tactile.plates.presets import get_plate
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.slides import SlideJob, SlideWorker
from sim_tactile.slides.jobs import SLIDE_EXT

proto = Protocol(duration_s=0.15, rate_hz=100.0, speed_jitter=0.05)
job = SlideJob(get_plate("finger7/ridges-2"), get_sensor("grid3x3"), proto, seed=5, fidelity="L0")
SlideWorker(sys.argv[2])(job)
print(ArtefactCache(Path(sys.argv[2])).path(job.key(), SLIDE_EXT), flush=True)
ready = Path(sys.argv[3])
(ready / Path(sys.argv[2]).name).touch()
t0 = time.monotonic()
while len(list(ready.iterdir())) < 2 and time.monotonic() - t0 < 120:
    time.sleep(0.001)
SlideWorker(sys.argv[1])(job)
"""


@pytest.mark.slow
def test_two_processes_writing_one_slide_leave_an_entry_the_next_run_reads(tmp_path):
    """Two runs on one slide cache simulate the same slide at once. An entry's bytes held the
    wall time of its simulation (and the .npz its members' time stamps), so the two wrote
    different bytes, and a checksum could end up beside the other's bytes: the next run
    warned of corruption and simulated again. The bytes are now the slide's content (the
    same in both processes) and an entry is replaced as one: the next run reads it."""
    import subprocess
    import sys

    shared, ready = tmp_path / "shared", tmp_path / "ready"
    ready.mkdir()
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", _WRITER, str(shared), str(tmp_path / f"own{k}"), str(ready)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for k in range(2)
    ]
    outs = [p.communicate(timeout=600) for p in procs]
    for p, (_, err) in zip(procs, outs, strict=True):
        assert p.returncode == 0 and "CacheWarning" not in err, err
    own = [Path(out.strip()).read_bytes() for out, _ in outs]
    assert own[0] == own[1]  # the same slide, the same bytes, whoever made it and when
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        _, stats = run_slides(_jobs()[:1], cache=ArtefactCache(shared), workers=1)
    assert stats["slides_cached"] == 1 and stats["slides_simulated"] == 0
