"""One default seed for the Python API and the command line: a configuration file's own
seed, with which ``generate`` wrote its store (``evaluate(CONFIG, store=...)`` took 0 and
was refused the store that ``run CONFIG --store`` reads)."""

from __future__ import annotations

import json

import pytest
from sklearn.linear_model import RidgeClassifier
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import FunctionTransformer

from sim_tactile.cli import main
from sim_tactile.errors import ConfigError, StoreError
from sim_tactile.generate import generate
from sim_tactile.tasks import evaluate

#: A small slide set (2 plates x 3 slides of 0.2 s) whose file carries its own seed, 7.
CONFIG = json.dumps(
    {
        "name": "seeded",
        "seed": 7,
        "sensor": "grid3x3",
        "plates": ["finger7/flat", "finger7/ridges-2"],
        "slides_per_plate": 3,
        "protocol": {"duration_s": 0.2},
        "evaluate": {"split": "2/1", "repeats": 2},
    }
)


def _flat(X):
    return X.reshape(len(X), -1)


@pytest.fixture
def seeded(tmp_path, cache_dir, monkeypatch):
    """The configuration (seed 7) and the store ``generate`` wrote from it."""
    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))
    cfg = tmp_path / "seeded.json"
    cfg.write_text(CONFIG)
    store = tmp_path / "seeded.zarr"
    generate(str(cfg), store, workers=1, progress=False, log=lambda m: None)
    return cfg, store


class _Seen(Exception):
    pass


def test_evaluate_passes_no_seed_and_the_run_takes_the_files(tmp_path, monkeypatch):
    """Without simulating: the seed the task's data would be loaded with."""
    import sim_tactile.tasks.runner as runner

    def seen(spec, **kw):
        raise _Seen(kw["seed"])

    monkeypatch.setattr(runner, "load_task", seen)
    cfg = tmp_path / "seeded.json"
    cfg.write_text(CONFIG)
    ridge = Pipeline([("flat", FunctionTransformer(_flat)), ("r", RidgeClassifier())])
    for kw, want in (({}, 7), ({"seed": 3}, 3)):
        with pytest.raises(_Seen) as exc:
            evaluate(str(cfg), {"ridge": ridge}, classifiers="none", **kw)
        assert exc.value.args == (want,)
    with pytest.raises(_Seen) as exc:  # a task id: 0
        evaluate("finger7-v1", {"ridge": ridge}, classifiers="none")
    assert exc.value.args == (0,)


@pytest.mark.slow
def test_evaluate_and_run_take_the_configurations_seed_by_default(seeded, tmp_path, capsys):
    cfg, store = seeded
    ridge = Pipeline([("flat", FunctionTransformer(_flat)), ("r", RidgeClassifier())])
    rep = evaluate(str(cfg), {"ridge": ridge}, store=store, classifiers="none")
    assert rep["protocol"]["seed"] == 7
    args = ["run", str(cfg), "--store", str(store), "--classifiers", "svm-raw", "--json"]
    assert main([*args, "--out", str(tmp_path / "cli")]) == 0
    assert json.loads(capsys.readouterr().out)["protocol"]["seed"] == 7
    # another seed is another data set: the store made with 7 is refused, by name
    with pytest.raises((ConfigError, StoreError), match="seed"):
        evaluate(str(cfg), {"ridge": ridge}, store=store, classifiers="none", seed=0)
