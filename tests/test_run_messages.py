"""What a run's report says about itself: a quick run's own counts (the title and the notes
describe the full protocol), and rows a reader should not take at face value flagged in the
table and the report (one accuracy on every random split; an encoder that barely spikes)."""

from __future__ import annotations

import pytest
from _fake_task import tones_fixture
from sklearn.dummy import DummyClassifier
from sklearn.pipeline import make_pipeline
from sklearn.svm import SVC

from sim_tactile import tasks
from sim_tactile.encoders import LIFEncoder
from sim_tactile.learn.preprocess import SpikeCounts
from sim_tactile.tasks.flags import SAME_ON_EVERY_SPLIT_FROM, row_flags
from sim_tactile.tasks.report import Report, ResultRow


@pytest.fixture(scope="module")
def tones(tmp_path_factory, cache_dir):
    """The tones task and its quick store (tests/_fake_task.py)."""
    yield from tones_fixture(tmp_path_factory, cache_dir)


def _enc(per_s: float) -> dict:
    return {"encoder": {"spikes_per_s": 9 * per_s, "spikes_per_s_per_channel": per_s}}


def test_the_flags_and_where_they_start():
    n = SAME_ON_EVERY_SPLIT_FROM
    assert "the same accuracy (0.571) on all 50" in row_flags([4 / 7] * 50, None, 1.0)[0]
    assert row_flags([1.0] * 50, None, 1.0) == []  # perfect on every split is no fault
    assert row_flags([0.5] * (n - 1), None, 1.0) == []  # too few splits to tell
    assert row_flags([0.5, 0.6] * n, None, 1.0) == []
    # 144 spikes in 56 slides of 0.94 s on 9 channels: 0.29 spikes per channel per slide
    silent = row_flags([0.2, 0.3], _enc(144 / 56 / 0.94 / 9), 0.94)
    assert len(silent) == 1 and "0.29 spikes per channel per slide" in silent[0]
    assert "raise its gain" in silent[0]
    assert row_flags([0.9, 1.0], _enc(25.3 / 9), 0.94) == []  # finger7's encoder: 2.6


def _report(quick: bool, flags: list[str]) -> Report:
    row = ResultRow(
        "snn", "snn", "rasters", 0.286, 0.0, None, 50, {"message": "-"}, extra={"flags": flags}
    )
    return Report(
        task="finger7-v1",
        title="Soft finger, 7 plates x 32 slides",
        quick=quick,
        results=[row],
        timing={"simulate_s": 0, "encode_s": 0, "classify_s": 0},
        figures=[],
        protocol={"split": "6/2", "repeats": {"snn": 5, "svm-spike": 50}, "seed": 0}
        | {"encoding": "SA-I Izhikevich"},
        dataset={"samples": 56, "classes": 7, "per_class": [8] * 7, "time_steps": 94}
        | {"rate_hz": 100.0, "channels": 9},
        remarks=["each of the 1000 splits fits the SVM"],
        reference="",
        environment={},
    )


def test_a_quick_report_gives_its_own_counts_and_flags_its_rows():
    rep = _report(True, ["the encoder makes 0.29 spikes per channel per slide"])
    this = "This run: 56 slides (7 classes, 8 per class), split 6/2, repeats: snn 5, svm-spike 50"
    for text in (rep.text(), rep.markdown()):
        assert this in text
        assert "! snn" in text and "! snn: the encoder makes 0.29 spikes" in text
    assert "## Notes (on the full protocol)" in rep.markdown()
    full = _report(False, [])
    assert "This run" not in full.text() + full.markdown() and "! " not in full.text()
    assert "## Notes\n" in full.markdown()


@pytest.mark.slow
def test_a_run_flags_a_constant_model_and_a_silent_encoder(tones):
    """A model that always answers one class scores 4/12 on every split of 8/4 per class;
    an LIF encoder at a gain of 0.001 barely spikes: both rows are marked, and said why."""
    methods = {
        "constant": DummyClassifier(strategy="most_frequent"),
        "silent": (LIFEncoder(gain=1e-3, normalize="minmax"), make_pipeline(SpikeCounts(), SVC())),
    }
    rep = tasks.evaluate(
        tones.task, methods, quick=True, store=tones.store, classifiers="svm-raw", repeats=5
    )
    rows = {r["label"]: r for r in rep["results"]}
    assert rows["constant"]["accuracies"] == [pytest.approx(1 / 3)] * 5
    assert "the same accuracy (0.333) on all 5" in rows["constant"]["flags"][0]
    said = rows["silent"]["flags"]
    assert any("spikes per channel per slide" in f for f in said), rows["silent"].get(
        "neuromorphic"
    )
    assert "flags" not in rows["svm-raw"]
    text = Report.from_json(rep).text()
    assert "! constant" in text and "! silent" in text and "! svm-raw" not in text


def test_a_task_whose_rows_need_torch_names_them_and_the_way_round(monkeypatch, tmp_path):
    """On an installation without torch (the core install), a real-data task's run names
    its torch rows, the install command and the --classifiers that runs the rest."""
    import sys

    from sim_tactile.errors import MissingDependencyError

    monkeypatch.setitem(sys.modules, "torch", None)  # import torch fails, as without it
    with pytest.raises(MissingDependencyError) as exc:
        tasks.run_task("biotac20-real-v1", tmp_path / "out", quick=True, log=lambda m: None)
    msg = str(exc.value)
    assert "biotac20-real-v1" in msg and "lstm, snn need torch" in msg
    assert "pip install 'sim-tactile[learn]'" in msg
    assert msg.endswith("--classifiers svm-raw,svm-spike")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("kind", "name", "offered"),
    [
        ("task", "finger7-v9", "(did you mean 'finger7-v"),
        ("task", "roughnes8-v1", "(did you mean 'roughness8-v1'?)"),
        ("plate", "finger7/ridge-4", "(did you mean 'finger7/ridges-4'"),
        ("plate", "ridges-4", "'finger7/ridges-4'"),
        ("plate", "finger7/nope", None),
        ("sensor", "grid3x4", "(did you mean 'grid3x3'?)"),
        ("sensor", "biotac", "(did you mean 'biotac19'?)"),
        ("classifier", "svm_spike", "(did you mean 'svm-spike'"),
        ("task", "qqq", None),
    ],
)
def test_an_unknown_name_gets_the_closest_ones(kind, name, offered):
    from sim_tactile.errors import UnknownNameError
    from sim_tactile.learn.classifiers import get_classifier
    from sim_tactile.plates import get_plate
    from sim_tactile.sensors import get_sensor, resolve_sensor

    get = {
        "task": tasks.get_task,
        "plate": get_plate,
        "sensor": get_sensor,
        "classifier": get_classifier,
    }[kind]
    calls = [get, resolve_sensor] if kind == "sensor" else [get]
    for call in calls:
        with pytest.raises(UnknownNameError) as exc:
            call(name)
        msg = str(exc.value)
        # the valid names, or a task's family's versions
        assert repr(name) in msg and ("valid:" in msg or "has versions" in msg)
        if offered is None:
            assert "did you mean" not in msg
        else:
            assert offered in msg, msg
