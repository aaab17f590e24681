"""The simulated benchmark tasks: slides -> cached recordings -> report."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from sklearn.neighbors import KNeighborsClassifier
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

from sim_tactile.errors import ConfigError
from sim_tactile.learn.precomputed import OnDistances, OnFeatures, sample_index
from sim_tactile.tasks import Run, TaskSpec, get_task, register

PNG = b"\x89PNG\r\n\x1a\n"


def test_registry_rejects_bad_runs():
    base = get_task("finger7-v1")
    kw = {"title": "t", "get_data": base.get_data, "classifiers": ("svm",)}
    with pytest.raises(ConfigError, match="channel set 'left'"):
        register(TaskSpec(id="bad-channels-v1", runs=(Run("svm", channels="left"),), **kw))
    with pytest.raises(ConfigError, match="share a label"):
        register(TaskSpec(id="bad-labels-v1", runs=(Run("svm"), Run("svm")), **kw))
    with pytest.raises(ConfigError, match="already registered"):
        register(base)


def test_on_features_matches_a_direct_fit():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(60, 4)) + np.repeat(np.arange(3), 20)[:, None]
    y = np.repeat(np.arange(3), 20)
    tr, te = np.arange(0, 60, 2), np.arange(1, 60, 2)
    est = make_pipeline(StandardScaler(), SVC(kernel="linear"))
    wrapped = OnFeatures(est, x).fit(sample_index(60)[tr], y[tr])
    direct = make_pipeline(StandardScaler(), SVC(kernel="linear")).fit(x[tr], y[tr])
    np.testing.assert_array_equal(wrapped.predict(sample_index(60)[te]), direct.predict(x[te]))
    with pytest.raises(ConfigError, match="sample indices"):
        wrapped.predict(np.array([[60]]))
    with pytest.raises(ConfigError, match="finite"):
        OnFeatures(est, np.full((3, 2), np.nan)).fit(sample_index(3), [0, 1, 0])


def test_on_distances_matches_precomputed_knn():
    rng = np.random.default_rng(1)
    pts = rng.normal(size=(40, 2)) + np.repeat([[0, 0], [3, 3]], 20, axis=0)
    y = np.repeat([0, 1], 20)
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    tr, te = np.arange(0, 40, 3), np.setdiff1d(np.arange(40), np.arange(0, 40, 3))
    wrapped = OnDistances(d, n_neighbors=3).fit(tr[:, None], y[tr])
    ref = KNeighborsClassifier(3, metric="precomputed").fit(d[np.ix_(tr, tr)], y[tr])
    np.testing.assert_array_equal(wrapped.predict(te[:, None]), ref.predict(d[np.ix_(te, tr)]))
    assert wrapped.score(te[:, None], y[te]) > 0.9
    with pytest.raises(ConfigError, match="n_neighbors = 50"):
        OnDistances(d, n_neighbors=50).fit(tr[:, None], y[tr])


def _check_report(doc: dict, out: Path, task: str) -> None:
    assert doc["task"] == task
    assert {"results", "timing", "figures"} <= set(doc)
    assert {"simulate_s", "encode_s", "classify_s"} <= set(doc["timing"])
    for r in doc["results"]:
        assert {"classifier", "features", "accuracy_mean", "accuracy_std", "paper"} <= set(r)
        assert 0.0 <= r["accuracy_mean"] <= 1.0 and r["accuracy_std"] >= 0.0
    for f in doc["figures"]:
        assert Path(f).read_bytes()[:8] == PNG
    assert (out / "report.json").is_file() and (out / "report.md").is_file()


@pytest.mark.slow
@pytest.mark.xdist_group("finger7-v1-quick")  # one worker: the first simulates, the rest read
def test_run_finger7_quick_and_rerun_is_exact(tmp_path, cli):
    out1, out2 = tmp_path / "a", tmp_path / "b"
    p = cli(["run", "finger7-v1", "--quick", "--out", str(out1), "--json"], check=False)
    assert p.returncode == 0, p.stderr
    doc = json.loads(p.stdout)
    _check_report(doc, out1, "finger7-v1")
    by = {r["label"]: r for r in doc["results"]}
    allt = by["svm all taxels"]
    singles = [r for r in doc["results"] if r["channels"] != "all"]
    assert len(singles) == 9 and allt["paper"]["mean"] == pytest.approx(0.9921)
    # the paper's finding: all taxels together beat any single taxel
    assert allt["accuracy_mean"] > max(r["accuracy_mean"] for r in singles)
    assert allt["accuracy_mean"] > 3 / 7  # far above chance (1/7)
    assert {Path(f).name for f in doc["figures"]} >= {"plates.png", "streams_per_class.png"}
    # re-run with the same seed: every slide from the cache, the same numbers exactly
    p2 = cli(["run", "finger7-v1", "--quick", "--out", str(out2), "--json"], check=False)
    assert p2.returncode == 0, p2.stderr
    doc2 = json.loads(p2.stdout)
    assert doc2["timing"]["simulate_s"] == 0.0
    assert [r["accuracies"] for r in doc2["results"]] == [r["accuracies"] for r in doc["results"]]
    # the table for people (what `make demo` prints)
    p3 = cli(["run", "finger7-v1", "--quick", "--out", str(out2)], check=False)
    assert p3.returncode == 0, p3.stderr
    table = p3.stdout
    assert f"{allt['accuracy_mean']:.3f} ({allt['accuracy_std']:.3f})" in table
    lo, hi = allt["accuracy_ci95"]
    assert f"[{lo:.3f}, {hi:.3f}]" in table and lo <= allt["accuracy_mean"] <= hi
    # one result file per row, each valid
    files = sorted((out1 / "results").glob("finger7-v1--*.json"))
    assert len(files) == len(doc["results"]) == len(doc["result_files"])
    assert cli(["check", *files]).stdout.count(": ok") == len(files)
    assert "svm all taxels" in table and "figure:" in table


@pytest.mark.slow
@pytest.mark.parametrize(
    "task, n_rows",
    [("multilayer3-v1", 9), ("multilayer3-v2", 9), ("finger7-v2", 11), ("roughness8-v1", 10)],
)
def test_run_quick_feature_tasks(task, n_rows, tmp_path, cli):
    p = cli(["run", task, "--quick", "--out", str(tmp_path), "--json"], check=False)
    assert p.returncode == 0, p.stderr
    doc = json.loads(p.stdout)
    _check_report(doc, tmp_path, task)
    assert len(doc["results"]) == n_rows
    papers = [r for r in doc["results"] if r["paper"]]
    assert papers and all(isinstance(r["paper"]["mean"], float) for r in papers)
    # chance level is 1/3 (multilayer) or 1/8 (roughness): the best row is well above it
    n_cls = doc["dataset"]["classes"]
    assert max(r["accuracy_mean"] for r in doc["results"]) > 1.5 / n_cls


@pytest.mark.slow
def test_run_textures20_quick_suite(tmp_path, cli):
    pytest.importorskip("torch")
    p = cli(["run", "textures20-v1", "--quick", "--out", str(tmp_path), "--json"], check=False)
    assert p.returncode == 0, p.stderr
    doc = json.loads(p.stdout)
    _check_report(doc, tmp_path, "textures20-v1")
    parts = {r["part"] for r in doc["results"]}
    assert parts == {"textures20-biotac19-v1", "textures20-icub60-v1"}
    assert {r["classifier"] for r in doc["results"]} == {"svm-raw", "svm-spike", "lstm", "snn"}
    for part in parts:
        sub = json.loads((tmp_path / part / "report.json").read_text())
        assert sub["dataset"]["classes"] == 4 and sub["dataset"]["samples"] == 12
        assert any(r["over_time"] for r in sub["results"])
