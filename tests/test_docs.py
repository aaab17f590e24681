"""The manual builds with warnings as errors, documents every public name, and its
tutorials run in their quick forms."""

from __future__ import annotations

import importlib
import re
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
#: the pages generated at build time (from the code), not written by hand
GENERATED = (
    DOCS / "reference" / "api",
    DOCS / "reference" / "tasks",
    DOCS / "results" / "leaderboard.md",
)
RESULTS = DOCS / "results"

#: a commit: 7 to 12 hex digits in backticks, or bare with both letters and digits
COMMIT = re.compile(r"`[0-9a-f]{7,12}`|\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,12}\b")
#: a command a reader can run, and the machine it ran on
COMMAND = re.compile(r"`(?:sim-tactile|python) [^`]+`")
MACHINE = re.compile(r"\b\d+ cores?\b")


def _pages() -> list[Path]:
    return sorted(p for p in DOCS.rglob("*.md") if not any(p.is_relative_to(g) for g in GENERATED))


def _tables(lines: list[str]) -> list[tuple[int, int]]:
    """The (first, end) line indices of each Markdown table outside code fences."""
    tables, start, fenced = [], None, False
    for i, line in enumerate([*lines, ""]):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        is_row = not fenced and line.startswith("|")
        if is_row and start is None:
            start = i
        elif not is_row and start is not None:
            tables.append((start, i))
            start = None
    return tables


def _header(lines: list[str], first: int) -> tuple[int, int]:
    """The (first, end) line indices of the paragraph just above the line ``first``."""
    end = first
    while end > 0 and not lines[end - 1].strip():
        end -= 1
    start = end
    while start > 0 and lines[start - 1].strip() and not lines[start - 1].startswith("#"):
        start -= 1
    return start, end


def _cells(row: str) -> list[str]:
    return [c.strip() for c in row.strip().strip("|").split("|")]


def history_in_results_page(page: Path) -> list[str]:
    """What breaks the results pages' rule: a table without a header paragraph that names
    a command, a machine and a commit (its own, or a commit column's), and a commit named
    anywhere but in such a header or a commit column."""
    lines = page.read_text().splitlines()
    allowed, faults = set(), []
    for first, end in _tables(lines):
        h0, h1 = _header(lines, first)
        header = " ".join(lines[h0:h1])
        columns = [i for i, c in enumerate(_cells(lines[first])) if "commit" in c.lower()]
        if not (COMMAND.search(header) and MACHINE.search(header)):
            faults.append(f"{page.name}:{first + 1}: no command and machine above the table")
        if not (COMMIT.search(header) or columns):
            faults.append(f"{page.name}:{first + 1}: no commit above the table or in a column")
        allowed.update(range(h0, h1))
        for i in range(first + 2, end):
            cells = _cells(lines[i])
            rest = [c for j, c in enumerate(cells) if j not in columns]
            if any(COMMIT.search(c) for c in rest):
                faults.append(f"{page.name}:{i + 1}: a commit outside the commit column")
            if columns and not any(COMMIT.search(cells[j]) for j in columns if j < len(cells)):
                faults.append(f"{page.name}:{i + 1}: a row without its commit")
            allowed.add(i)
    faults += [
        f"{page.name}:{i + 1}: {m.group()}"
        for i, line in enumerate(lines)
        if i not in allowed
        for m in [COMMIT.search(line)]
        if m
    ]
    return faults


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


def test_no_page_outside_the_results_names_a_commit():
    """History is in CHANGELOG.md and the commit messages, not in the manual."""
    found = [
        f"{p.relative_to(DOCS)}:{i}: {m.group()}"
        for p in _pages()
        if not p.is_relative_to(RESULTS)
        for i, line in enumerate(p.read_text().splitlines(), 1)
        for m in [COMMIT.search(line)]
        if m
    ]
    assert found == []


def test_each_results_table_says_its_command_machine_and_commit_once_above_it():
    # (the leaderboard's page is generated: each of its rows names its own commit and machine)
    pages = sorted(
        p for p in RESULTS.glob("*.md") if not any(p.is_relative_to(g) for g in GENERATED)
    )
    assert len(pages) >= 5
    assert [f for p in pages for f in history_in_results_page(p)] == []


def test_the_results_rule_finds_what_breaks_it(tmp_path):
    table = ["| a | b |", "|---|---|", "| 1 | 2 |"]
    good = ["Measured with `sim-tactile run x` on 2 cores at `abc1234`:", "", *table]
    column = ["Measured with `python b.py` on 2 cores:", "", "| a | commit |", "|---|---|"]
    cases = {
        "good": (good, 0),
        "column": ([*column, "| 1 | `abc1234` |"], 0),
        "no header": (["# Title", "", *table], 2),
        "no commit": (["With `python b.py` on 2 cores:", *table], 1),
        "prose": ([*good, "", "It moved since `abc1234`."], 1),
        "inline": ([*good[:2], *table[:2], "| 1 at 9f3e2d1 | 2 |"], 1),
        "row without": ([*column, "| 1 | |"], 1),
        "column title": ([*good[:2], "| at `abc1234` | b |", *table[1:]], 1),
    }
    for name, (text, faults) in cases.items():
        page = tmp_path / f"{name}.md"
        page.write_text("\n".join(text) + "\n")
        assert len(history_in_results_page(page)) == faults, (name, history_in_results_page(page))


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


#: the tutorials that load finger7-v1's quick data share a worker with the other tests that
#: do (test_tasks_sim, test_user_methods, test_readme), so that one of them simulates it
_F7 = {"your_method"}


@pytest.mark.slow
@pytest.mark.parametrize(
    "script",
    [
        pytest.param(p, marks=pytest.mark.xdist_group("finger7-v1-quick")) if p.stem in _F7 else p
        for p in TUTORIALS
    ],
    ids=[p.stem for p in TUTORIALS],
)
def test_tutorial_runs_in_its_quick_form(script, tmp_path, monkeypatch, cache_dir):
    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    module = runpy.run_path(str(script))
    assert module["main"](tmp_path / "out", quick=True) is not None
