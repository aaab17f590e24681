"""A compiled kernel is never older than its source (sim_tactile/_jit.py).

numba's own cache checks only the file of the kernel it loads: a kernel that calls a jitted
function of another file kept the old callee after an edit, and an edited simulator stored
its old physics under its new key. These tests edit a callee *in another file* of a copy of
the package, in place, and check that the next process computes with the new code (and that
an unedited package is still served from the cache)."""

from __future__ import annotations

import ast
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import sim_tactile
from sim_tactile import hashing
from sim_tactile._jit import kernel_root, kernel_stamp, njit

_CALLEE = """
from ._jit import njit

@njit
def shift(x):
    return x + {shift!r}
"""
_CALLER = """
from ._jit import njit
from ._probe_callee import shift

@njit
def twice_shifted(x):
    return 2.0 * shift(x)
"""
_RUN = """
import json
from sim_tactile._probe_caller import twice_shifted
value = twice_shifted(1.0)
print(json.dumps({"value": value, "hits": sum(twice_shifted.stats.cache_hits.values()),
                  "misses": sum(twice_shifted.stats.cache_misses.values())}))
"""


def _copy_package(tmp_path: Path, *, with_caches: bool) -> Path:
    """A copy of the package (its compiled caches too, or none) and its preset assets."""
    src = Path(sim_tactile.__file__).parent
    pkg = tmp_path / "copy" / "sim_tactile"
    ignore = None if with_caches else shutil.ignore_patterns("__pycache__")
    shutil.copytree(src, pkg, ignore=ignore)
    shutil.copytree(src.parent / "assets", pkg / "assets", ignore=ignore)
    return pkg


def _env(pkg: Path, tmp_path: Path, kernels: Path | None = None) -> dict:
    """The copy's environment: its own kernel folder (``kernels``, default a new one), so
    that nothing it compiles reaches the machine's."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(
        PYTHONPATH=str(pkg.parent),
        SIM_TACTILE_CACHE=str(tmp_path / "cache"),
        SIM_TACTILE_KERNELS=str(kernels or tmp_path / "kernels"),
    )
    return env


def _python(code: str, env: dict, cwd: Path) -> str:
    p = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, cwd=cwd
    )
    assert p.returncode == 0, p.stderr[-3000:]
    return p.stdout


@pytest.mark.slow
def test_a_kernel_follows_an_edit_of_a_jitted_callee_in_another_file(tmp_path):
    pkg = _copy_package(tmp_path, with_caches=False)
    (pkg / "_probe_caller.py").write_text(_CALLER)
    (pkg / "_probe_callee.py").write_text(_CALLEE.format(shift=1.0))
    env = _env(pkg, tmp_path)

    def run() -> dict:
        return json.loads(_python(_RUN, env, tmp_path))

    first = run()
    assert first == {"value": 4.0, "hits": 0, "misses": 1}
    assert run() == {"value": 4.0, "hits": 1, "misses": 0}  # served from the disk cache
    (pkg / "_probe_callee.py").write_text(_CALLEE.format(shift=2.0))  # the caller's file as it was
    edited = run()
    assert edited["value"] == 6.0, "the cached kernel kept its old callee"
    assert edited["misses"] == 1
    assert run() == {"value": 6.0, "hits": 1, "misses": 0}  # the new code is cached in turn


_COUNT = """
from sim_tactile.cli._common import kernels_to_compile
print(kernels_to_compile(("sim_tactile._probe_caller",)))
"""


@pytest.mark.slow
def test_the_first_run_notice_counts_a_stale_kernel_as_one_to_compile(tmp_path):
    """The notice's count agrees with the versioned cache: a kernel whose cached copy numba
    would not load (its callee in another file edited) is still to compile, although its
    cache index exists."""
    pkg = _copy_package(tmp_path, with_caches=False)
    (pkg / "_probe_caller.py").write_text(_CALLER)
    (pkg / "_probe_callee.py").write_text(_CALLEE.format(shift=1.0))
    env = _env(pkg, tmp_path)

    def count() -> int:
        return int(_python(_COUNT, env, tmp_path))

    fresh = count()  # nothing of the copy compiled yet (the package's other kernels too)
    _python(_RUN, env, tmp_path)
    assert count() == fresh - 2  # the caller and its callee, now on disk
    (pkg / "_probe_callee.py").write_text(_CALLEE.format(shift=2.0))
    assert count() == fresh  # both indexes are still on disk, and both are stale


def test_the_stamp_follows_the_modules_a_kernel_imports():
    held = hashing.import_closure("sim_tactile.sim.step.held")
    assert "sim_tactile.sim.collide.shapes" in held  # through the collider
    assert kernel_stamp("sim_tactile.sim.step.held") != kernel_stamp(
        "sim_tactile.sim.collide.shapes"
    )
    assert kernel_stamp("sim_tactile.sim.step.held") == hashing.code_version(
        "sim_tactile.sim.step.held", libraries=("numba", "numpy")
    )


def test_njit_refuses_an_unversioned_cache_and_compiles_what_it_is_given():
    with pytest.raises(TypeError, match="cache"):
        njit(cache=True)

    def add(a, b):
        return a + b

    assert njit(add)(2, 3) == 5


def test_the_import_scan_finds_every_import_of_every_module():
    """hashing.import_statements (a line scan) against a whole-module parse: the same
    statements in every module of the package, so code versions are unchanged by it."""
    root = Path(sim_tactile.__file__).parent
    for f in sorted(root.rglob("*.py")):
        src = f.read_bytes()
        whole = sorted(
            ast.dump(n)
            for n in ast.walk(ast.parse(src))
            if isinstance(n, ast.Import | ast.ImportFrom)
        )
        assert sorted(ast.dump(n) for n in hashing.import_statements(src)) == whole, f


_SLIDE = """
import sys
import numpy as np
from sim_tactile.sim import Protocol, simulate
proto = Protocol(speed_m_s=0.06, force_n=1.0, duration_s=0.3, start="texture")
res = simulate("textures20/cylinders-3.0mm", "grid3x3", protocol=proto, fidelity="L0", seed=1)
np.save(sys.argv[1], res.recording.data)
"""


@pytest.mark.slow
def test_a_slide_moves_when_a_collider_shape_in_another_file_is_edited(tmp_path):
    """The tracker's case: raise the cylinders' tops (sim/collide/shapes.py::cylinder_distance,
    which the compiled collider in sim/collide/primitive.py calls) by 0.2 mm in place. The next
    slide moves (it was the old slide bit for bit), the kernels of the modules that import the
    shapes are compiled again under their new stamp, and a kernel that does not (the contact
    solve's) is served as it was. (That a recompiled kernel computes the edited code is the
    fast test above: a fresh compile of a whole slide here would cost a minute of the suite.)
    The copy starts from the machine's compiled kernels, copied."""
    pkg = _copy_package(tmp_path, with_caches=False)
    kernels = tmp_path / "kernels"
    if kernel_root().is_dir():
        shutil.copytree(kernel_root(), kernels)
    env = _env(pkg, tmp_path, kernels)

    def slide(name: str) -> np.ndarray:
        out = tmp_path / f"{name}.npy"
        subprocess.run([sys.executable, "-c", _SLIDE, str(out)], env=env, check=True, cwd=tmp_path)
        return np.load(out)

    def stamps() -> dict[str, set[str]]:
        return {d.name: {s.name for s in d.iterdir()} for d in kernels.iterdir() if d.is_dir()}

    before = slide("before")
    kept = stamps()
    shapes = pkg / "sim" / "collide" / "shapes.py"
    text = shapes.read_text()
    old = "    if qr <= 0.0 and upright:\n        return lz - hz\n"
    assert old in text
    shapes.write_text(text.replace(old, old.replace("lz - hz", "lz - hz - 0.0002")))
    after = slide("after")
    assert not np.array_equal(after, before), "the cached collider kept the old shapes"
    now = stamps()
    renewed = {m for m in now if now[m] - kept.get(m, set())}
    assert {"sim_tactile.sim.collide.primitive", "sim_tactile.sim.step.held"} <= renewed
    assert "sim_tactile.sim.skin.contact.kernels" in kept
    assert "sim_tactile.sim.skin.contact.kernels" not in renewed


def test_a_module_keeps_its_most_recent_code_versions(tmp_path):
    """The kernel folder keeps the newest versions of a module beside the one in use."""
    import os

    from sim_tactile._jit import KEEP_VERSIONS, _prune

    module = tmp_path / "sim_tactile.x"
    for k in range(KEEP_VERSIONS + 3):
        d = module / f"v{k}"
        d.mkdir(parents=True)
        os.utime(d, (1000 + k, 1000 + k))
    _prune(module / "v0")  # the oldest, used again now
    kept = {d.name for d in module.iterdir()}
    assert len(kept) == KEEP_VERSIONS and "v0" in kept
    assert kept == {"v0", *(f"v{k}" for k in range(4, KEEP_VERSIONS + 3))}


@pytest.mark.slow
def test_a_data_file_from_another_versions_folder_does_not_run_its_physics(tmp_path):
    """Version A (callee shift 1) and version B (shift 2) each compile into their own
    folder; B's compiled caller is copied over A's, then B's whole folder into A's. A
    computes A's value (it ran B's, 6 instead of 4, with exit 0), warning of the file, and
    compiles it again."""
    pkg = _copy_package(tmp_path, with_caches=False)
    (pkg / "_probe_caller.py").write_text(_CALLER)
    callee = pkg / "_probe_callee.py"
    env = _env(pkg, tmp_path)
    kernels = tmp_path / "kernels" / "sim_tactile._probe_caller"

    def run() -> tuple[dict, str]:
        p = subprocess.run(
            [sys.executable, "-c", _RUN], env=env, capture_output=True, text=True, cwd=tmp_path
        )
        assert p.returncode == 0, p.stderr[-3000:]
        return json.loads(p.stdout), p.stderr

    callee.write_text(_CALLEE.format(shift=1.0))
    assert run()[0]["value"] == 4.0
    (a,) = kernels.iterdir()
    callee.write_text(_CALLEE.format(shift=2.0))
    assert run()[0]["value"] == 6.0
    (b,) = set(kernels.iterdir()) - {a}
    callee.write_text(_CALLEE.format(shift=1.0))
    (theirs,) = b.glob("*.nbc")
    (ours,) = a.glob("*.nbc")
    shutil.copyfile(theirs, ours)  # B's compiled caller under A's name
    got, err = run()
    assert got == {"value": 4.0, "hits": 0, "misses": 1}, err[-2000:]
    assert ours.name in err and "another version of the code" in err
    assert run()[0] == {"value": 4.0, "hits": 1, "misses": 0}
    for f in b.iterdir():  # the whole of B's folder copied into A's (`cp B/* A/`)
        shutil.copyfile(f, a / f.name)
    got, err = run()
    assert got == {"value": 4.0, "hits": 0, "misses": 1}, err[-2000:]
    assert ".nbi" in err and "another version of the code" in err
