"""The manual builds with warnings as errors, documents every public name, and the code of
its tutorials and how-to guides, shown in the pages themselves, runs as written."""

from __future__ import annotations

import importlib
import os
import re
import subprocess
import sys
import sysconfig
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
sys.path.insert(0, str(DOCS))

import _docstrings  # noqa: E402
import _gen  # noqa: E402

#: the pages whose ```python blocks are their tested source (the code a reader sees where
#: the page is browsed, on the repository's site too): tutorials and how-to guides
CODE_PAGES = sorted([*(DOCS / "tutorials").glob("*.md"), *(DOCS / "how-to").glob("*.md")])
#: a ```toml block whose first line is ``# NAME.toml ...`` is a file the page's code reads
FILE_BLOCK = re.compile(r"```toml\n(# ([\w.-]+\.toml)\b.*?)```", re.S)
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


#: The extras besides the manual's own ([docs]) and the tests' ([test]): `make docs` and a
#: reader's `pip install ".[docs]"` install none of them.
OTHER_EXTRAS = ("learn", "ray", "tonic", "hub", "nir", "neurobench")


def extras_modules() -> list[str]:
    """The top-level modules of the other extras' distributions (their names: torch, ray,
    tonic, datasets, pyarrow, mlcroissant, nir, snntorch, nirtorch; tqdm is a core one)."""
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    core = {re.split(r"[<>=\[ ]", d)[0] for d in meta["dependencies"]}
    names = {
        re.split(r"[<>=\[ ]", d)[0]
        for extra in OTHER_EXTRAS
        for d in meta["optional-dependencies"][extra]
    }
    return sorted(names - core)


#: Sphinx run as after `pip install ".[docs]"`, not editable: ``python -S`` runs no .pth file,
#: so the editable install's finder (which maps assets/ into the package) is not there, and
#: the other extras' modules are not found (as where they are not installed).
BUILD = """
import sys
BLOCKED = set(sys.argv[1].split(","))
class NotInstalled:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, NotInstalled())
from sphinx.cmd.build import main
sys.exit(main(sys.argv[2:]))
"""


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> Path:
    """The manual built as a reader builds it after ``pip install ".[docs]"`` (a regular
    install, only the [docs] extra: :data:`BUILD`), as ``make docs`` does (-W: a warning
    fails)."""
    pytest.importorskip("sphinx")
    out = tmp_path_factory.mktemp("docs")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = sysconfig.get_paths()["purelib"]  # the libraries, no .pth run
    args = ["-W", "--keep-going", "-q", "-b", "html", str(DOCS), str(out)]
    proc = subprocess.run(
        [sys.executable, "-S", "-c", BUILD, ",".join(extras_modules()), *args],
        capture_output=True,
        text=True,
        timeout=900,
        env=env,
        cwd=out,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    return out


def test_the_manual_needs_only_its_own_extra():
    """`make docs` installs the [docs] extra, not the tests' and the bridges' extras (the
    build above runs without them); the modules those extras bring are what it hides."""
    rule = re.search(r"^docs: (.*)$", (ROOT / "Makefile").read_text(), flags=re.M)[1]
    stamp = re.search(r"^\$\(STAMP_DOCS\):.*\n\t(.*)$", (ROOT / "Makefile").read_text(), re.M)
    assert rule.strip() == "$(STAMP_DOCS)" and stamp[1].endswith("install -q -e '.[docs]'")
    assert {"torch", "tonic", "nir", "datasets", "ray"} <= set(extras_modules())
    assert "tqdm" not in extras_modules()


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


def test_the_architecture_page_names_every_part_of_the_package_and_every_task():
    """The hand-written map follows the code: each subpackage and top-level module, each
    floor of sim/, and each task id is named on it."""
    from sim_tactile.tasks import task_ids

    page = (DOCS / "explanation" / "architecture.md").read_text()
    pkg = ROOT / "sim_tactile"
    parts = [f"{p.name}/" for p in pkg.iterdir() if (p / "__init__.py").is_file()]
    parts += [p.name for p in pkg.glob("*.py") if p.name != "__init__.py"]
    parts += [f"{p.name}/" for p in (pkg / "sim").iterdir() if (p / "__init__.py").is_file()]
    parts += [f"`{t}`" for t in task_ids()]
    assert [p for p in parts if p not in page] == []


def test_the_file_format_page_names_every_key_the_readers_take():
    """Each key a configuration, sensor file or plate reference may hold is on the file
    formats page (the readers declare them: the page follows them)."""
    from dataclasses import fields

    from sim_tactile.plates.user import Source

    from sim_tactile.sensors import files
    from sim_tactile.slides.config import RANDOMISE, TOP_KEYS

    page = (DOCS / "reference" / "file-formats.md").read_text()
    keys = [*TOP_KEYS, *RANDOMISE, *files.TOP_KEYS, *files.LAYOUT_KEYS, *files.GRID_KEYS]
    keys += [f.name for f in fields(Source) if f.name not in ("path", "function")]
    assert sorted({k for k in keys if f"`{k}`" not in page and f"[{k}]" not in page}) == []
    assert "heightmap" in page and "columns run along the slide" in page


def test_the_file_format_page_holds_the_knobs_as_they_are_declared():
    """The configuration table's rows of the knobs of how a slide is computed are those their
    declaration writes (sim.plan.options.KNOBS): a knob added or changed there is a failing
    test until the page follows."""
    from sim_tactile.sim.plan.options import reference_rows

    page = (DOCS / "reference" / "file-formats.md").read_text().splitlines()
    assert [r for r in reference_rows() if r not in page] == []


def test_every_picture_is_shown_in_the_manual():
    """Each figure in docs/img is on a page (a picture nobody sees is a page not written)."""
    text = "\n".join(p.read_text() for p in _pages())
    assert [p.name for p in (DOCS / "img").glob("*.png") if f"img/{p.name}" not in text] == []


def test_the_examples_link_to_files_that_exist():
    """The examples' READMEs are read on the repository's site, outside the manual's build
    (which checks its own links): each relative link leads to a file."""
    dead = [
        f"{page.relative_to(ROOT)}: {target}"
        for page in (ROOT / "examples").rglob("*.md")
        for target in re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", page.read_text())
        if not target.startswith("http") and not (page.parent / target).exists()
    ]
    assert dead == []


def test_public_packages_are_found():
    found = set(_gen.public_packages())
    assert {"sim_tactile.plates", "sim_tactile.tasks", "sim_tactile.spikes"} <= found


def page_code(page: Path) -> tuple[str, dict[str, str]]:
    """A page's Python (its ```python blocks, in order) and the files it names (its
    :data:`FILE_BLOCK` blocks)."""
    text = page.read_text()
    code = "\n".join(re.findall(r"```python\n(.*?)```", text, flags=re.S))
    return code, {name: body for body, name in FILE_BLOCK.findall(text)}


def test_tutorials_and_how_tos_show_their_code_in_the_page():
    """No page includes its code from a file (browsed on the repository's site, a
    literalinclude shows nothing); every tutorial has Python to run, and the folders hold
    no script beside the pages."""
    assert [p.name for p in DOCS.rglob("*.md") if "literalinclude" in p.read_text()] == []
    assert list((DOCS / "tutorials").glob("*.py")) + list((DOCS / "how-to").glob("*.py")) == []
    tutorials = [p for p in CODE_PAGES if p.parent.name == "tutorials"]
    assert len(tutorials) >= 3 and all(page_code(p)[0] for p in tutorials)
    code, files = page_code(DOCS / "tutorials" / "your-plates-and-sensor.md")
    assert set(files) == {"my-grating.toml", "my4x4.toml"} and "my4x4.toml" in code


def test_markdown_tables_in_docstrings_become_list_tables():
    rest = _docstrings.to_rest(
        ["Sensors:", "", "| a | b |", "|---|---|", "| 1 | 2 |", "", "|x| is a norm"]
    )
    assert ".. list-table::" in rest and "   * - 1" in rest and "\\|x\\| is a norm" in rest


#: the pages that load finger7-v1's quick data share a worker with the other tests that do
#: (test_tasks_sim, test_user_methods, test_readme), so that one of them simulates it
_F7 = {"your-method", "nir-export", "ablate"}
RUNNABLE = [p for p in CODE_PAGES if page_code(p)[0]]
#: the pages whose Python runs a task's full protocol (a leaderboard entry is a full run:
#: 224 slides of finger7-v2, five minutes of the suite's 2 cores); the suite runs their
#: ``evaluate`` in its quick form
FULL_RUNS = {"submit-a-result"}


@pytest.mark.slow
@pytest.mark.parametrize(
    "page",
    [
        pytest.param(p, marks=pytest.mark.xdist_group("finger7-v1-quick")) if p.stem in _F7 else p
        for p in RUNNABLE
    ],
    ids=[f"{p.parent.name}/{p.stem}" for p in RUNNABLE],
)
def test_a_page_runs_as_written(page, tmp_path, cache_dir):
    """The page's blocks in order, as a reader pastes them: in a new process, in an empty
    folder holding the files the page names. A page that runs a task's full protocol
    (:data:`FULL_RUNS`: minutes of simulation) runs it in its quick form, as written
    otherwise."""
    code, files = page_code(page)
    if page.stem in FULL_RUNS:
        head, call = code.split("evaluate(\n")  # the page's one full run
        end = call.index("\n)")
        code = f"{head}evaluate(\n{call[:end]}\n    quick=True,{call[end:]}"
    for name, body in files.items():
        (tmp_path / name).write_text(body)
    env = dict(os.environ, SIM_TACTILE_CACHE=str(cache_dir), MPLBACKEND="Agg")
    proc = subprocess.run(
        [sys.executable, "-c", code],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
