"""The manual builds with warnings as errors, documents every public name, and its
tutorials run in their quick forms."""

from __future__ import annotations

import importlib
import runpy
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
sys.path.insert(0, str(DOCS))

import _docstrings  # noqa: E402
import _gen  # noqa: E402

TUTORIALS = sorted((DOCS / "tutorials").glob("*.py"))


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    """The manual built as ``make docs`` builds it (-W: a warning fails)."""
    pytest.importorskip("sphinx")
    out = tmp_path_factory.mktemp("docs")
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-W",
            "--keep-going",
            "-q",
            "-b",
            "html",
            str(DOCS),
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    return out


@pytest.mark.slow
def test_the_manual_builds_and_documents_every_public_name(built):
    from sphinx.util.inventory import InventoryFile

    with open(built / "objects.inv", "rb") as f:
        inv = InventoryFile.load(f, "", lambda base, uri: uri)
    documented = {
        name for kind, entries in inv.items() if kind.startswith("py:") for name in entries
    }
    missing = []
    for package in _gen.public_packages():
        for name in importlib.import_module(package).__all__:
            role, target = _gen.canonical(package, name)
            if target not in documented:
                missing.append(f"{package}.{name} (as {target})")
    assert missing == []
    assert (built / "reference" / "tasks" / "finger7-v1.html").is_file()
    assert "ablate" in (built / "reference" / "cli.html").read_text()


def test_public_packages_are_found():
    found = set(_gen.public_packages())
    assert {"sim_tactile.plates", "sim_tactile.tasks", "sim_tactile.spikes"} <= found


def test_every_tutorial_has_a_page_that_shows_it():
    pages = "\n".join(p.read_text() for p in (DOCS / "tutorials").glob("*.md"))
    assert TUTORIALS
    for script in TUTORIALS:
        assert f"literalinclude:: {script.name}" in pages.replace("} ", ":: "), script.name


def test_markdown_tables_in_docstrings_become_list_tables():
    rest = _docstrings.to_rest(
        ["Sensors:", "", "| a | b |", "|---|---|", "| 1 | 2 |", "", "|x| is a norm"]
    )
    assert ".. list-table::" in rest and "   * - 1" in rest and "\\|x\\| is a norm" in rest


@pytest.mark.slow
@pytest.mark.parametrize("script", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_tutorial_runs_in_its_quick_form(script, tmp_path, monkeypatch, cache_dir):
    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    module = runpy.run_path(str(script))
    assert module["main"](tmp_path / "out", quick=True) is not None
