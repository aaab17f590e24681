"""The contract's plate commands, through the real console script."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

EXE = shutil.which("sim-tactile", path=str(Path(sys.executable).parent)) or "sim-tactile"


def run(args: list[str], env: dict, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run([EXE, *args], env=env, capture_output=True, text=True, check=check)


def test_plates_list_json(cli_env):
    out = run(["plates", "list", "--json"], cli_env)
    rows = json.loads(out.stdout)
    names = {r["name"] for r in rows}
    assert {"finger7/ridges-4", "multilayer3/grating-9", "roughness8/ra-0.4"} <= names
    assert all(set(r) >= {"name", "family", "params", "hash"} for r in rows)
    assert len(rows) == 38


def test_plates_build_json_writes_the_four_files(cli_env, tmp_path):
    out = run(
        ["plates", "build", "multilayer3/grating-9", "--out", str(tmp_path), "--json"], cli_env
    )
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
def test_errors_exit_nonzero_with_one_line(cli_env, tmp_path, args, needle):
    out = run(args, cli_env, check=False)
    assert out.returncode != 0
    assert out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0]
