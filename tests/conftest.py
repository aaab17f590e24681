"""Shared fixtures: one artefact cache per test session, so each preset is built once."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from sim_tactile.cache import ArtefactCache

#: The real data set of the first seed paper, found beside the project (never committed).
DATASET_DIR = Path(__file__).resolve().parents[2] / "shared" / "datasets" / "biotac_slide_20_50"


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
