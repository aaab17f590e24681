"""A user's method on the benchmark: a task as data and protocol (``tasks.load``), the user's
estimators and encoders under the task's protocol (``tasks.evaluate``, ``run --method``), and
the CI mode (``--baseline``, ``--save-baseline``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.linear_model import RidgeClassifier
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import FunctionTransformer, StandardScaler
from sklearn.svm import SVC

from sim_tactile.encoders import IzhikevichEncoder
from sim_tactile.errors import ConfigError
from sim_tactile.spikes import SpikeFeatures
from sim_tactile.tasks import evaluate, load
from sim_tactile.tasks.baseline import compare_baseline, load_baseline, save_baseline
from sim_tactile.tasks.check import check_file
from sim_tactile.tasks.intervals import interval
from sim_tactile.tasks.methods import as_method, as_methods, import_method, prepared

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "delta_method.py"


def _mean_over_time(X):
    return np.asarray(X).mean(axis=1)


def raw_ridge():
    """A user's estimator on the raw (samples, time, channels) array."""
    return Pipeline([("mean", FunctionTransformer(_mean_over_time)), ("clf", RidgeClassifier())])


def builtin_svm_again():
    """finger7's built-in ``svm`` row built from public names: the task's encoder (SA
    Izhikevich, gain 15, min-max) and features, then scaling and a linear SVM."""
    enc = Pipeline(
        [
            (
                "encode",
                IzhikevichEncoder(rate_hz=100.0, preset="SA", gain=15.0, normalize="minmax"),
            ),
            ("features", SpikeFeatures(features=("rate_hz", "mean_isi_s"))),
        ]
    )
    return enc, Pipeline([("scale", StandardScaler()), ("clf", SVC(kernel="linear", C=1.0))])


class NoPredict(BaseEstimator):
    def fit(self, X, y):
        return self


class Boom(ClassifierMixin, BaseEstimator):
    def fit(self, X, y):
        raise RuntimeError("my bug")

    def predict(self, X):
        return np.zeros(len(X))


# -- methods: what is accepted, what is refused, and how a repeat's estimator is made --------


def test_methods_are_checked_and_named():
    m = as_method("mine", raw_ridge())
    assert m.encoder is None and "RidgeClassifier" in m.describe()
    pair = as_method("pair", builtin_svm_again())
    assert pair.encoder is not None and " -> " in pair.describe()
    with pytest.raises(ConfigError, match="method 'x': its estimator NoPredict has no predict"):
        as_method("x", NoPredict())
    with pytest.raises(ConfigError, match="its encoder int has no fit or transform"):
        as_method("x", (3, raw_ridge()))
    with pytest.raises(ConfigError, match="a pair is \\(encoder, estimator\\), got 3 items"):
        as_method("x", (1, 2, 3))
    with pytest.raises(ConfigError, match="method name 'a b' is not valid"):
        as_method("a b", raw_ridge())
    with pytest.raises(ConfigError, match="are the task's own rows"):
        as_methods({"svm-raw": raw_ridge()}, {"svm-raw"})


def test_a_repeats_estimator_gets_the_seed_and_the_rate_where_unset():
    est = Pipeline(
        [("enc", IzhikevichEncoder(rate_hz=50.0)), ("clf", SVC(kernel="linear", random_state=7))]
    )
    got = prepared(est, 11, 1000.0)
    assert got.get_params()["enc__rate_hz"] == 50.0  # set by the user: kept
    assert got.get_params()["clf__random_state"] == 7
    unset = prepared(SVC(), 11, 1000.0)
    assert unset.random_state == 11 and prepared(SVC(), None, 100.0).random_state is None
    spec = __import__("importlib").util.spec_from_file_location("delta_method", EXAMPLE)
    mod = __import__("importlib").util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    enc = prepared(mod.DeltaEncoder(), None, 250.0)
    assert enc.rate_hz == 250.0 and est.get_params()["enc__rate_hz"] == 50.0  # a clone


def test_method_specs_import_what_the_user_names(tmp_path, monkeypatch):
    m = import_method(f"delta={EXAMPLE}:delta_nearest_mean")
    assert m.name == "delta" and m.encoder is not None
    (tmp_path / "my_methods.py").write_text(
        "from sklearn.linear_model import RidgeClassifier\n"
        "def ridge():\n    return RidgeClassifier()\n"
        "def broken():\n    raise ValueError('no such thing')\n"
    )
    monkeypatch.chdir(tmp_path)  # a module beside the user, by its dotted name
    assert import_method("r=my_methods:ridge").name == "r"
    with pytest.raises(ConfigError, match="my_methods:broken\\(\\) raised ValueError: no such"):
        import_method("b=my_methods:broken")
    with pytest.raises(ConfigError, match="no module named 'not_a_module_here'"):
        import_method("x=not_a_module_here:make")
    with pytest.raises(ConfigError, match="has no callable 'nope'"):
        import_method("x=my_methods:nope")
    with pytest.raises(ConfigError, match="valid: NAME=module:callable"):
        import_method("just-a-name")


# -- the baseline comparison -----------------------------------------------------------------


def _report(task="finger7-v1", quick=True, rows=(("a", 0.9), ("b", 0.8))):
    return {
        "task": task,
        "quick": quick,
        "results": [
            {"label": n, "classifier": n, "features": "f", "accuracy_mean": a} for n, a in rows
        ],
    }


def test_the_baseline_passes_within_the_tolerance_and_fails_below_or_missing(tmp_path):
    base = _report()
    assert not compare_baseline(_report(), base, 0.02, "b.json").failed
    assert not compare_baseline(_report(rows=(("a", 0.885), ("b", 0.8))), base, 0.02, "b").failed
    below = compare_baseline(_report(rows=(("a", 0.87), ("b", 0.8))), base, 0.02, "b")
    assert below.failed and [r["status"] for r in below.rows] == ["below", "ok"]
    assert "FAILED" in below.table()[-1] and any("-0.0300" in line for line in below.table())
    missing = compare_baseline(_report(rows=(("a", 0.95), ("c", 0.5))), base, 0.02, "b")
    assert missing.failed
    assert {r["label"]: r["status"] for r in missing.rows} == {
        "a": "ok",
        "b": "missing",
        "c": "new",
    }
    path = save_baseline(base, tmp_path / "sub" / "base.json")
    assert load_baseline(path, "finger7-v1", True)["results"] == base["results"]
    with pytest.raises(ConfigError, match="is a baseline of finger7-v1, not of roughness8-v1"):
        load_baseline(path, "roughness8-v1", True)
    with pytest.raises(
        ConfigError, match="saved from a --quick run of finger7-v1; this run is full"
    ):
        load_baseline(path, "finger7-v1", False)
    (tmp_path / "junk.json").write_text("{not json")
    with pytest.raises(ConfigError, match="not a JSON report"):
        load_baseline(tmp_path / "junk.json", "finger7-v1", True)
    with pytest.raises(ConfigError, match="--tolerance = -0.1; valid: an accuracy in \\[0, 1\\]"):
        compare_baseline(base, base, -0.1, "b")


def test_the_baseline_compares_with_the_lower_end_of_its_interval(tmp_path):
    """A row may fall below its baseline's mean by more than the tolerance and pass, as long
    as it stays within the tolerance of the baseline's 95% interval (its repeats' spread)."""
    reps = [0.8, 0.85, 0.9, 0.95, 1.0, 0.9]
    base = _report(rows=(("a", 0.9),))
    base["results"][0]["accuracies"] = reps
    lo = interval(reps)[0]
    assert lo < 0.9 - 0.01  # the interval is wider than the tolerance here
    ok = compare_baseline(_report(rows=(("a", lo - 0.02 + 0.001),)), base, 0.02, "b")
    assert not ok.failed and ok.rows[0]["baseline_ci95"] == list(interval(reps))
    below = compare_baseline(_report(rows=(("a", lo - 0.02 - 0.001),)), base, 0.02, "b")
    assert below.failed and "its 95% interval" in below.table()[1]
    # a saved baseline keeps the interval (and compares the same without the repeats)
    saved = json.loads(
        save_baseline(
            {**base, "results": [{**base["results"][0], "accuracy_ci95": list(interval(reps))}]},
            tmp_path / "b.json",
        ).read_text()
    )
    assert "accuracies" not in saved["results"][0]
    assert not compare_baseline(_report(rows=(("a", lo - 0.019),)), saved, 0.02, "b").failed


# -- on the tasks -------------------------------------------------------------------------------


@pytest.fixture
def shared_cache(cache_dir, monkeypatch):
    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))


@pytest.mark.slow
@pytest.mark.xdist_group("finger7-v1-quick")  # one worker: the first simulates, the rest read
def test_the_builtin_svm_given_as_a_users_method_scores_exactly_the_builtin_row(shared_cache):
    rep = evaluate(
        "finger7-v1", {"svm-again": builtin_svm_again()}, quick=True, classifiers="svm", seed=0
    )
    rows = {r["label"]: r for r in rep["results"]}
    mine, builtin = rows["svm-again"], rows["svm all taxels"]
    assert mine["accuracies"] == builtin["accuracies"] and len(mine["accuracies"]) == 50
    assert mine["confusion"] == builtin["confusion"]
    assert mine["features"] == "user method" and mine["user_method"] is True
    assert rep["figures"] == []  # no out: a temporary folder, removed


@pytest.mark.slow
@pytest.mark.xdist_group("finger7-v1-quick")  # one worker: the first simulates, the rest read
def test_loaded_splits_are_repeatable_and_the_ones_the_builtin_run_used(shared_cache, tmp_path):
    a, b = load("finger7-v1", quick=True), load("finger7-v1", quick=True)
    assert a.X.shape == (56, a.X.shape[1], 9) and a.y.shape == (56,) and a.rate_hz == 100.0
    assert a.channel_positions_m.shape == (9, 3) and len(a.class_names) == 7
    assert a.protocol.split == "6/2" and a.protocol.repeats == 50 and a.protocol.encode_once
    pa, pb = list(a.splits()), list(b.splits())
    assert len(pa) == 50
    assert all(
        np.array_equal(x, y) for p, q in zip(pa, pb, strict=True) for x, y in zip(p, q, strict=True)
    )
    # the first pairs do not depend on how many are drawn (a row of fewer repeats)
    first = list(a.splits(repeats=5))
    assert all(np.array_equal(p[0], q[0]) for p, q in zip(first, pa[:5], strict=True))
    tr, te = a.protocol.get_train_test_split_indices(3)
    assert np.array_equal(tr, pa[3][0]) and np.array_equal(te, pa[3][1])
    # the built-in run used exactly these splits (its report's digest of them)
    rep = evaluate("finger7-v1", {"r": raw_ridge()}, quick=True, out=tmp_path / "r")
    assert rep["protocol"]["splits_sha256"]["6/2"] == a.protocol.digest()
    assert (
        rep["protocol"]["splits_sha256"]["6/2"]
        != load("finger7-v1", quick=True, seed=1).protocol.digest()
    )
    assert (tmp_path / "r" / "report.json").is_file()
    # a result file of the user's estimator: it passes check (the open track: its own features)
    (path,) = [p for p in rep["result_files"] if p.endswith("--r.json")]
    assert (
        check_file(path) == [] and json.loads(Path(path).read_text())["config"]["track"] == "open"
    )
    with pytest.raises(ConfigError, match="is a suite of"):
        load("textures20-v1")


@pytest.mark.slow
@pytest.mark.xdist_group("finger7-v1-quick")  # one worker: the first simulates, the rest read
def test_run_with_methods_and_the_ci_mode(tmp_path, cli):
    ex = f"delta={EXAMPLE}:delta_nearest_mean"

    def run(out, *more, check=True):
        return cli(
            ["run", "finger7-v1", "--quick", "--method", ex, "--out", out, *more], check=check
        )

    base = tmp_path / "baseline.json"
    out = tmp_path / "a"
    p = run(out, "--save-baseline", base, "--json")
    doc = json.loads(p.stdout)
    rows = {r["label"]: r for r in doc["results"]}
    assert rows["delta"]["accuracy_mean"] > 3 / 7 and "DeltaEncoder" in rows["delta"]["method"]
    assert "svm all taxels" in rows and json.loads(base.read_text())["task"] == "finger7-v1"
    assert "| delta | user method |" in (out / "report.md").read_text()
    # against its own baseline: passes, and says so
    p = run(tmp_path / "b", "--baseline", base)
    assert "passed: no row below the baseline" in p.stderr and "delta" in p.stdout
    # against a baseline whose accuracies were raised: exit 1, with the table
    raised = json.loads(base.read_text())
    for r in raised["results"]:
        r["accuracy_mean"] = min(1.0, r["accuracy_mean"] + 0.05)
        r["accuracy_ci95"] = [min(1.0, v + 0.05) for v in r["accuracy_ci95"]]
    (tmp_path / "raised.json").write_text(json.dumps(raised))
    p = run(tmp_path / "c", "--baseline", tmp_path / "raised.json", "--json", check=False)
    assert p.returncode == 1 and "FAILED" in p.stderr and "below" in p.stderr
    assert json.loads(p.stdout)["baseline_check"]["failed"] is True
    # a baseline row missing from the run (the user's method not given): exit 1
    p = cli(
        ["run", "finger7-v1", "--quick", "--out", tmp_path / "d", "--baseline", base], check=False
    )
    assert p.returncode == 1 and "missing" in p.stderr


@pytest.mark.slow
@pytest.mark.parametrize(
    "args, message",
    [
        (["--method", "x=not_a_module_here:make"], "no module named 'not_a_module_here'"),
        (["--method", "x=BROKEN:broken"], "raised ValueError: no such thing"),
        (["--method", "x=BROKEN:no_predict"], "has no predict"),
        (["--baseline", "OTHER"], "is a baseline of roughness8-v1, not of finger7-v1"),
    ],
    ids=["no-module", "raises", "no-predict", "other-task"],
)
def test_bad_input_is_refused_before_anything_is_written(tmp_path, cli, args, message):
    mod = tmp_path / "user_mod.py"
    mod.write_text(
        "class P:\n    def fit(self, X, y):\n        return self\n"
        "def broken():\n    raise ValueError('no such thing')\n"
        "def no_predict():\n    return P()\n"
    )
    other = tmp_path / "other.json"
    other.write_text(json.dumps(_report("roughness8-v1")))
    args = [str(a).replace("BROKEN", str(mod)).replace("OTHER", str(other)) for a in args]
    out = tmp_path / "out"
    p = cli(["run", "finger7-v1", "--quick", *args, "--out", out], check=False)
    assert p.returncode == 2 and message in p.stderr, p.stderr
    assert not out.exists()


def test_a_users_estimator_that_raises_is_named(tmp_path, fake_icub):
    with pytest.raises(
        ConfigError,
        match="method 'boom': its estimator \\(fitting or predicting\\) raised RuntimeError: my bug",
    ):
        evaluate("icub20-real-v1", {"boom": Boom()}, quick=True, data=fake_icub, classifiers="none")


def test_user_methods_run_on_a_real_data_task(tmp_path, fake_icub):
    """The iCub task's layout on a stand-in data set (the real one is not in CI): a raw
    estimator with accuracy over time, beside the built-in raw SVM, on the task's splits."""
    rep = evaluate(
        "icub20-real-v1",
        {"ridge": raw_ridge()},
        quick=True,
        data=fake_icub,
        classifiers="svm-raw",
        out=tmp_path / "o",
    )
    rows = {r["label"]: r for r in rep["results"]}
    assert set(rows) == {"svm-raw", "ridge"}
    assert rows["ridge"]["accuracy_mean"] > 0.9 and rows["ridge"]["over_time"]
    assert rows["ridge"]["split"] == rows["svm-raw"]["split"]
    assert rows["ridge"]["repeats"] == rows["svm-raw"]["repeats"]
    data = load("icub20-real-v1", quick=True, data=fake_icub)
    assert rep["protocol"]["splits_sha256"][data.protocol.split] == data.protocol.digest(
        repeats=rows["svm-raw"]["repeats"]
    )


@pytest.mark.slow
@pytest.mark.xdist_group("finger7-v1-quick")  # one worker: the first simulates, the rest read
def test_user_methods_run_on_a_store(tmp_path, cli, shared_cache):
    store = tmp_path / "f7.zarr"
    cli(["generate", "finger7-v1", "--quick", "--out", store, "--workers", "1"])
    direct = evaluate("finger7-v1", {"r": raw_ridge()}, quick=True, classifiers="none")
    stored = evaluate("finger7-v1", {"r": raw_ridge()}, quick=True, classifiers="none", store=store)
    assert stored["results"][0]["accuracies"] == direct["results"][0]["accuracies"]
    assert stored["timing"]["simulate_s"] == 0.0


@pytest.mark.slow
@pytest.mark.xdist_group("finger7-v1-quick")  # one worker: the first simulates, the rest read
def test_the_worked_example_scores_on_finger7_and_roughness8(tmp_path, cli):
    for task in ("finger7-v1", "roughness8-v1"):
        p = cli(
            [
                "run",
                task,
                "--quick",
                "--classifiers",
                "none",
                "--method",
                f"delta={EXAMPLE}:delta_nearest_mean",
                "--out",
                tmp_path / task,
                "--json",
            ]
        )
        (row,) = json.loads(p.stdout)["results"]
        assert row["label"] == "delta" and row["accuracy_mean"] > 2 / 8, (task, row)
