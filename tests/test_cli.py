"""The plate commands, through the real console script."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sim_tactile.plates import get_plate, preset_names


def test_plates_list_json_is_the_python_api(cli):
    rows = json.loads(cli(["plates", "list", "--json"]).stdout)
    assert [r["name"] for r in rows] == preset_names()
    for r in rows:
        plate = get_plate(r["name"])
        assert (r["family"], r["params"], r["hash"]) == (plate.family, plate.params(), plate.hash)
    text = cli(["plates", "list"]).stdout.splitlines()
    assert text[0].split() == ["name", "family", "hash"] and len(text) == len(rows) + 1


@pytest.mark.slow
def test_plates_build_json_writes_the_four_files(cli, tmp_path):
    out = cli(["plates", "build", "multilayer3/grating-9", "--out", tmp_path, "--json"])
    doc = json.loads(out.stdout)
    assert doc["name"] == "multilayer3/grating-9"
    assert set(doc["files"]) == {"stl", "step", "mjcf", "png"}
    for k, ext in (("stl", "stl"), ("step", "step"), ("mjcf", "xml"), ("png", "png")):
        assert Path(doc["files"][k]) == tmp_path / f"multilayer3_grating-9.{ext}"
        assert Path(doc["files"][k]).stat().st_size > 0
    assert doc["geoms"] == {"box": 1, "mesh": 9}
    assert len(doc["hash"]) == 16


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (
            ["plates", "build", "finger7/nope", "--out", "x", "--json"],
            "'finger7/nope' is not a preset",
        ),
        (["plates", "build", "--out", "x", "--json"], "give a plate NAME or --all"),
    ],
)
def test_errors_exit_nonzero_with_one_line(cli, args, needle):
    out = cli(args, check=False)
    assert out.returncode != 0
    assert out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0]
