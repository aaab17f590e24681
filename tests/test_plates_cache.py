"""The content-addressed cache: hits never import cadquery, builds are byte-identical
across processes, writes are atomic."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from sim_tactile.cache import ArtefactCache, atomic_write
from sim_tactile.plates import build, get_plate, load_heightmap, surface_of
from sim_tactile.plates.make.build import artefact_key

_SCRIPT = """
import json, sys
from pathlib import Path
from sim_tactile.cache import ArtefactCache
from sim_tactile.plates import build
res = build(sys.argv[1], cache=ArtefactCache(Path(sys.argv[2])), kinds=tuple(sys.argv[3].split(",")))
print(json.dumps({"cached": res.cached, "files": {k: str(v) for k, v in res.files.items()},
                  "cadquery": "cadquery" in sys.modules}))
"""


def _build_in_subprocess(name: str, root, kinds: str) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", _SCRIPT, name, str(root), kinds],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["multilayer3/grating-9", "roughness8/ra-6.3"])
def test_same_parameters_give_identical_bytes_across_processes(name, tmp_path):
    kinds = "stl,mjcf,heightmap"
    a = _build_in_subprocess(name, tmp_path / "a", kinds)
    b = _build_in_subprocess(name, tmp_path / "b", kinds)
    assert not any(a["cached"].values()) and not any(b["cached"].values())
    for k in kinds.split(","):
        assert open(a["files"][k], "rb").read() == open(b["files"][k], "rb").read(), k
    # a hit in a fresh process returns the same files and never imports cadquery
    c = _build_in_subprocess(name, tmp_path / "a", kinds)
    assert all(c["cached"].values())
    assert c["cadquery"] is False
    assert c["files"] == a["files"]


def test_heightmap_artefact_is_the_analytic_map(cache):
    xs, ys, z = load_heightmap("finger7/bumps-3x3", cache=cache)
    plate = get_plate("finger7/bumps-3x3")
    assert z.shape == (len(ys), len(xs))
    np.testing.assert_array_equal(z, surface_of(plate).height(xs[None, :], ys[:, None]))


def test_key_depends_on_parameters_kind_and_settings():
    a, b = get_plate("finger7/ridges-2"), get_plate("finger7/ridges-4")
    assert artefact_key(a, "stl") != artefact_key(b, "stl")
    assert artefact_key(a, "stl") != artefact_key(a, "step")
    assert artefact_key(a, "stl") == artefact_key(get_plate("finger7/ridges-2"), "stl")


def test_atomic_write_keeps_the_old_file_when_interrupted(tmp_path, monkeypatch):
    target = tmp_path / "x" / "artefact.bin"
    atomic_write(target, b"old")

    def boom(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr("os.replace", boom)
    with pytest.raises(KeyboardInterrupt):
        atomic_write(target, b"new-but-interrupted")
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in target.parent.iterdir()) == ["artefact.bin"]  # no temp left


def test_build_copies_to_out_dir_with_slug_names(tmp_path, cache):
    res = build("finger7/ridges-4", tmp_path / "out", cache=cache)
    assert {p.name for p in (tmp_path / "out").iterdir()} == {
        "finger7_ridges-4.stl",
        "finger7_ridges-4.step",
        "finger7_ridges-4.xml",
        "finger7_ridges-4.png",
    }
    assert res.files["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert b"ISO-10303-21" in res.files["step"].read_bytes()[:100]
    again = build("finger7/ridges-4", tmp_path / "out", cache=cache)
    assert all(again.cached.values())
    assert isinstance(ArtefactCache.default().root.name, str)
