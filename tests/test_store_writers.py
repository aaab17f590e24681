"""One writer at a time: a store is made under a fresh temporary name and taken by an atomic
rename, under a lock (``flock`` on ``.NAME.lock`` beside it) held for the whole write. Two
``generate``s into one ``--out`` always leave one whole store of one configuration and one
clear refusal; concurrent ``--resume``s neither duplicate slides nor lose history; a dead
writer's lock and temporary folder are no obstacle. Fake workers: no physics."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from _stores import (
    TINY,
    assert_same,
    fake_slide,
    make_store,
    quiet_generate,
    read_back,
    store_files,
    write_config,
)

from sim_tactile import datasets
from sim_tactile.datasets import store as store_mod
from sim_tactile.datasets.lock import StoreLock, lock_path
from sim_tactile.errors import StoreError

#: what the refused writer of a pair may be told (one line each)
REFUSALS = (
    "is being written by another process",
    "already exists",
    "appeared while this was written",
)
OTHER = {**TINY, "slides_per_plate": 4, "seed": 8}


def _check_one_whole_store(out: Path, winner: dict) -> None:
    back = read_back(out)  # every slide, checked
    st = datasets.open(out)
    assert st.config["seed"] == winner["seed"]
    assert len(st) == 2 * winner["slides_per_plate"] and st.complete
    assert len(st.meta["runs"]) == 1 and back["meta"]["complete"]


def _race(folder: Path, trial: int) -> tuple[list, Path]:
    """Two generates of two configurations into one --out, started together (threads)."""
    out = folder / f"race{trial}.zarr"
    cfgs = [write_config(folder, c, f"c{k}.json") for k, c in enumerate((TINY, OTHER))]
    barrier = threading.Barrier(2)
    results: list = [None, None]

    def slow(job):
        time.sleep(0.002)
        return fake_slide(job)

    def go(k: int) -> None:
        barrier.wait()
        try:
            results[k] = quiet_generate(cfgs[k], out, _worker=slow)
        except StoreError as exc:
            results[k] = exc

    threads = [threading.Thread(target=go, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    return results, out


@pytest.mark.slow
def test_two_writers_into_one_out_leave_one_whole_store(tmp_path):
    seen = set()
    for trial in range(8):
        results, out = _race(tmp_path, trial)
        won = [k for k, r in enumerate(results) if isinstance(r, dict)]
        lost = [r for r in results if isinstance(r, StoreError)]
        assert len(won) == 1 and len(lost) == 1, results
        msg = str(lost[0])
        assert "\n" not in msg and any(r in msg for r in REFUSALS), msg
        seen.add(next(r for r in REFUSALS if r in msg))
        _check_one_whole_store(out, (TINY, OTHER)[won[0]])
        assert not lock_path(out).exists()
    assert not list(tmp_path.glob(".*.creating")) and not list(tmp_path.glob(".*.partial"))
    assert seen  # (which refusal depends on the timing)


_RACE_SCRIPT = """
import contextlib, io, json, sys, time
import sim_tactile.generate as g
from sim_tactile.cli import main
sys.path.insert(0, {tests!r})
from _stores import fake_slide

def slow(job):
    time.sleep(0.02)
    return fake_slide(job)

g.SlideWorker = lambda *a, **k: slow
cfg, outs, start = sys.argv[1], sys.argv[2:], {start}
res = []
for k, out in enumerate(outs):  # trial k starts at the same instant in both processes
    time.sleep(max(0.0, start + {period} * k - time.time()))
    err, std = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(std):
        code = main(["generate", cfg, "--out", out, "--workers", "1", "--json"])
    res.append([code, std.getvalue(), err.getvalue()])
print(json.dumps(res))
"""


@pytest.mark.slow
def test_two_generate_commands_into_one_out_leave_one_store_and_one_refusal(tmp_path, cli_env):
    """The command line, as users met it: two processes, each running ``generate`` into the
    same 16 ``--out``s in turn, every pair started at the same instant."""
    n = 16
    tests = str(Path(__file__).parent)
    cfgs = [write_config(tmp_path, c, f"c{k}.json") for k, c in enumerate((TINY, OTHER))]
    outs = [str(tmp_path / f"cli{k}.zarr") for k in range(n)]
    script = _RACE_SCRIPT.format(tests=tests, start=time.time() + 15.0, period=1.0)
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", script, str(c), *outs],
            env=cli_env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for c in cfgs
    ]
    docs = []
    for p in procs:
        stdout, stderr = p.communicate(timeout=240)
        assert p.returncode == 0, stderr[-2000:]
        docs.append(json.loads(stdout))
    seen = []
    for k in range(n):
        codes = [docs[0][k][0], docs[1][k][0]]
        assert sorted(codes) == [0, 2], (k, docs[0][k], docs[1][k])
        win, lose = codes.index(0), codes.index(2)
        _, stdout, err = docs[lose][k]
        err = err.strip()
        assert "\n" not in err and err.startswith("sim-tactile: error: "), err
        assert stdout == "" and json.loads(docs[win][k][1])["trials"] > 0
        seen.append(next(r for r in REFUSALS if r in err))
        _check_one_whole_store(Path(outs[k]), (TINY, OTHER)[win])
    assert REFUSALS[0] in seen, seen  # the lock, met at least once


def _interrupted_store(folder: Path) -> tuple[Path, Path]:
    cfg = write_config(folder)
    out = folder / "cut.zarr"
    calls = {"n": 0}

    def cut(job):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return fake_slide(job)

    with pytest.raises(KeyboardInterrupt):
        quiet_generate(cfg, out, _worker=cut)
    assert datasets.open(out).missing() == 4
    return cfg, out


def test_concurrent_resumes_neither_duplicate_slides_nor_lose_history(tmp_path):
    cfg, out = _interrupted_store(tmp_path)
    entered, release = threading.Event(), threading.Event()
    simulated = []

    def held(job):  # the first resume holds the lock while the second one tries
        entered.set()
        release.wait(30)
        simulated.append(job.seed)
        return fake_slide(job)

    first: list = []
    t = threading.Thread(
        target=lambda: first.append(quiet_generate(cfg, out, resume=True, _worker=held))
    )
    t.start()
    assert entered.wait(30)
    with pytest.raises(
        StoreError,
        match=rf"being written by another process \(pid {os.getpid()} on {socket.gethostname()}, since ",
    ):
        quiet_generate(cfg, out, resume=True)
    release.set()
    t.join(60)
    assert first[0]["written"] == 4 and first[0]["reused"] == 2 and len(simulated) == 4
    runs = datasets.open(out).meta["runs"]
    assert [r["interrupted"] for r in runs] == [True, False]
    assert [r["written"] for r in runs] == [2, 4]
    res = quiet_generate(cfg, out, resume=True)  # and a third, after: nothing to do
    assert res["written"] == 0 and len(datasets.open(out).meta["runs"]) == 3
    ref = tmp_path / "ref.zarr"
    quiet_generate(cfg, ref)
    for k, v in read_back(ref)["index"].items():
        np.testing.assert_array_equal(read_back(out)["index"][k], v)
    np.testing.assert_array_equal(read_back(out)["data"], read_back(ref)["data"])


def test_a_held_lock_is_refused_at_once_naming_its_holder(tmp_path):
    out = tmp_path / "x.zarr"
    with StoreLock(out):
        doc = json.loads(lock_path(out).read_text())
        assert doc["pid"] == os.getpid() and doc["host"] == socket.gethostname()
        for call in (
            lambda: StoreLock(out).acquire(),
            lambda: StoreLock.probe(out),
            lambda: quiet_generate(write_config(tmp_path), out),
        ):
            with pytest.raises(
                StoreError, match=f"x.zarr is being written by another process \\(pid {os.getpid()}"
            ):
                call()
    assert not out.exists() and not lock_path(out).exists()
    quiet_generate(write_config(tmp_path), out)  # free again


def test_a_dead_writers_lock_and_temporary_store_are_no_obstacle(tmp_path, cli_env):
    out = tmp_path / "x.zarr"
    code = (
        "import sys, time\n"
        "from sim_tactile.datasets.lock import StoreLock\n"
        f"StoreLock({str(out)!r}).acquire()\n"
        "print('held', flush=True)\n"
        "time.sleep(120)\n"
    )
    p = subprocess.Popen(
        [sys.executable, "-c", code], env=cli_env, stdout=subprocess.PIPE, text=True
    )
    assert p.stdout.readline().strip() == "held"
    with pytest.raises(StoreError, match=f"pid {p.pid} "):
        StoreLock(out).acquire()
    os.kill(p.pid, signal.SIGKILL)  # kill -9: the lock file stays, the lock goes
    p.communicate(timeout=30)
    assert lock_path(out).exists()
    stale = tmp_path / ".x.zarr.0123456789ab.creating"  # a dead writer's half-made store
    (stale / "data").mkdir(parents=True)
    res = quiet_generate(write_config(tmp_path), out)
    assert res["written"] == 6 and not stale.exists() and not lock_path(out).exists()
    read_back(out)


def test_a_store_that_appears_while_one_is_made_is_left_alone(tmp_path, monkeypatch):
    out = tmp_path / "x.zarr"
    real = store_mod._create_group

    def intruder(*a, **k):  # someone else's folder appears at the target meanwhile
        (out / "theirs").mkdir(parents=True, exist_ok=True)
        return real(*a, **k)

    monkeypatch.setattr(store_mod, "_create_group", intruder)
    with pytest.raises(StoreError, match="x.zarr appeared while this was written"):
        quiet_generate(write_config(tmp_path), out)
    assert [p.name for p in out.iterdir()] == ["theirs"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiny.json", "x.zarr"]


def test_the_writer_puts_zarrs_own_chunk_files_without_its_write_path(tmp_path, monkeypatch):
    """The slides' chunks are written without Zarr's asynchronous path (:mod:`.chunks`: 1 ms
    a slide of the small sets): the files are the ones Zarr writes, byte for byte, under the
    same names, and every reader reads them back; arrays in another layout go through Zarr."""
    import zarr

    from sim_tactile.datasets.chunks import ChunkFile

    fast = make_store(tmp_path, "fast.zarr")
    for name in ("data", "checksum"):  # the store's arrays take the writer's own path
        assert ChunkFile.for_array(zarr.open_array(str(fast / name), mode="r")) is not None
    monkeypatch.setattr(ChunkFile, "for_array", classmethod(lambda cls, arr: None))
    plain = make_store(tmp_path, "plain.zarr")
    files = store_files(fast)
    chunks = [f for f in files if f.parts[0] in ("data", "checksum") and f.parts[1][0] == "c"]
    assert len(chunks) == 2 * 6  # each slide's samples and its mark
    assert chunks == [f for f in store_files(plain) if f in chunks]
    for f in chunks:
        assert (fast / f).read_bytes() == (plain / f).read_bytes(), f
    assert_same(read_back(fast), read_back(plain))


def test_the_chunk_writer_takes_only_the_layout_it_writes(tmp_path):
    """Row chunks encoded by ``bytes`` little endian and optionally ``zstd``, on a local
    store: anything else (another compressor, other chunks) is left to Zarr."""
    import zarr

    from sim_tactile.datasets.chunks import ChunkFile

    g = zarr.open_group(str(tmp_path / "g.zarr"), mode="w")
    kw = dict(dtype="float32", fill_value=np.nan)
    row = g.create_array("row", shape=(3, 4, 2), chunks=(1, 4, 2), **kw)
    bare = g.create_array("bare", shape=(3,), chunks=(1,), dtype="uint64", compressors=None)
    other = g.create_array(
        "other", shape=(3, 4, 2), chunks=(1, 4, 2), compressors=zarr.codecs.GzipCodec(), **kw
    )
    tiles = g.create_array("tiles", shape=(3, 4, 2), chunks=(1, 2, 2), **kw)
    assert ChunkFile.for_array(row) is not None and ChunkFile.for_array(bare) is not None
    assert ChunkFile.for_array(other) is None and ChunkFile.for_array(tiles) is None
    x = np.arange(8, dtype=np.float32).reshape(4, 2)
    ChunkFile.for_array(row).write(1, x)
    ChunkFile.for_array(bare).write(2, np.uint64(2**63 + 5))
    np.testing.assert_array_equal(row[1], x)
    assert np.isnan(row[0]).all() and int(bare[2]) == 2**63 + 5 and int(bare[0]) == 0
    assert not list((tmp_path / "g.zarr").rglob("*.partial"))


def test_a_chunk_write_stopped_before_its_rename_leaves_nothing_or_what_the_cleanup_removes(
    tmp_path, monkeypatch
):
    """Stopped between the temporary file and its rename, the writer removes the temporary
    file; killed there (no clean-up runs), the file it leaves is one that
    :func:`remove_partial_chunks` removes (Zarr's own temporary name)."""
    import os

    import zarr

    from sim_tactile.datasets import chunks
    from sim_tactile.datasets.chunks import ChunkFile, remove_partial_chunks

    g = zarr.open_group(str(tmp_path / "g.zarr"), mode="w")
    arr = g.create_array("row", shape=(3, 4, 2), chunks=(1, 4, 2), dtype="float32")
    names = []

    def stop(src, dst):
        names.append(Path(src))
        raise KeyboardInterrupt

    with monkeypatch.context() as mp:
        mp.setattr(chunks.os, "replace", stop)
        with pytest.raises(KeyboardInterrupt):
            ChunkFile.for_array(arr).write(1, np.ones((4, 2), np.float32))
    (tmp,) = names
    assert not tmp.exists() and not (tmp.parent / "0").exists()
    tmp.write_bytes(b"half")  # as a killed writer leaves it
    assert remove_partial_chunks(tmp_path / "g.zarr") == 1 and not tmp.exists()
    assert os.listdir(tmp.parent) == []


def test_a_slides_samples_make_no_folder_and_a_store_keyed_the_old_way_is_resumed_alike(
    tmp_path, monkeypatch
):
    """The samples' chunks lie in their array's own folder (``c.<slide>.0.0``: no folder a
    slide), and a store whose samples are keyed Zarr's default way (``c/<slide>/0/0``, as
    stores were made before) is read and resumed alike: its own metadata says where."""
    new = make_store(tmp_path, "new.zarr")
    assert sorted(p.name for p in (new / "data").iterdir() if p.is_dir()) == []
    assert (new / "data" / "c.4.0.0").is_file()
    monkeypatch.setattr(
        store_mod, "SAMPLE_KEYS", {"name": "default", "configuration": {"separator": "/"}}
    )
    old = make_store(tmp_path, "old.zarr")
    monkeypatch.undo()
    lost = old / "data" / "c" / "4" / "0" / "0"
    assert lost.is_file() and not (old / "data" / "c.4.0.0").exists()
    lost.unlink()
    res = quiet_generate(tmp_path / "tiny.json", old, resume=True)
    assert res["written"] == 1 and lost.is_file() and not (old / "data" / "c.4.0.0").exists()
    assert datasets.open(old).verify() == []
    a, b = read_back(old), read_back(new)  # (their metadata differ: data/zarr.json's digest)
    for k in ("data", "slides", "labels"):
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
