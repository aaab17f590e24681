"""The task registry: released ids keep their meaning (their whole description is pinned),
aliases, removal, and every simulated task's slides are deterministic."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from sim_tactile.errors import ConfigError, UnknownNameError
from sim_tactile.slides import SlideSet
from sim_tactile.tasks import TaskSpec, get_task, register, task_ids
from sim_tactile.tasks.registry import alias, unregister

DESCRIPTIONS = Path(__file__).parent / "data" / "task_descriptions.json"
#: Length of each task's determinism slide [s]: the pad reaches the texture's first features.
DETERMINISM_WINDOW_S = 0.3


def test_every_released_task_keeps_its_description():
    """Each task's whole definition (data, protocol, settings, runs, paper cells) as it was
    released; a difference is a new task version, not an edit (``python
    tools/task_descriptions.py`` only when a task is added). The quick form (``quick``, a
    smoke run) is pinned too, in the next test."""
    released = json.loads(DESCRIPTIONS.read_text())
    now = {t: get_task(t).describe() for t in task_ids()}
    assert sorted(now) == sorted(released), "a task was added or removed"
    for t in released:
        full = {k: v for k, v in now[t].items() if k != "quick"}
        assert full == {k: v for k, v in released[t].items() if k != "quick"}, (
            f"task {t} changed meaning: release a new version"
        )


def test_every_task_keeps_its_quick_form():
    """A task's quick form is pinned as well: a change to it is a change of every quick run's
    numbers, said in the CHANGELOG when the file is written again."""
    released = json.loads(DESCRIPTIONS.read_text())
    for t in task_ids():
        assert get_task(t).describe()["quick"] == released[t]["quick"], (
            f"task {t}'s quick form changed: say so in the CHANGELOG and run "
            "tools/task_descriptions.py"
        )


def test_the_quick_form_caps_the_networks_and_keeps_a_task_own():
    """Where a task's quick settings give the torch rows nothing, they get the quick
    network settings and at most QUICK_NETWORK_REPEATS repeats; a task's own stay."""
    from sim_tactile.tasks.registry import QUICK_NETWORK_PARAMS, QUICK_NETWORK_REPEATS

    finger = get_task("finger7-v1").settings(quick=True)
    assert finger.repeats_for("snn") == QUICK_NETWORK_REPEATS < finger.repeats_for("svm")
    assert dict(finger.params["snn"]) == dict(QUICK_NETWORK_PARAMS["snn"])
    assert get_task("finger7-v1").settings(quick=False).repeats_for("snn") == 1000
    biotac = get_task("biotac20-real-v1").settings(quick=True)
    assert biotac.repeats_for("snn") == 1 and biotac.params["snn"]["epochs"] == 12


def test_aliases_resolve_and_removal_is_explicit():
    base = get_task("finger7-v1")
    spec = replace(base, id="registry-probe-v1", bench=None)
    register(spec)
    try:
        alias("registry-probe", spec.id)
        assert get_task("registry-probe") is spec and "registry-probe" not in task_ids()
        with pytest.raises(ConfigError, match="already registered"):
            alias("registry-probe", "finger7-v1")
    finally:
        unregister(spec.id)
    with pytest.raises(UnknownNameError):
        get_task("registry-probe")
    with pytest.raises(UnknownNameError, match="not registered"):
        unregister(spec.id)


def test_a_task_has_data_or_parts():
    kw = {"title": "t", "classifiers": ("svm",)}
    with pytest.raises(ConfigError, match="get_data .* or parts"):
        register(TaskSpec(id="neither-v1", get_data=None, **kw))
    with pytest.raises(ConfigError, match="get_data .* or parts"):
        register(
            TaskSpec(id="both-v1", get_data=get_task("finger7-v1").get_data, parts=("a",), **kw)
        )


SIMULATED = [t for t in task_ids() if isinstance(get_task(t).get_data, SlideSet)]


#: the iCub's spectral slides take 5-15 s each: in the full suite only
SLOW_TASKS = {"textures20-icub60-v1", "textures20-icub60-v2"}


@pytest.mark.parametrize(
    "task_id",
    [pytest.param(t, marks=pytest.mark.slow) if t in SLOW_TASKS else t for t in SIMULATED],
)
def test_every_simulated_task_is_deterministic(task_id, cache):
    """One short slide of each task, simulated twice from the same seed: the same bits (on
    the probe rig, its whole window: a pass takes a second, and it is computed in about one)."""
    job = get_task(task_id).get_data.jobs(seed=0, quick=True)[-1]
    if job.rig is None:
        job = replace(job, protocol=replace(job.protocol, duration_s=DETERMINISM_WINDOW_S))
    a = job.simulate(cache).recording
    b = job.simulate(cache).recording
    assert a.data.tobytes() == b.data.tobytes()
    assert a.meta["normal_force_n"] == b.meta["normal_force_n"]
    assert a.data.any()


# -- versions: successors, history, suites and the error of an unknown id ---------------------


@pytest.fixture
def warned(monkeypatch):
    """The set of ids warned of this process, empty for the test."""
    import sim_tactile.tasks.registry as reg

    monkeypatch.setattr(reg, "_WARNED", set())
    return reg._WARNED


def test_each_v2_supersedes_its_v1_and_core_v1_lists_current_ids():
    from sim_tactile.tasks.registry import latest, successor, suite

    for old, new in (
        ("finger7-v1", "finger7-v2"),
        ("multilayer3-v1", "multilayer3-v2"),
        ("textures20-v1", "textures20-v2"),
        ("textures20-biotac19-v1", "textures20-biotac19-v2"),
        ("textures20-icub60-v1", "textures20-icub60-v2"),
    ):
        assert successor(old) == new and latest(old) == new and get_task(new).supersedes == old
    core = suite("core-v1")
    assert all(latest(t) == t and not get_task(t).parts for t in core)
    families = {t.rsplit("-v", 1)[0] for t in task_ids() if not get_task(t).parts}
    assert {t.rsplit("-v", 1)[0] for t in core} == families  # one current id of each


def test_a_superseded_id_warns_once_naming_its_successor(warned):
    from sim_tactile.tasks.registry import OutdatedTaskWarning, use_task

    with pytest.warns(OutdatedTaskWarning, match="textures20-biotac19-v2 supersedes it") as rec:
        use_task("textures20-biotac19-v1")
        use_task("textures20-biotac19-v1")
        use_task("textures20-biotac19-v2")  # current: no warning
    assert len(rec) == 1 and "still runs as released" in str(rec[0].message)


def test_every_version_has_its_own_history_and_one_successor():
    v1 = get_task("finger7-v1")
    assert v1.history and v1.history != get_task("finger7-v2").history
    with pytest.raises(ConfigError, match="its history is finger7-v1's"):
        register(replace(v1, id="finger7-v3", bench=None))
    with pytest.raises(ConfigError, match="finger7-v1 is already superseded by finger7-v2"):
        register(replace(v1, id="finger7-v3", bench=None, history=("x",), supersedes="finger7-v1"))
    with pytest.raises(ConfigError, match="valid: a registered older version of the family"):
        register(
            replace(v1, id="finger7-v3", bench=None, history=("x",), supersedes="roughness8-v1")
        )
    assert "finger7-v3" not in task_ids()


def test_history_and_succession_are_not_the_definition():
    d = get_task("finger7-v2").describe()
    assert "history" not in d and "supersedes" not in d


@pytest.mark.parametrize(
    "asked, message",
    [
        ("finger7-v9", "the family finger7 has versions v1, v2: finger7-v1, finger7-v2"),
        ("finger7", "the family finger7 has versions v1, v2"),
        ("fingr7-v1", "did you mean 'finger7-v1'"),
        ("zzz", "is not known; valid: finger7-v1"),
    ],
)
def test_an_unknown_id_names_its_family_or_the_closest(asked, message):
    with pytest.raises(UnknownNameError, match=message):
        get_task(asked)


def test_a_superseded_suite_warns_once_for_itself_and_its_parts(warned, tmp_path):
    from sim_tactile.tasks import run_task
    from sim_tactile.tasks.registry import OutdatedTaskWarning

    with pytest.warns(OutdatedTaskWarning) as rec, pytest.raises(ConfigError, match="nothing"):
        run_task("textures20-v1", tmp_path / "out", quick=True, classifiers="none")
    assert [str(w.message).split(":")[0] for w in rec] == ["task textures20-v1 is out of date"]
    assert "textures20-v2 supersedes it" in str(rec[0].message)


@pytest.mark.slow
def test_run_of_a_superseded_id_warns_once_and_names_the_newer_id(cli, tmp_path):
    """12 BioTac slides of the quick run (a few seconds), the raw SVM only."""
    out = tmp_path / "out"
    p = cli(["run", "textures20-biotac19-v1", "--quick", "--classifiers", "svm-raw", "--out", out])
    lines = [x for x in p.stderr.splitlines() if "out of date" in x]
    assert lines == [
        "sim-tactile: warning: task textures20-biotac19-v1 is out of date: "
        "textures20-biotac19-v2 supersedes it; textures20-biotac19-v1 still runs as released "
        "(the ids a paper should report: sim-tactile tasks --suite core-v1)"
    ]
    assert (out / "report.json").is_file()
