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
