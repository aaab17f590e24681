"""The kernel folder proves what it holds (sim_tactile/_kernel_files.py, sim_tactile/_jit.py).

Each of numba's files (the ``.nbi`` index, the ``.nbc`` data) carries a digest that binds
its bytes to its name and its code version, checked before numba reads it. Before, a
truncated file gave ``UnpicklingError`` on every run, flipped bits could crash the
interpreter, a data file copied from another version's folder ran that version's physics,
and a full folder failed the run although the compile had succeeded. Each case here failed
then (one in-process flip crashed the interpreter with "Illegal instruction"; the slow test
flips bits in child processes, so that a crash is a failure, not the suite's end).

A small real kernel serves: ``rect_entry`` of sim/skin/clipped.py (Love's rectangle, a
scalar function), compiled afresh through :func:`sim_tactile._jit.njit` into a folder of
the test's own (``SIM_TACTILE_KERNELS``)."""

from __future__ import annotations

import errno
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from _kernels import ARGS, MODULE, compile_into, fresh, kernel_file, run
from numba.core import caching

from sim_tactile.sim.skin import clipped


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """A kernel folder holding the kernel (and its callee ``_F``), and its value."""
    folder = tmp_path_factory.mktemp("kernels")
    return folder, compile_into(folder)


@pytest.fixture
def kernels(reference, tmp_path, monkeypatch) -> Path:
    """A copy of the reference folder, in use."""
    folder = tmp_path / "kernels"
    shutil.copytree(reference[0], folder)
    monkeypatch.setenv("SIM_TACTILE_KERNELS", str(folder))
    return folder


def test_a_whole_folder_is_read_and_its_files_carry_their_digest(kernels, reference):
    assert run() == (reference[1], 1, 0, [])
    from sim_tactile._kernel_files import MAGIC

    for ext in ("nbi", "nbc"):
        assert kernel_file(kernels, ext).read_bytes().startswith(MAGIC)


def _compiled_again(reference, name: str, *words: str) -> None:
    value, hits, misses, said = run()
    assert (value, hits, misses) == (reference[1], 0, 1)
    assert said and name in said[0], said
    for w in words:
        assert w in said[0], said


@pytest.mark.parametrize("keep", [0, 10, 60, 0.5, 0.99], ids=lambda k: f"keep{k}")
@pytest.mark.parametrize("ext", ["nbi", "nbc"])
def test_a_truncated_file_is_compiled_again_naming_it(kernels, reference, ext, keep):
    path = kernel_file(kernels, ext)
    raw = path.read_bytes()
    path.write_bytes(raw[: int(keep * len(raw)) if isinstance(keep, float) else keep])
    _compiled_again(reference, path.name)
    assert run()[:3] == (reference[1], 1, 0)  # kept whole again


#: bits to flip in the data file: its digest line, the start, middle and end of its bytes
FLIPS = [8 * 30 + 1, 8 * 90 + 4, 8 * 400, 0.5, 0.75, -1]


@pytest.mark.parametrize("where", FLIPS)
def test_a_flipped_bit_in_a_data_file_is_compiled_again_naming_it(kernels, reference, where):
    path = kernel_file(kernels, "nbc")
    b = bytearray(path.read_bytes())
    bit = int(where * 8 * len(b)) if isinstance(where, float) else where % (8 * len(b))
    b[bit // 8] ^= 1 << (bit % 8)
    path.write_bytes(bytes(b))
    _compiled_again(reference, path.name)


def test_a_data_file_from_another_versions_folder_is_compiled_again(
    kernels, reference, monkeypatch
):
    """Compile the kernel as another code version would (another stamp, its own folder),
    then copy that version's data file over this version's."""
    import sim_tactile._jit as jit

    real = jit.kernel_stamp
    monkeypatch.setattr(jit, "kernel_stamp", lambda m: "0123456789abcdef")
    value, _, misses, _ = run()
    assert misses == 1
    monkeypatch.setattr(jit, "kernel_stamp", real)
    other = kernels / MODULE / "0123456789abcdef"
    (theirs,) = other.glob("clipped.rect_entry-*.nbc")
    ours = kernel_file(kernels, "nbc")
    assert ours.parent != other
    shutil.copyfile(theirs, ours)
    _compiled_again(reference, ours.name, "another version of the code")


def test_a_data_file_copied_under_another_kernels_name_is_compiled_again(kernels, reference):
    ours = kernel_file(kernels, "nbc")
    (other,) = ours.parent.glob("clipped._F-*.nbc")  # the callee's, in the same folder
    shutil.copyfile(other, ours)
    _compiled_again(reference, ours.name, "another kernel file")


def test_an_unreadable_file_is_compiled_again_naming_it(kernels, reference):
    path = kernel_file(kernels, "nbc")
    path.unlink()
    path.mkdir()  # opening it fails (permission bits would not bind for root)
    value, hits, misses, said = run()
    assert (value, hits, misses) == (reference[1], 0, 1)
    assert any(path.name in s and "cannot be read" in s for s in said), said
    assert any("nothing" in s for s in said), said  # nor can the new one be put there


def _no_folder_can_be_written(monkeypatch) -> None:
    """Every folder read-only, as numba finds out (a temporary file) and as it writes."""

    def refuse(*a, **k):
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(caching.tempfile, "TemporaryFile", refuse)
    monkeypatch.setattr(caching.IndexDataCacheFile, "_open_for_write", refuse)


def test_a_read_only_folder_serves_what_it_holds(kernels, reference, monkeypatch):
    _no_folder_can_be_written(monkeypatch)
    value, hits, misses, said = run()
    assert (value, hits, misses) == (reference[1], 1, 0)
    assert any(str(kernels) in s and "cannot be written" in s for s in said), said


def test_a_read_only_folder_lets_the_run_finish_keeping_nothing(tmp_path, reference, monkeypatch):
    monkeypatch.setenv("SIM_TACTILE_KERNELS", str(tmp_path / "kernels"))
    _no_folder_can_be_written(monkeypatch)
    value, hits, misses, said = run()
    assert (value, hits, misses) == (reference[1], 0, 1)
    assert any("keeps nothing" in s and "read-only" in s for s in said), said


def test_a_full_folder_lets_the_run_finish_keeping_nothing(tmp_path, reference, monkeypatch):
    monkeypatch.setenv("SIM_TACTILE_KERNELS", str(tmp_path / "kernels"))

    def full(self, path):
        raise OSError(errno.ENOSPC, "No space left on device", path)

    monkeypatch.setattr(caching.IndexDataCacheFile, "_open_for_write", full)
    value, hits, misses, said = run()
    assert (value, hits, misses) == (reference[1], 0, 1)
    assert any("keeps nothing" in s and "no space left" in s for s in said), said
    assert not list((tmp_path / "kernels").rglob("*.nb?"))


#: Flips tried in child processes (each about 4 s: an import and a compile).
CHILD_FLIPS = 5
_CHILD = """
import sys
from sim_tactile._jit import kernel_stamp, njit
from sim_tactile.sim.skin import clipped
print(njit(clipped.rect_entry.py_func)(*map(float, sys.argv[1:])))
"""


@pytest.mark.slow
def test_no_flipped_bit_in_a_data_file_crashes_the_interpreter(kernels, reference, tmp_path):
    """Flips over the whole data file, each in a child process (one crashed the
    interpreter with no message before): each ends with the right value and a warning."""
    path = kernel_file(kernels, "nbc")
    raw = path.read_bytes()
    env = {
        **__import__("os").environ,
        "SIM_TACTILE_KERNELS": str(kernels),
        "PYTHONPATH": str(Path(clipped.__file__).parents[3]),
    }
    for k in range(1, 1 + CHILD_FLIPS):
        bit = (k * 8 * len(raw)) // (CHILD_FLIPS + 1) + 3
        b = bytearray(raw)
        b[bit // 8] ^= 1 << (bit % 8)
        path.write_bytes(bytes(b))
        p = subprocess.run(
            [sys.executable, "-c", _CHILD, *map(str, ARGS)],
            env=env,
            capture_output=True,
            text=True,
            cwd=tmp_path,
        )
        assert p.returncode == 0, (bit, p.returncode, p.stderr[-1500:])
        assert float(p.stdout) == reference[1], bit
        assert path.name in p.stderr and "CacheWarning" in p.stderr, (bit, p.stderr[-1500:])
        path.write_bytes(raw)


def test_two_processes_saving_two_signatures_at_once_keep_each_ones_code(kernels):
    """Two processes compile two signatures of one kernel at once: each read the index
    before the other wrote it. numba named both data files ``.1.nbc``, so the index could
    send one signature to the other's code; each new entry now has a file of its own."""
    a, b, later = (fresh()._cache._cache_file for _ in range(3))
    for cache in (a, b):
        cache._load_index = dict  # the index as both read it: empty
    a.save(("signature", 1), "code for 1")
    b.save(("signature", 2), "code for 2")
    names = sorted(p.name for p in kernel_file(kernels, "nbi").parent.glob("*.nbc"))
    assert len(set(names)) == len(names) and len(names) >= 3, names  # with the kernel's own
    assert later.load(("signature", 2)) == "code for 2"
    assert later.load(("signature", 1)) in (None, "code for 1")  # lost from the index at worst
