"""Ablation sweeps over a task's cached recordings."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sim_tactile.encoders import IzhikevichEncoder, ThresholdEncoder
from sim_tactile.errors import ConfigError, UnknownNameError
from sim_tactile.learn.classifiers import LearnContext
from sim_tactile.tasks import get_task
from sim_tactile.tasks.ablate import _point_spec, ablate, parse_sets


def test_parse_sets_values_and_errors():
    sets = parse_sets(["gain=5,15", "preset=RS,FS", "K=1,3", "q=0.5"])
    assert sets == {"gain": [5.0, 15.0], "preset": ["RS", "FS"], "K": [1, 3], "q": [0.5]}
    with pytest.raises(ConfigError, match="unknown parameter; valid"):
        parse_sets(["gian=5"])
    with pytest.raises(ConfigError, match="K = 0; valid: 1..10"):
        parse_sets(["K=0"])
    with pytest.raises(ConfigError, match="gain = -1; valid"):
        parse_sets(["gain=-1"])
    with pytest.raises(UnknownNameError, match="preset = 'XX'"):
        parse_sets(["preset=XX"])
    with pytest.raises(ConfigError, match="given twice"):
        parse_sets(["k=3", "k=5"])
    with pytest.raises(ConfigError, match="NAME=v1"):
        parse_sets(["gain"])


def test_point_spec_changes_the_encoders_and_classifiers():
    ctx = LearnContext(rate_hz=50.0, n_channels=4)  # the encodings read the rate
    icub = _point_spec(get_task("icub20-real"), {"K": 3})
    steps = dict(icub.encoder(ctx))
    assert steps["scale"].span == 4.0
    np.testing.assert_array_equal(steps["encode"].thresholds, [1.0, 2.0, 3.0])
    bio = dict(_point_spec(get_task("biotac20-real"), {"K": 3}).encoder(ctx))
    assert isinstance(bio["encode"], ThresholdEncoder)
    np.testing.assert_array_equal(bio["encode"].thresholds, [-1.0, 0.0, 1.0])
    ml = _point_spec(get_task("multilayer3-v1"), {"gain": 40.0, "d": 4.0})
    enc = dict(ml.encoder(ctx))["encode"]
    assert isinstance(enc, IzhikevichEncoder) and enc.gain == 40.0 and enc.max_rate_hz is None
    assert {p.d for p in enc.preset} == {4.0} and {p.a for p in enc.preset} == {0.1, 0.02}
    r8 = {r.name: r for r in _point_spec(get_task("roughness8-v1"), {"q": 6.0, "k": 3}).runs}
    # the swept values are written into the labels
    assert r8["VP q=6/s k=3 film1 9:1"].params["q"] == 6.0
    assert r8["VP q=6/s k=3 film1 9:1"].params["n_neighbors"] == 3
    assert "q" not in r8["ISI k=3 film1 9:1"].params  # q belongs to Victor-Purpura only


@pytest.mark.slow
def test_ablate_roughness_reuses_the_slides(tmp_path, cache_dir, monkeypatch):
    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))
    monkeypatch.setenv("SIM_TACTILE_WORKERS", "2")
    lines: list[str] = []
    sets = {"gain": [60.0, 600.0], "k": [3]}
    rep = ablate("roughness8-v1", sets, tmp_path / "a", quick=True, repeats=5, log=lines.append)
    assert len(rep["rows"]) == 2 * len(get_task("roughness8-v1").runs)
    acc = {
        (r["params"]["gain"], r["run"]): r["accuracy_mean"]
        for r in rep["rows"]
        if r["run"].startswith("VP")
    }
    assert all("k=3" in r["label"] for r in rep["rows"] if r["run"].startswith("VP"))
    # the gain reaches the neurons: ten times the input changes the spike trains
    assert any(acc[(60.0, lab)] != acc[(600.0, lab)] for _, lab in acc)
    assert Path(rep["figures"][0]).read_bytes()[:4] == b"\x89PNG"
    doc = json.loads((tmp_path / "a" / "ablation.json").read_text())
    assert doc["sets"] == {"gain": [60.0, 600.0], "k": [3]}
    # a second sweep reads every slide from the cache
    lines.clear()
    ablate("roughness8-v1", {"q": [12.0]}, tmp_path / "b", quick=True, repeats=2, log=lines.append)
    assert not any(line.startswith("simulating") for line in lines)


@pytest.mark.slow
def test_cli_ablate_names_a_bad_parameter_and_writes_nothing(tmp_path, cli):
    bad = cli(["ablate", "roughness8-v1", "--set", "gian=3", "--out", tmp_path], check=False)
    assert bad.returncode == 2 and "--set gian: unknown parameter; valid: gain" in bad.stderr
    assert not list(tmp_path.iterdir())  # nothing written before the input is valid


def test_ablate_errors(tmp_path):
    with pytest.raises(ConfigError, match="does not use q"):
        ablate("finger7-v1", {"q": [1.0]}, tmp_path, quick=True)
    with pytest.raises(ConfigError, match="made of parts"):
        ablate("textures20-v1", {"K": [1]}, tmp_path, quick=True)
    with pytest.raises(ConfigError, match="--data PATH"):
        ablate("icub20-real", {"K": [1]}, tmp_path)
