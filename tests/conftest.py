"""Shared fixtures: one artefact cache per test session (each preset is built once), the
console script, and the real data set (tests that need it skip, saying why, without it)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sim_tactile.cache import SETUP, ArtefactCache, forget_process_memos

_NAME = "biotac_slide_20_50"
#: The console script of this environment.
EXE = shutil.which("sim-tactile", path=str(Path(sys.executable).parent)) or "sim-tactile"


def _find_dataset() -> Path:
    """The real data set of the first seed paper (never committed): ``$SIM_TACTILE_DATASETS``,
    else ``shared/datasets`` beside the checkout, else the workplace's shared folder. The
    first that exists; else the first candidate (the tests that need it then skip)."""
    env = os.environ.get("SIM_TACTILE_DATASETS")
    cands = [Path(env) / _NAME] if env else []
    cands += [
        Path(__file__).resolve().parents[2] / "shared" / "datasets" / _NAME,
        Path("/work/shared/datasets") / _NAME,
    ]
    return next((c for c in cands if c.is_dir()), cands[0])


@pytest.fixture(scope="session")
def dataset_dir() -> Path:
    """The real data set's folder; the test skips, naming the path, when it is absent."""
    path = _find_dataset()
    if not path.is_dir():
        pytest.skip(f"real data set not found at {path} (set SIM_TACTILE_DATASETS)")
    return path


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("cache")


@pytest.fixture(scope="session")
def cache(cache_dir) -> ArtefactCache:
    return ArtefactCache(cache_dir)


@pytest.fixture
def cli_env(cache_dir) -> dict:
    """Environment for CLI subprocesses that shares the session's cache."""
    env = dict(os.environ)
    env["SIM_TACTILE_CACHE"] = str(cache_dir)
    env["MPLBACKEND"] = "Agg"
    return env


@pytest.fixture
def cli(cli_env):
    """Run the console script: ``cli(args, check=True, env=None, timeout=600)`` returns the
    completed process (stdout and stderr as text); ``cli.exe`` is its path."""

    def run(args, *, check: bool = True, env: dict | None = None, timeout: float = 600):
        return subprocess.run(
            [EXE, *(str(a) for a in args)],
            env=env or cli_env,
            capture_output=True,
            text=True,
            check=check,
            timeout=timeout,
        )

    run.exe = EXE
    return run


@pytest.fixture
def fresh_memo():
    """The test starts, and leaves, with nothing kept in the process: the set-up arrays, the
    compiled scene models and every other in-process memo
    (:func:`~sim_tactile.cache.forget_process_memos`). Gives the set-up memo
    (:data:`~sim_tactile.cache.SETUP`)."""
    forget_process_memos()
    yield SETUP
    forget_process_memos()


@pytest.fixture(scope="session")
def fake_icub(tmp_path_factory) -> Path:
    """compiled_data/ like the release's, 4 materials x 10 slides: material k vibrates taxel
    patch k at 2 + 3 k Hz on top of a level k (so every model can tell them apart)."""
    root = tmp_path_factory.mktemp("icub")
    (root / "compiled_data").mkdir()
    rng = np.random.default_rng(0)
    t = np.arange(75) / 50.0
    for f in ("test", "val_0", "val_1", "val_2", "val_3"):
        y = np.repeat(np.arange(4), 2)
        x = rng.normal(0, 0.2, size=(8, 6, 10, 75)).astype(np.float32)
        for i, k in enumerate(y):
            x[i, k] += k + np.sin(2 * np.pi * (2 + 3 * k) * t + rng.uniform(0, 6))
        np.save(root / "compiled_data" / f"icub_{f}.npy", x)
        np.save(root / "compiled_data" / f"labels_{f}.npy", y)
    return root
