"""Content hashes, code versions from the import graph, and derived seeds."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.hashing import (
    PACKAGE,
    code_version,
    content_hash,
    derive_seed,
    import_closure,
    imports_of,
    module_file,
)


def test_content_hash_is_the_canonical_json_of_the_data():
    a = {"b": [1, 2.5, "x"], "a": {"z": None, "y": True}}
    b = {"a": {"y": True, "z": None}, "b": [1, 2.5, "x"]}
    assert content_hash(a) == content_hash(b)
    assert len(content_hash(a)) == 64 and content_hash(a, 16) == content_hash(a)[:16]
    assert content_hash(a) != content_hash({**a, "b": [1, 2.5, "y"]})
    with pytest.raises(ConfigError, match="not JSON data"):
        content_hash({"x": object()})


def test_derived_seeds_keep_the_formulas_the_data_sets_were_made_with():
    # slides: SeedSequence([seed, plate, slide]) as a 63-bit integer; splits: a 32-bit one
    for seed, keys in ((0, (0, 0)), (7, (3, 11)), (2**40, (19, 49))):
        ss = np.random.SeedSequence([seed, *keys])
        assert derive_seed(seed, *keys, bits=63) == int(ss.generate_state(1, np.uint64)[0] >> 1)
        assert derive_seed(seed, *keys) == int(ss.generate_state(1)[0])
    assert 0 <= derive_seed(5, 1, bits=63) < 2**63 and 0 <= derive_seed(5, 1) < 2**32


def test_names_key_a_seed_by_what_it_is():
    s = {name: derive_seed(0, "model", name, 0) for name in ("lstm", "snn", "svm")}
    assert len(set(s.values())) == 3
    assert derive_seed(0, "model", "lstm", 0) == s["lstm"]  # independent of any list
    assert derive_seed(0, "model", "lstm", 1) != s["lstm"]
    for bad in (-1, 1.5, True):
        with pytest.raises(ConfigError, match="seed key"):
            derive_seed(0, bad)
    with pytest.raises(ConfigError, match="bits"):
        derive_seed(0, bits=16)


def test_the_import_closure_is_the_import_graphs():
    """Against grimp (the graph import-linter checks): every module that importing the root
    runs, following the imports of each module and of the packages each sits in."""
    grimp = pytest.importorskip("grimp", reason="grimp comes with the test extra import-linter")
    graph = grimp.build_graph(PACKAGE, cache_dir=None)
    for root in (f"{PACKAGE}.sim.slide", f"{PACKAGE}.plates.make.mjcf", f"{PACKAGE}.spikes"):
        want, todo = set(), [root]
        while todo:
            m = todo.pop()
            if m in want:
                continue
            want.add(m)
            parts = m.split(".")
            todo += [".".join(parts[:k]) for k in range(1, len(parts))]
            todo += list(graph.find_modules_directly_imported_by(m))
        assert set(import_closure(root)) == want, root
    for m in sorted(graph.modules):
        direct = set(graph.find_modules_directly_imported_by(m))
        assert direct <= imports_of(m), m


def test_code_version_follows_the_source_and_the_libraries():
    v = code_version(f"{PACKAGE}.plates.define.spec")
    assert len(v) == 16 and v == code_version(f"{PACKAGE}.plates.define.spec")
    assert v != code_version(f"{PACKAGE}.plates.define.spec", libraries=("numpy",))
    assert v != code_version(f"{PACKAGE}.sim.slide")
    with pytest.raises(ConfigError, match="not a module"):
        code_version(f"{PACKAGE}.no_such_module")


def test_a_code_version_hashes_its_closures_files_as_they_are_on_disk():
    """The sources are read once a process (``_source``) and shared by every code version:
    a version is the sha256 of its closure's names and files' bytes, read here afresh."""
    import hashlib

    root = f"{PACKAGE}.sim.step.held"
    code_version(f"{PACKAGE}.sim.slide")  # reads most of the same files first
    h = hashlib.sha256()
    for m in import_closure(root):
        h.update(m.encode() + b"\0" + module_file(m).read_bytes() + b"\0")
    assert code_version(root) == h.hexdigest()[:16]


_BLAS_PROBE = """
import json, sys
from threadpoolctl import ThreadpoolController
from sim_tactile.hashing import blas_kernel, one_blas_thread
first = sys.argv[1]
if first == "scipy":
    import scipy.linalg
kernel = blas_kernel()
before = "scipy.linalg" in sys.modules
with one_blas_thread():
    import scipy.linalg
    inside = [(i["filepath"], i["num_threads"]) for i in ThreadpoolController().info()
              if i["user_api"] == "blas"]
print(json.dumps({"kernel": kernel, "before": before, "inside": inside}))
"""


@pytest.mark.parametrize("first", ["scipy", "package"])
def test_scipys_blas_runs_on_one_thread_and_keys_alike_whatever_was_imported_first(first):
    """The BLAS limit and kernel no longer import scipy.linalg (0.15 s of a command's
    start-up): scipy's library is loaded alone, so scipy.linalg imported inside a slide
    still runs on one thread, and the kernel in cache keys is the same either way."""
    import json
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-c", _BLAS_PROBE, first], capture_output=True, text=True, check=True
    )
    got = json.loads(out.stdout)
    assert got["before"] is (first == "scipy")  # the package's own look imports no scipy.linalg
    libs = {path: n for path, n in got["inside"]}
    bundled = ("scipy.libs", "scipy/.dylibs")  # where a wheel keeps scipy's own library
    import importlib.util
    from pathlib import Path

    here = Path(importlib.util.find_spec("scipy").submodule_search_locations[0])
    if any((here.parent / "scipy.libs").glob("*openblas*")):
        assert any(b in p for p in libs for b in bundled), libs
    assert set(libs.values()) == {1}, libs  # every BLAS library, scipy's too, on one thread
    from sim_tactile.hashing import blas_kernel

    assert got["kernel"] == blas_kernel()
