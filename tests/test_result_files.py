"""Result files and ``sim-tactile check``: what ``tasks.evaluate`` writes passes; each edit a
submitter could make is refused with one line; the tracks; the 95% interval recomputed by
hand from a row's repeats. On the suite's tone task (no physics): a few seconds."""

from __future__ import annotations

import copy
import itertools
import json
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from _fake_task import TASK, tones_store, tones_task
from sklearn.linear_model import LogisticRegression, RidgeClassifier
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import FunctionTransformer, StandardScaler

from sim_tactile.learn.preprocess import SpikeCounts
from sim_tactile.tasks import evaluate, intervals
from sim_tactile.tasks.check import check_document, check_file
from sim_tactile.tasks.result_file import dumps

ROOT = Path(__file__).resolve().parents[1]
#: the tone task's quick protocol here: enough repeats for an interval
REPEATS = 6


def _mean_over_time(X):
    return np.asarray(X).mean(axis=1)


def _std_over_time(X):
    return np.asarray(X).std(axis=1)


def _ridge():
    return Pipeline([("mean", FunctionTransformer(_mean_over_time)), ("clf", RidgeClassifier())])


def _own_encoder():
    """A user's encoder (the SD over time per channel) and its classifier: the open track."""
    enc = FunctionTransformer(_std_over_time)
    return enc, Pipeline([("scale", StandardScaler()), ("clf", LogisticRegression())])


def _on_task_encoding():
    """A classifier on the task's own encoding (its spike counts): the closed track."""
    clf = Pipeline([("counts", SpikeCounts()), ("scale", StandardScaler())])
    return "task", Pipeline([*clf.steps, ("clf", LogisticRegression(max_iter=1000))])


@pytest.fixture(scope="module")
def tones(tmp_path_factory, cache_dir):
    """The tone task (svm-raw and svm-spike rows, 6 repeats) scored with three user methods;
    the files by method name."""
    root = tmp_path_factory.mktemp("results")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SIM_TACTILE_CACHE", str(cache_dir))
        with tones_task(classifiers=("svm-raw", "svm-spike"), repeats=REPEATS) as spec:
            tones_store(root / "tones.zarr")
            methods = {"ridge": _ridge(), "own-enc": _own_encoder(), "on-task": _on_task_encoding()}
            report = evaluate(
                TASK,
                methods,
                quick=True,
                store=root / "tones.zarr",
                out=root / "out",
                about={"ridge": {"version": "1.2", "link": "https://example.org/ridge"}},
            )
            files = {
                json.loads(Path(f).read_text())["config"]["model_name"]: Path(f)
                for f in report["result_files"]
            }
            yield SimpleNamespace(spec=spec, report=report, files=files)


def _doc(tones, name: str) -> dict:
    return json.loads(tones.files[name].read_text())


def test_evaluate_writes_one_file_per_method_and_each_passes_check(tones):
    assert set(tones.files) == {"svm-raw", "svm-spike", "ridge", "own-enc", "on-task"}
    assert all(_doc(tones, n)["config"]["variant"] is None for n in tones.files)
    for name, path in tones.files.items():
        assert path.parent.name == "results" and path.name.startswith(f"{TASK}--")
        assert check_file(path) == [], name
    doc = _doc(tones, "ridge")
    cfg, m = doc["config"], doc["results"][TASK]
    assert set(doc) == {"schema", "config", "results"} and set(doc["results"]) == {TASK}
    assert (cfg["task"], cfg["family"], cfg["version"]) == (TASK, "formats-tones", 1)
    assert cfg["model_name"] == "ridge" and cfg["model_sha"] == "1.2"
    assert cfg["method"]["link"] == "https://example.org/ridge"
    assert cfg["protocol"]["repeats"] == REPEATS and cfg["protocol"]["split"] == "8/4"
    assert cfg["environment"]["sim_tactile"] and cfg["environment"]["machine"]
    row = {r["label"]: r for r in tones.report["results"]}["ridge"]
    assert m["accuracy_repeats"] == row["accuracies"] and len(m["fit_s_repeats"]) == REPEATS
    assert m["accuracy"] == pytest.approx(np.mean(row["accuracies"]), abs=1e-12)
    assert m["accuracy_ci95"] == row["accuracy_ci95"]
    assert m["accuracy_ci95"][0] <= m["accuracy"] <= m["accuracy_ci95"][1]
    # Hugging Face's leaderboards read results[task][metric] as a number
    assert isinstance(m["accuracy"], float)
    # a spiking row carries NeuroBench's figures (here the encoder's spike rate), the raw not
    spike = _doc(tones, "svm-spike")["results"][TASK]["neurobench"]
    assert spike["encoder"]["spikes_per_s"] > 0
    assert "neurobench" not in _doc(tones, "svm-raw")["results"][TASK]
    from sim_tactile.tasks.leaderboard import neurobench_text

    assert neurobench_text({"neurobench": spike}).startswith("encoder ")
    snn = {
        "parameter_count": 768,
        "activation_sparsity": 0.9,
        "synaptic_operations": {"effective_acs": 1.5e4},
    }
    assert neurobench_text({"neurobench": snn}) == (
        "768 parameters, 1.5e+04 ACs/sample, activation sparsity 0.900"
    )


def test_the_tracks_follow_what_is_the_methods_own(tones):
    tracks = {n: _doc(tones, n)["config"]["track"] for n in tones.files}
    assert tracks == {
        "svm-raw": "closed",
        "svm-spike": "closed",
        "on-task": "closed",
        "ridge": "open",  # an estimator on the recordings: its own features
        "own-enc": "open",
    }
    assert _doc(tones, "on-task")["config"]["method"]["encoder"] == "task"
    assert "FunctionTransformer" in _doc(tones, "own-enc")["config"]["method"]["encoder"]


def _edit(doc: dict, what: str) -> dict:
    d = copy.deepcopy(doc)
    cfg, m = d["config"], d["results"][d["config"]["task"]]
    if what == "split digest":
        cfg["protocol"]["splits_sha256"] = "0" * 64
    elif what == "repeat dropped":
        m["accuracy_repeats"] = m["accuracy_repeats"][:-1]
    elif what == "mean edited":
        m["accuracy"] = m["accuracy"] - 0.01
    elif what == "interval edited":
        m["accuracy_ci95"] = [m["accuracy_ci95"][0] - 0.05, m["accuracy_ci95"][1]]
    elif what == "own encoder on the closed track":
        cfg["track"] = "closed"
    elif what == "labels of its own":
        cfg["protocol"]["labels"] = cfg["protocol"]["labels"][::-1]
    elif what == "incomplete":
        del cfg["protocol"]
    elif what == "another seed":
        cfg["protocol"]["seed"] = 1
    return d


@pytest.mark.parametrize(
    "name, what, needle",
    [
        ("svm-spike", "split digest", "splits_sha256 is not the digest of the task's splits"),
        ("svm-spike", "repeat dropped", "accuracy_repeats holds 5 values; config.protocol.repeats"),
        ("svm-spike", "mean edited", "accuracy = "),
        ("on-task", "interval edited", "accuracy_ci95 = "),
        ("own-enc", "own encoder on the closed track", "the method brings its own encoding"),
        ("ridge", "labels of its own", "labels_sha256 is not the digest of config.protocol"),
        ("svm-raw", "incomplete", "config lacks protocol: the file is incomplete"),
        ("svm-raw", "another seed", "config.protocol.seed = 1; the task's splits are seed 0"),
    ],
)
def test_each_edit_is_refused_with_one_line(tones, name, what, needle):
    refusals = check_document(_edit(_doc(tones, name), what))
    assert len(refusals) == 1, refusals
    assert needle in refusals[0] and "\n" not in refusals[0]


def test_a_closed_entry_on_data_of_its_own_is_refused_and_the_open_one_is_not(tones):
    doc = _doc(tones, "on-task")
    p = doc["config"]["protocol"]
    p["labels"] = sorted(p["labels"], reverse=True)  # another data set's order
    from sim_tactile.tasks.result_file import labels_sha256
    from sim_tactile.tasks.splits import splits_digest, task_splits

    p["labels_sha256"] = labels_sha256(p["labels"])
    p["splits_sha256"] = splits_digest(
        task_splits(np.asarray(p["labels"]), p["split"], p["repeats"], 0)
    )
    refusals = check_document(doc)
    assert len(refusals) == 1 and "the labels are not formats-tones-v1's" in refusals[0]
    doc["config"]["track"] = "open"
    assert check_document(doc) == []


def test_a_calibrated_sensor_is_a_variant_on_the_open_track():
    from sim_tactile.sensors.calibration import load_calibration
    from sim_tactile.tasks import get_task
    from sim_tactile.tasks.registry import with_calibration
    from sim_tactile.tasks.result_file import task_sha256, track_of, variant_of

    spec = get_task("textures20-biotac19-v2")
    cal = with_calibration(spec, load_calibration("biotac19"))
    assert task_sha256(cal) != task_sha256(spec)
    assert variant_of(cal, spec).startswith("Sensor calibrated (--sensor-config) on 1000 real")
    assert track_of({"builtin": True, "encoder": "none"}, own_definition=False) == "open"
    assert track_of({"builtin": True, "encoder": "none"}, own_definition=True) == "closed"


def test_a_broken_or_foreign_file_is_one_line(tmp_path, tones):
    (tmp_path / "cut.json").write_text(tones.files["ridge"].read_text()[:500])
    assert check_file(tmp_path / "cut.json")[0].startswith("not JSON")
    assert check_file(tmp_path / "none.json") == ["no such file"]
    (tmp_path / "other.json").write_text(json.dumps({"config": {}, "results": {}}))
    assert check_file(tmp_path / "other.json")[0].startswith("not a sim-tactile result file")
    doc = _doc(tones, "ridge")
    doc["config"]["task"] = "formats-tones-v2"
    assert check_document(doc) == [
        "config.task: task 'formats-tones-v2' is not known (did you mean 'formats-tones-v1'?); "
        "the family formats-tones has versions v1: formats-tones-v1"
    ]


def test_the_interval_of_a_row_recomputed_by_hand(tones):
    """The percentile bootstrap written out (2000 resamples of the 6 repeats from
    default_rng(0), the 2.5th and 97.5th percentiles of their means) gives the file's
    interval exactly; and the exact bootstrap distribution (all 6**6 equally likely
    resamples) agrees within its lattice step plus the Monte Carlo error."""
    m = _doc(tones, "on-task")["results"][TASK]
    x = np.asarray(m["accuracy_repeats"])
    rng = np.random.default_rng(0)
    means = x[rng.integers(0, x.size, size=(2000, x.size))].mean(axis=1)
    assert list(np.percentile(means, [2.5, 97.5])) == m["accuracy_ci95"]
    exact = np.sort([x[list(i)].mean() for i in itertools.product(range(x.size), repeat=x.size)])
    lo, hi = exact[int(0.025 * exact.size)], exact[int(0.975 * exact.size) - 1]
    # the means lie on a lattice of 1 / (repeats x test samples); the Monte Carlo error of
    # each end is about 6% of the standard error (intervals.RESAMPLES)
    step = 1.0 / (x.size * 12) + 0.25 * x.std() / np.sqrt(x.size)
    assert abs(lo - m["accuracy_ci95"][0]) <= step and abs(hi - m["accuracy_ci95"][1]) <= step


def test_scipy_bootstrap_gives_the_same_interval():
    from scipy import stats

    x = np.random.default_rng(3).random(40)
    ref = stats.bootstrap(
        (x,),
        np.mean,
        n_resamples=intervals.RESAMPLES,
        confidence_level=intervals.LEVEL,
        method="percentile",
        random_state=np.random.default_rng(intervals.SEED),
    ).confidence_interval
    np.testing.assert_allclose(intervals.interval(x), (ref.low, ref.high), rtol=1e-12)
    assert intervals.interval(x[:4]) is None  # below MIN_REPEATS


def test_the_written_text_round_trips(tones):
    doc = _doc(tones, "svm-raw")
    text = tones.files["svm-raw"].read_text()
    assert json.loads(dumps(doc)) == doc and dumps(doc) == text
    assert '"accuracy_repeats": [' in text  # a list of numbers on one line


def test_a_methods_version_and_link_are_checked_before_anything_runs():
    from sim_tactile.cli.tasks import about_arg
    from sim_tactile.errors import ConfigError

    assert about_arg(["m=1.0,https://x.org/a,b"], {"m": 1}) == {
        "m": {"version": "1.0", "link": "https://x.org/a,b"}
    }
    with pytest.raises(ConfigError, match="'n' is not a --method; valid: m"):
        about_arg(["n=1"], {"m": 1})
    with pytest.raises(ConfigError, match="valid: NAME=VERSION or NAME=VERSION,LINK"):
        about_arg(["m="], {"m": 1})
    with pytest.raises(ConfigError, match="about names 'x', which is not a method"):
        evaluate("finger7-v1", {"m": _ridge()}, about={"x": {"version": "1"}})
    with pytest.raises(ConfigError, match="valid: a mapping with 'version' and 'link'"):
        evaluate("finger7-v1", {"m": _ridge()}, about={"m": {"commit": "1"}})


def test_the_closed_track_example_is_a_method_on_the_tasks_encoding():
    import runpy

    from sim_tactile.tasks import TASK_ENCODER
    from sim_tactile.tasks.methods import as_method

    make = runpy.run_path(str(ROOT / "examples" / "closed_track.py"))["spike_features_logreg"]
    m = as_method("logreg", make())
    assert m.encoder is TASK_ENCODER and m.encoder_kind == "task"
    assert m.describe().startswith("the task's encoder -> Pipeline")


def test_the_commit_is_this_repositorys_only(monkeypatch, tmp_path):
    from sim_tactile.tasks import result_file

    if (ROOT / ".git").exists():
        assert re.match(r"^[0-9a-f]{7,}(-dirty)?$", result_file._commit())
    # an installed copy inside some other repository (a project's venv) names no commit
    monkeypatch.setattr(
        result_file, "_git", lambda *a: str(tmp_path) if "--show-toplevel" in a else "abc"
    )
    assert result_file._commit() is None


def _paths(node, path=()):
    """Every key path of a JSON document (a list's first item stands for the list's)."""
    yield path
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, (*path, k))
    elif isinstance(node, list) and node:
        yield from _paths(node[0], (*path, 0))


def test_any_field_replaced_by_any_json_value_is_refused_not_a_crash(tones):
    """Each field of a valid file, in turn, replaced by a value of another JSON type (or an
    out-of-range number): check returns its refusals (one line each) and never raises."""
    doc = _doc(tones, "on-task")
    doc["results"][TASK]["accuracy_repeats"] = doc["results"][TASK]["accuracy_repeats"][:5]
    doc["config"]["protocol"]["labels"] = doc["config"]["protocol"]["labels"][:3]
    for path in list(_paths(doc))[1:]:
        for value in (None, "x", [], {}, -1, 1e308, True):
            d = copy.deepcopy(doc)
            node = d
            for k in path[:-1]:
                node = node[k]
            node[path[-1]] = value
            refusals = check_document(d)
            assert all(isinstance(r, str) and "\n" not in r for r in refusals), (path, value)
