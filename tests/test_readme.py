"""The README is a short introduction whose code runs as written."""

from __future__ import annotations

import re
import shlex
import subprocess
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
TEXT = README.read_text()
LINES = TEXT.splitlines()


def _first(pattern: str) -> int:
    return next(i + 1 for i, line in enumerate(LINES) if re.search(pattern, line))


def test_the_readme_is_short_and_has_no_commit_hash():
    assert len(LINES) <= 200
    assert re.findall(r"`[0-9a-f]{7,40}`", TEXT) == []
    assert "since `" not in TEXT


def test_install_the_two_commands_and_the_quick_start_come_first():
    assert _first(r"pip install") <= 60
    assert _first(r"^make demo") <= 60 and _first(r"^make test") <= 60
    assert _first(r"tasks\.load\(") <= 60 and _first(r"tasks\.evaluate\(") <= 60


def test_every_link_to_a_file_points_at_one():
    root = README.parent
    for target in re.findall(r"\]\(([^)#]+)\)", TEXT):
        if not target.startswith("http"):
            assert (root / target).exists(), target


def test_every_number_of_the_task_table_is_on_the_results_page_with_its_commit():
    """Each README row's numbers stand in a row of the task results page for the same task,
    and that row names its commit (its command is the page's, with the row's options)."""
    page = (README.parent / "docs" / "results" / "task-runs.md").read_text().splitlines()
    commit = re.compile(r"`[0-9a-f]{7,12}`")
    table = [line for line in LINES if line.startswith("| `")]
    assert len(table) >= 10
    for line in table:
        task = line.split("|")[1].strip()  # `finger7-v1`
        rows = [r for r in page if r.startswith(f"| {task}") and commit.search(r)]
        assert rows, f"no row of {task} with its commit on the results page"
        for number in re.findall(r"\b0\.\d{3}\b", line):
            assert any(number in r for r in rows), (number, line)


@pytest.mark.slow
@pytest.mark.xdist_group("finger7-v1-quick")  # one worker: the first simulates, the rest read
def test_every_python_block_runs_as_written(tmp_path, monkeypatch, cache_dir):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    blocks = re.findall(r"```python\n(.*?)```", TEXT, flags=re.S)
    assert blocks
    for code in blocks:
        exec(compile(code, str(README), "exec"), {"__name__": "__readme__"})
    assert (tmp_path / "out" / "mine" / "report.json").is_file()


@pytest.mark.slow
@pytest.mark.xdist_group("finger7-v1-quick")
def test_the_use_it_with_commands_run_as_written(tmp_path, cli_env):
    """The bridges' command lines, pasted into a shell in an empty folder: a store, its
    Parquet export (which Hugging Face's datasets reads), and a run that saves its spiking
    network as a NIR graph whose outputs are the plates."""
    from conftest import EXE

    section = TEXT[TEXT.index("## Use it with") : TEXT.index("## The tasks")]
    lines = re.findall(r"```bash\n(.*?)```", section, flags=re.S)[0].splitlines()
    assert len(lines) == 3
    for line in lines:
        argv = shlex.split(line, comments=True)
        assert argv[0] == "sim-tactile"
        proc = subprocess.run(
            [EXE, *argv[1:]], cwd=tmp_path, env=cli_env, capture_output=True, text=True
        )
        assert proc.returncode == 0, (line, proc.stderr[-3000:])
    datasets = pytest.importorskip("datasets")
    nir = pytest.importorskip("nir")
    hub = datasets.load_dataset(str(tmp_path / "f7-hub"))
    assert set(hub) == {"train", "test"} and len(hub["train"]) == 42
    names = [c.decode() for c in nir.read(str(tmp_path / "snn.nir")).metadata["classes"]]
    assert names == list(hub["train"].features["label"].names)
