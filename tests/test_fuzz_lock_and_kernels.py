"""Fuzzing the two things beside the data that a command trusts: the store's lock file and
the compiled-kernel folder (hypothesis).

- Anything at a store's lock path (a file of any content or mode, a link to anything, a
  hard link, a FIFO, a socket, a folder, a device, a lock another process holds) is either
  refused with one StoreError line, or the lock is taken and given back; never a hang,
  never another exception, and no file that a link or a second name points at is changed.
- Any corruption of a compiled kernel's files (a flipped bit, a truncation, bytes added or
  overwritten, a file swapped for another) is found before numba reads it: the kernel is
  compiled again, with a warning naming the file; never a crash, never the damaged code.

The fast lane samples; the slow lane searches wider and compiles the kernel again each time.
"""

from __future__ import annotations

import os
import shutil
import socket
import stat
import tempfile
import warnings
from pathlib import Path

import pytest
from _kernels import compile_into, fresh, kernel_file, run
from _stores import within
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sim_tactile import _kernel_files
from sim_tactile.datasets.lock import StoreLock, lock_path
from sim_tactile.errors import CacheWarning, StoreError

_SETTINGS = {
    "deadline": None,
    "derandomize": True,  # the same cases on every run: a failure is reproducible
    "suppress_health_check": [HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
}
#: How long taking or refusing a lock may take [s]: nothing is waited on (a hang is forever).
HANG_S = 20.0

# ------------------------------------------------------------------------------ the lock
KINDS = [
    "nothing",
    "file",
    "read-only file",
    "unreadable file",
    "holder's file",
    "held file",
    "link to a file",
    "link to a folder",
    "dangling link",
    "link to itself",
    "hard link",
    "fifo",
    "socket",
    "folder",
    "folder with a file",
    "device",
]


def _plant(kind: str, path: Path, content: bytes, victim: Path, keep: list) -> None:
    """Put ``kind`` at ``path`` (``keep`` holds what must stay open meanwhile)."""
    if kind in ("file", "read-only file", "unreadable file", "holder's file", "held file"):
        path.write_bytes(
            b'{"pid": 1, "host": "elsewhere", "since": "then"}'
            if kind == "holder's file"
            else content
        )
        if kind == "read-only file":
            path.chmod(0o444)
        elif kind == "unreadable file":
            path.chmod(0o000)
        elif kind == "held file":
            import fcntl

            fd = os.open(path, os.O_RDONLY)
            fcntl.flock(fd, fcntl.LOCK_EX)
            keep.append(fd)
    elif kind == "link to a file":
        path.symlink_to(victim)
    elif kind == "link to a folder":
        path.symlink_to(victim.parent)
    elif kind == "dangling link":
        path.symlink_to(victim.parent / "made-through-the-link")
    elif kind == "link to itself":
        path.symlink_to(path.name)
    elif kind == "hard link":
        os.link(victim, path)
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "socket":
        s = socket.socket(socket.AF_UNIX)
        s.bind(str(path))
        keep.append(s)
    elif kind.startswith("folder"):
        path.mkdir()
        if kind == "folder with a file":
            (path / "x").write_bytes(content)
    elif kind == "device":
        try:
            os.mknod(path, 0o600 | stat.S_IFCHR, os.makedev(1, 3))  # as /dev/null
        except OSError:
            path.write_bytes(content)  # not allowed here: a plain file instead


def _within(call) -> dict:
    hung, box = within(call, HANG_S)
    assert not hung, "the lock hung"
    return box


def _check_lock(kind: str, content: bytes, through_link: bool) -> str:
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        victim = folder / "victim" / "precious.txt"
        victim.parent.mkdir()
        victim.write_bytes(b"precious\n")
        store = folder / "x.zarr"
        name = store
        if through_link:
            name = folder / "link.zarr"
            name.symlink_to(store)
        keep: list = []
        _plant(kind, lock_path(store), content, victim, keep)
        try:
            for call in (lambda: StoreLock.probe(name), lambda: StoreLock(name).acquire()):
                box = _within(call)
                if "exc" in box:
                    exc = box["exc"]
                    assert isinstance(exc, StoreError), repr(exc)
                    msg = str(exc)
                    assert "\n" not in msg
                    assert str(lock_path(store)) in msg or "being written by another" in msg
                elif isinstance(box.get("value"), StoreLock):
                    box["value"].release()
            outcome = "refused" if "exc" in box else "locked"
        finally:
            for k in keep:
                k.close() if hasattr(k, "close") else os.close(k)
        assert victim.read_bytes() == b"precious\n"
        assert sorted(p.name for p in victim.parent.iterdir()) == ["precious.txt"]
        if kind in ("nothing", "file", "read-only file", "holder's file", "hard link"):
            assert outcome == "locked", kind  # a dead writer's lock file is no obstacle
        return outcome


def _fuzz_lock(examples: int) -> None:
    @settings(max_examples=examples, **_SETTINGS)
    @given(
        kind=st.sampled_from(KINDS),
        content=st.binary(max_size=64),
        through_link=st.booleans(),
    )
    def case(kind, content, through_link):
        _check_lock(kind, content, through_link)

    case()


def test_anything_at_the_lock_path_is_refused_or_locked_never_hangs():
    _fuzz_lock(60)


@pytest.mark.slow
def test_anything_at_the_lock_path_is_refused_or_locked_never_hangs_wide():
    _fuzz_lock(400)


# --------------------------------------------------------------------- the kernel folder
@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    """A kernel folder holding the kernel, its files' bytes, and the kernel's value."""
    folder = tmp_path_factory.mktemp("fuzz-kernels")
    value = compile_into(folder)
    files = {ext: kernel_file(folder, ext) for ext in ("nbi", "nbc")}
    return folder, {ext: p.read_bytes() for ext, p in files.items()}, value


@st.composite
def corruptions(draw, sizes: dict):
    """``(ext, kind, a, b, extra)``: which file, and what is done to it."""
    ext = draw(st.sampled_from(["nbi", "nbc"]))
    n = sizes[ext]
    kind = draw(st.sampled_from(["flip", "flip", "truncate", "append", "overwrite", "swap"]))
    a = draw(st.integers(0, 8 * n - 1 if kind == "flip" else n - 1))
    b = draw(st.integers(1, 64))
    extra = draw(st.binary(min_size=1, max_size=64))
    return ext, kind, a, b, extra


def _corrupt(raw: dict, ext: str, kind: str, a: int, b: int, extra: bytes) -> bytes:
    data = bytearray(raw[ext])
    if kind == "flip":
        data[a // 8] ^= 1 << (a % 8)
    elif kind == "truncate":
        del data[a:]
    elif kind == "append":
        data += extra
    elif kind == "overwrite":
        end = min(len(data), a + len(extra))
        new = extra[: end - a]
        if bytes(data[a:end]) == new:  # the same bytes: change them for sure
            new = bytes(x ^ 0xFF for x in new)
        data[a:end] = new
    else:  # the other file's bytes under this one's name
        data = bytearray(raw["nbc" if ext == "nbi" else "nbi"])
    return bytes(data)


def _check_kernel(compiled, tmp: Path, fault, whole_run: bool) -> None:
    folder, raw, value = compiled
    ext = fault[0]
    work = tmp / "kernels"
    if work.exists():
        shutil.rmtree(work)
    shutil.copytree(folder, work)
    path = kernel_file(work, ext)
    path.write_bytes(_corrupt(raw, *fault))
    os.environ["SIM_TACTILE_KERNELS"] = str(work)
    _kernel_files._warned.clear()  # each case as a new process sees it (a file warns once)
    if whole_run:  # the kernel compiled again, with a warning naming the file
        got, hits, misses, said = run()
        assert (got, hits, misses) == (value, 0, 1), fault
    else:  # nothing of the file is loaded (numba then compiles)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            cache = fresh()._cache._cache_file
            index = cache._load_index()
            loaded = [cache.load(key) for key in index]
        assert not any(x is not None for x in loaded), fault
        said = [str(w.message) for w in caught if w.category is CacheWarning]
    assert any(path.name in s for s in said), (fault, said)


def _fuzz_kernels(compiled, tmp: Path, examples: int, whole_run: bool) -> None:
    sizes = {ext: len(b) for ext, b in compiled[1].items()}

    @settings(max_examples=examples, **_SETTINGS)
    @given(fault=corruptions(sizes))
    def case(fault):
        _check_kernel(compiled, tmp, fault, whole_run)

    case()


def test_any_corruption_of_a_kernels_files_is_found_before_numba_reads_it(
    compiled, tmp_path, monkeypatch
):
    monkeypatch.setenv("SIM_TACTILE_KERNELS", str(compiled[0]))  # restored afterwards
    _fuzz_kernels(compiled, tmp_path, 60, whole_run=False)


@pytest.mark.slow
def test_any_corruption_of_a_kernels_files_is_compiled_again_with_a_warning(
    compiled, tmp_path, monkeypatch
):
    monkeypatch.setenv("SIM_TACTILE_KERNELS", str(compiled[0]))
    _fuzz_kernels(compiled, tmp_path, 40, whole_run=True)
