"""The worked example of examples/own_sensor_and_plates in its quick form, as a new user runs
it: generate the configuration's store, then run the configuration on it."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "own_sensor_and_plates"


@pytest.mark.slow
def test_the_example_generates_and_runs(cli, tmp_path):
    ex = tmp_path / "ex"
    shutil.copytree(EXAMPLE, ex)  # as a user's own folder
    cli(["generate", ex / "set.toml", "--quick", "--out", ex / "my.zarr", "--workers", "2"])
    res = cli(
        [
            "run",
            ex / "set.toml",
            "--quick",
            "--store",
            ex / "my.zarr",
            "--out",
            ex / "report",
            "--json",
        ]
    )
    rep = json.loads(res.stdout)
    assert rep["task"] == "config:my4x4-textures"
    assert rep["dataset"]["channels"] == 16 and rep["dataset"]["classes"] == 4
    assert [r["classifier"] for r in rep["results"]] == ["svm-raw", "svm-spike"]
    assert rep["timing"]["simulate_s"] == 0.0  # read from the store
    spike = rep["results"][1]["accuracy_mean"]
    assert spike > 0.4  # the gratings are told apart well above chance (0.25)
    # another configuration's store is refused before anything is scored
    other = ex / "other.toml"
    other.write_text((ex / "set.toml").read_text().replace("seed = 0", "seed = 1"))
    p = cli(["run", other, "--quick", "--store", ex / "my.zarr", "--out", ex / "r2"], check=False)
    assert p.returncode == 2 and "another configuration" in p.stderr


@pytest.mark.slow
def test_a_bad_evaluate_table_is_refused_before_anything_runs(tmp_path):
    from sim_tactile.errors import ConfigError
    from sim_tactile.tasks.config_task import config_task

    ex = tmp_path / "ex"
    shutil.copytree(EXAMPLE, ex)
    text = (ex / "set.toml").read_text()
    for change, words in [
        ('classifiers = ["svm-raw", "svm-spike"]', ["evaluate.classifiers", "svm-rbf", "knn"]),
        ("repeats = 5", ["evaluate.repeats", "0", "[1, 10000]"]),
        ('split = "7:3"', ["unknown key(s) evaluate.folds", "valid: evaluate."]),
    ]:
        bad = {
            'classifiers = ["svm-raw", "svm-spike"]': 'classifiers = ["svm-rbf"]',
            "repeats = 5": "repeats = 0",
            'split = "7:3"': "folds = 3",
        }[change]
        (ex / "bad.toml").write_text(text.replace(change, bad))
        with pytest.raises(ConfigError) as exc:
            config_task(ex / "bad.toml")
        for w in words:
            assert w in str(exc.value), (w, str(exc.value))
    spec, seed = config_task(ex / "set.toml")
    assert spec.id == "config:my4x4-textures" and seed == 0 and spec.full.repeats == 5
