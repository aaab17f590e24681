"""The leaderboard in the repository: every entry passes ``sim-tactile check`` (a broken
entry fails CI here), the papers' entries are the cells their tasks register, and the page
the docs build makes from the folder: one ranked table per task version and track."""

from __future__ import annotations

import json
import re
import shutil
import sys
from pathlib import Path

import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.tasks.check import check_file
from sim_tactile.tasks.leaderboard import groups, load_entries, page
from sim_tactile.tasks.result_file import reported_documents

ROOT = Path(__file__).resolve().parents[1]
BOARD = ROOT / "leaderboard"
ENTRIES = sorted(BOARD.glob("*.json"))
sys.path.insert(0, str(ROOT / "docs"))


@pytest.mark.parametrize("path", ENTRIES, ids=[p.stem for p in ENTRIES])
def test_every_entry_passes_check(path):
    assert check_file(path) == []
    assert json.loads(path.read_text())["config"]["protocol"]["mode"] == "full"


def test_the_board_holds_baselines_and_the_papers_numbers():
    entries = load_entries(BOARD)
    reported = [e for e in entries if e.reported]
    assert reported and len(reported) < len(entries)
    for e in reported:
        cfg = e.config
        want = [
            d
            for d in reported_documents(cfg["task"])
            if d["config"]["method"]["row"] == cfg["method"]["row"]
        ]
        assert e.doc == want[0], e.path.name
    tasks = {e.config["task"] for e in entries}
    assert {"finger7-v1", "roughness8-v1", "biotac20-real-v1"} <= tasks


def test_a_refused_entry_fails_the_board_naming_it(tmp_path):
    for p in ENTRIES[:3]:
        shutil.copy(p, tmp_path / p.name)
    bad = tmp_path / ENTRIES[0].name
    doc = json.loads(bad.read_text())
    doc["results"][doc["config"]["task"]]["accuracy"] = 0.5
    bad.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match=re.escape(f"{bad.name}: reported: accuracy")):
        load_entries(tmp_path)


def _tables(text: str) -> dict[str, list[list[str]]]:
    """The page's tables by heading: their body rows as cells."""
    out, head = {}, None
    for line in text.splitlines():
        if line.startswith("## "):
            head = line[3:]
            out[head] = []
        elif line.startswith("| ") and head and not line.startswith("| rank"):
            out[head].append([c.strip() for c in line.strip("|").split("|")])
    return out


@pytest.mark.slow
def test_the_page_ranks_one_table_per_task_version_and_track():
    entries = load_entries(BOARD)
    tables = _tables(page(BOARD))
    assert list(tables) == [
        f"`{task}`, {track} track, split {split}" for task, track, split in groups(entries)
    ]
    for head, rows in tables.items():
        ranks = [r[0] for r in rows]
        n = ranks.count("reported")
        assert ranks == ["reported"] * n + [str(i + 1) for i in range(len(rows) - n)], head
        ranked = [float(r[2]) for r in rows[n:]]
        assert ranked == sorted(ranked, reverse=True), head
        for r in rows[n:]:
            assert re.fullmatch(r"\[\d\.\d{4}, \d\.\d{4}\]", r[3]), (head, r)  # the interval


def test_each_task_page_carries_its_version_history():
    import _gen

    text = _gen.task_page("finger7-v1")
    assert "Superseded by [`finger7-v2`](finger7-v2.md)" in text
    history = text.split("## Version history")[1].split("##")[0]
    assert "`finger7-v1` (this page), superseded by [`finger7-v2`](finger7-v2.md):" in history
    assert "[`finger7-v2`](finger7-v2.md), current:" in history
    assert "first release" in history and "the paper's finger and protocol" in history
    assert "in the suite `core-v1`" in _gen.task_page("finger7-v2")


@pytest.mark.slow
def test_check_exits_0_for_valid_files_and_1_with_a_line_per_refusal(cli, tmp_path):
    p = cli(["check", *ENTRIES[:2]])
    assert p.stdout.splitlines() == [f"{e}: ok" for e in ENTRIES[:2]]
    doc = json.loads(ENTRIES[0].read_text())
    doc["config"]["task"] = "finger7-v9"
    doc["config"]["protocol"]["mode"] = "quick"
    (tmp_path / "edited.json").write_text(json.dumps(doc))
    p = cli(["check", ENTRIES[1], tmp_path / "edited.json", "--json"], check=False)
    assert p.returncode == 1
    out = json.loads(p.stdout)
    assert out["ok"] is False and [f["ok"] for f in out["files"]] == [True, False]
    lines = p.stderr.strip().splitlines()
    assert lines == [
        f"{tmp_path / 'edited.json'}: config.task: task 'finger7-v9' is not known (did you "
        "mean 'finger7-v2' or 'finger7-v1'?); the family finger7 has versions v1, v2: "
        "finger7-v1, finger7-v2",
        "sim-tactile: check: 1 of 2 file(s) refused",
    ]


def test_the_interval_of_the_real_biotac_raw_svm_recomputed_by_hand():
    """biotac20-real-v1's raw SVM, 5 repeats: every one of the 5**5 equally likely
    resamples enumerated, the 2.5th and 97.5th percentiles of their means (the exact
    bootstrap interval), against the entry's 2000-resample interval: within a quarter of
    the standard error of the mean (the Monte Carlo error is about 6% of it)."""
    import itertools

    import numpy as np

    doc = json.loads((BOARD / "biotac20-real-v1--svm-raw.json").read_text())
    m = doc["results"]["biotac20-real-v1"]
    x = np.asarray(m["accuracy_repeats"])
    assert x.size == 5 and m["accuracy"] == pytest.approx(x.mean(), abs=1e-12)
    means = np.sort([x[list(i)].mean() for i in itertools.product(range(5), repeat=5)])
    exact = np.percentile(means, [2.5, 97.5])
    se = x.std() / np.sqrt(x.size)
    np.testing.assert_allclose(m["accuracy_ci95"], exact, atol=0.25 * se)
