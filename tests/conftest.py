"""Shared fixtures: one artefact cache per test session, so each preset is built once."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from sim_tactile.cache import ArtefactCache

_NAME = "biotac_slide_20_50"


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


DATASET_DIR = _find_dataset()


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
