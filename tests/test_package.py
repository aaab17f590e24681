"""The package installs without the Makefile: a wheel that carries its assets, installed in
a fresh virtual environment, runs a task's quick form from a folder outside the repository;
its metadata builds without a warning."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tomllib
import zipfile
from pathlib import Path

import pytest

import sim_tactile

ROOT = Path(__file__).resolve().parents[1]


def test_license_citation_and_changelog_exist_and_agree():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert meta["license"] == "Apache-2.0" and meta["license-files"] == ["LICENSE"]
    assert "Apache License" in (ROOT / "LICENSE").read_text()
    cff = (ROOT / "CITATION.cff").read_text()
    assert f'version: "{sim_tactile.__version__}"' in cff and "license: Apache-2.0" in cff
    assert "## [Unreleased]" in (ROOT / "CHANGELOG.md").read_text()
    assert "version" in meta.get("dynamic", []) and "version" not in meta


#: How many kernels a quick run would compile now (what `run` asks before it says so).
_TO_COMPILE = (
    "from sim_tactile.cli._common import kernels_to_compile; "
    "print(kernels_to_compile(('sim_tactile.sim.slide', 'sim_tactile.encoders')))"
)


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> tuple[Path, str]:
    out = tmp_path_factory.mktemp("wheel")
    # built from a copy of what the package is made of: setuptools builds in the source's own
    # build/ folder, which a build cut short elsewhere would leave half full
    src = tmp_path_factory.mktemp("src")
    skip = shutil.ignore_patterns("__pycache__", "*.egg-info")
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(ROOT / name, src / name)
    for name in ("sim_tactile", "assets"):
        shutil.copytree(ROOT / name, src / name, ignore=skip)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "-w",
            str(out),
            str(src),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return next(out.glob("sim_tactile-*.whl")), proc.stdout + proc.stderr


@pytest.mark.slow
def test_the_wheel_carries_the_assets_and_builds_without_warnings(wheel):
    path, log = wheel
    names = set(zipfile.ZipFile(path).namelist())
    assert "sim_tactile/sim/plan/measured_errors.json" in names
    assert "sim_tactile/assets/plates/finger7/ridges-4.toml" in names
    assert "sim_tactile/assets/sensors/grid3x3.toml" in names
    assert "sim_tactile/sensors/calibrations/biotac19.toml" in names
    assert any(n.endswith("licenses/LICENSE") for n in names)
    warnings = [
        line for line in log.splitlines() if "warning" in line.lower() and "byte-compil" not in line
    ]
    assert warnings == []


@pytest.mark.slow
def test_the_wheel_runs_a_quick_task_in_a_fresh_environment(wheel, tmp_path):
    path, _ = wheel
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    py = venv / "bin" / "python"
    site = Path(
        subprocess.check_output(
            [str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], text=True
        ).strip()
    )
    # the dependencies: this interpreter's (a .pth file); the package: only the wheel's,
    # installed into the new environment as its own pip would (pip --python), so that the
    # console script runs the new interpreter; `pip install --target` would write this
    # interpreter into its first line, and the command would import this checkout instead
    # (--ignore-installed: a checkout that the .pth file or PYTHONPATH shows is not this one)
    (site / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH",)}
    pip = [sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps"]
    subprocess.run(
        [*pip, "--ignore-installed", str(path)], check=True, capture_output=True, env=env
    )
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    # the machine's compiled kernels serve the wheel too (they are kept by content,
    # sim_tactile/_jit.py): it compiles only what this suite has not compiled yet
    env.update(SIM_TACTILE_CACHE=str(tmp_path / "cache"), MPLBACKEND="Agg")
    where = subprocess.check_output(
        [str(py), "-c", "import sim_tactile; print(sim_tactile.__file__)"],
        cwd=elsewhere,
        env=env,
        text=True,
    )
    assert str(ROOT) not in where and str(site) in where
    exe = venv / "bin" / "sim-tactile"
    assert str(py) in exe.read_text()[:400]  # its first line: this environment's python
    to_compile = subprocess.check_output(
        [str(py), "-c", _TO_COMPILE], cwd=elsewhere, env=env, text=True
    ).strip()
    proc = subprocess.run(
        [str(exe), "run", "finger7-v1", "--quick", "--out", "out", "--json"],
        cwd=elsewhere,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = json.loads(proc.stdout)
    assert report["task"] == "finger7-v1" and report["results"]
    # the first-run notice only where the run compiles: never with every kernel on disk,
    # and never on a second run, which finds what the first compiled
    notice = "compiling the package's kernels once" in proc.stderr
    assert not notice or to_compile not in ("0", "None"), (to_compile, proc.stderr[-2000:])
    assert (elsewhere / "out" / "report.md").is_file()
    again = subprocess.run(
        [str(exe), "run", "finger7-v1", "--quick", "--out", "out2", "--classifiers", "svm"],
        cwd=elsewhere,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert again.returncode == 0 and "compiling" not in again.stderr, again.stderr[-2000:]
