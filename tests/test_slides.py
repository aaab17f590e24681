"""The slide engine: jobs keyed by content, one random draw, backends that agree, and a
cache that never serves a stale slide (tested on an edited copy of the package)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import sim_tactile
from sim_tactile.errors import ConfigError
from sim_tactile.plates import Plate, Ridges, get_plate
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.slides import SlideJob, SlideSet, make_backend, run_slides, stream
from sim_tactile.slides.jobs import SLIDE_MODULES

TWO = ("finger7/flat", "finger7/ridges-2")


def _job(**change) -> SlideJob:
    base = SlideJob(
        get_plate("finger7/ridges-4"),
        get_sensor("grid3x3"),
        Protocol(duration_s=0.2, rate_hz=100.0, speed_jitter=0.05),
        seed=11,
    )
    return replace(base, **change)


def test_a_slide_is_keyed_by_everything_that_determines_it():
    job = _job()
    assert job.key() == _job().key()
    # the plate by its parameters, not its name
    renamed = Plate(get_plate("finger7/ridges-4").texture, name="my/ridges")
    assert _job(plate=renamed).key() == job.key()
    wider = Plate(Ridges(count=4, width_m=2.6e-3, height_m=2.5e-3), name="finger7/ridges-4")
    others = [
        _job(plate=wider),
        _job(seed=12),
        _job(fidelity="L0"),
        _job(ideal=True),
        _job(protocol=replace(job.protocol, force_n=1.5)),
        _job(protocol=replace(job.protocol, speed_jitter=0.06)),
        _job(finger=replace(job.sensor.finger, young_pa=0.4e6)),
        _job(
            sensor=replace(
                job.sensor, imperfections=replace(job.sensor.imperfections, noise_std=0.01)
            )
        ),
        _job(sensor=get_sensor("multilayer3x3x2")),
    ]
    keys = [o.key() for o in others]
    assert job.key() not in keys and len(set(keys)) == len(keys)
    assert job.describe()["plate"] == get_plate("finger7/ridges-4").params()


def test_the_draw_is_the_simulations(cache):
    """A job's drawn protocol is the one the simulation ran (made in one place)."""
    job = _job(
        protocol=Protocol(duration_s=0.1, speed_jitter=0.2, force_jitter=0.2, offset_jitter_m=1e-3)
    )
    rec = job.simulate(cache).recording
    drawn = job.drawn()
    assert rec.meta["protocol"]["speed_m_s"] == drawn.speed_m_s
    assert rec.meta["protocol"]["force_n"] == drawn.force_n
    assert rec.meta["protocol"]["offset_y_m"] == drawn.offset_y_m
    assert drawn.speed_m_s != job.protocol.speed_m_s  # it did vary
    assert rec.data.shape[0] == job.n_samples() == 10


def test_slide_set_validation():
    proto = Protocol()
    with pytest.raises(ConfigError, match="at least 2 plates"):
        SlideSet(("finger7/flat",), "grid3x3", proto, 4, 2)
    with pytest.raises(ConfigError, match="not a preset"):
        SlideSet(("finger7/flat", "finger7/nope"), "grid3x3", proto, 4, 2)
    with pytest.raises(ConfigError, match="sensor 'grid9'"):
        SlideSet(TWO, "grid9", proto, 4, 2)
    with pytest.raises(ConfigError, match="quick_slides"):
        SlideSet(TWO, "grid3x3", proto, 4, 5)


def test_a_sets_slides_know_the_full_runs_slides_a_plate():
    """Each slide of a set knows how many slides of its plate the full run makes (what
    ``auto`` weighs a table shared by them against), in the quick run too, so that a quick
    run's slides are the full run's first ones, bit for bit."""
    ss = SlideSet(TWO, "grid3x3", Protocol(), 4, 2)
    full, quick = ss.jobs(3), ss.jobs(3, quick=True)
    assert {j.plate_slides for j in full + quick} == {4}
    assert [j.describe() for j in quick] == [
        j.describe() for j in full if j.label in {q.label for q in quick}
    ]


def test_a_sets_time_step_reaches_its_slides_and_its_description():
    """``SlideSet(dt_s=...)`` steps every slide at most that long (a piezoelectric sensor's
    vibration asks for it); the set's description and each slide's key record it, so
    nothing stepped otherwise is served for it; out of range, the error names it."""
    base = SlideSet(TWO, "grid3x3", Protocol(), 4, 2)
    fine = replace(base, dt_s=1.25e-4)
    jobs = fine.jobs(0)
    assert {j.dt_s for j in jobs} == {1.25e-4}
    assert all(j.resolved.dt_s <= 1.25e-4 for j in jobs)
    assert fine.describe()["dt_s"] == 1.25e-4 and "dt_s" not in base.describe()
    assert jobs[0].key() != base.jobs(0)[0].key()
    with pytest.raises(ConfigError, match=r"dt_s = 0\.1 s is out of range"):
        replace(base, dt_s=0.1)


def test_a_configuration_file_forces_the_step_and_the_node_pitch(tmp_path):
    """``dt_s`` and ``pitch_m`` in a configuration file reach the set and its slides (what
    the vibration and pitch warnings ask a ``generate`` user to set); a value out of range or
    not a number is refused naming the file, the key, the value and the valid range."""
    from sim_tactile.slides.config import config_slide_set, load_config

    def set_of(extra: str):
        path = tmp_path / "c.toml"
        path.write_text(
            f'plates = {list(TWO)!r}\nsensor = "grid3x3"\nslides_per_plate = 4\n{extra}'.replace(
                "'", '"'
            )
        )
        return config_slide_set(load_config(path), where=str(path), base_dir=tmp_path)[0]

    ss = set_of("dt_s = 1.25e-4\npitch_m = 4e-4\n")
    assert (ss.dt_s, ss.pitch_m) == (1.25e-4, 4e-4)
    job = ss.jobs(0)[0]
    assert job.resolved.dt_s <= 1.25e-4 and job.resolved.pitch_m == 4e-4
    assert set_of("").jobs(0)[0].key() != job.key()
    with pytest.raises(
        ConfigError, match=r"c\.toml: dt_s = 0\.5 s is out of range; valid: \[1e-06, 0\.01\]"
    ):
        set_of("dt_s = 0.5\n")
    with pytest.raises(ConfigError, match=r"c\.toml: pitch_m must be a number .*got 'fine'"):
        set_of('pitch_m = "fine"\n')


@pytest.mark.parametrize("dt_s", [-1.0, 0.0, 1.0, float("nan")])
def test_a_slides_own_step_out_of_range_is_refused_naming_it(dt_s):
    """``Slide(dt_s=...)`` (and so ``simulate``) checks the step it forces as a set does: a
    negative, zero or too long step was taken silently (clamped to the sample period, or the
    fidelity's own), and NaN failed deep inside the planner."""
    from sim_tactile.sim import Slide

    with pytest.raises(ConfigError, match=r"dt_s .* valid: \[1e-06, 0\.01\] s"):
        Slide(get_plate(TWO[0]), "grid3x3", dt_s=dt_s)
    with pytest.raises(ConfigError, match=r"pitch_m .* valid: \[2e-05, 0\.005\] m"):
        Slide(get_plate(TWO[0]), "grid3x3", pitch_m=dt_s)


def test_slides_are_cached_and_reproducible(cache):
    """Two slides of two plates: a second call reads the cache and gives identical data; the
    window is the crossing time at the nominal speed, so every slide has one length."""
    ss = SlideSet(
        TWO,
        "grid3x3",
        Protocol(speed_m_s=0.12, speed_jitter=0.05, force_jitter=0.1),
        slides=2,
        quick_slides=2,
    )
    jobs = ss.jobs(seed=3)
    assert len({j.seed for j in jobs}) == 4
    recs, stats = run_slides(jobs, cache=cache, workers=1)
    assert stats["slides_simulated"] + stats["slides_cached"] == 4
    again, stats2 = run_slides(jobs, cache=cache, workers=1)
    assert stats2["slides_simulated"] == 0 and stats2["simulate_s"] == 0.0
    for a, b in zip(recs, again, strict=True):
        assert a.data.tobytes() == b.data.tobytes()
    assert recs[0].data.shape[0] == ss.n_time() == jobs[0].n_samples()
    # flat ground: no pulses; ridges: load moves with the ridges under the pad
    assert np.ptp(recs[2].data[:, 4]) > 5 * np.ptp(recs[0].data[:, 4])
    # a different seed is a different slide (jittered speed and force, sensor noise)
    other, _ = run_slides(ss.jobs(seed=4)[:1], cache=cache, workers=1)
    assert not np.array_equal(other[0].data, recs[0].data)


def _square(x: int) -> int:
    return x * x


def test_the_backends_run_every_item_once():
    items = [(k, k + 1) for k in range(9)]
    for workers in (1, 2):
        backend = make_backend(_square, workers=workers)
        try:
            got = dict(stream(backend, items))
        finally:
            backend.close()
        assert got == {k: (k + 1) ** 2 for k in range(9)}, workers
    with pytest.raises(ConfigError, match="backend = 'gpu'"):
        make_backend(_square, kind="gpu")
    with pytest.raises(ConfigError, match="ray backend"):
        make_backend(_square, address="localhost:6379")


def test_the_slide_code_is_the_simulations_import_closure():
    from sim_tactile.hashing import import_closure

    closure = import_closure(*SLIDE_MODULES)
    for m in (
        "plates.read.presets",
        "plates.define.spec",
        "plates.make.mjcf",
        "sim.step.held",
        "sensors.transducers",
    ):
        assert f"sim_tactile.{m}" in closure, m
    for m in ("learn", "tasks", "datasets.store", "generate", "cli"):  # nothing downstream
        assert not any(c.startswith(f"sim_tactile.{m}") for c in closure), m


def test_the_slide_key_follows_the_measured_errors_table(tmp_path, monkeypatch):
    """auto picks its node grid from the measured errors: a table that changes changes every
    slide's key, so no slide made under the old table is served. The table is read once a
    process (a memo), and so is its digest in the key: a process reads both again together
    (forget_process_memos), so a key never names a table the process did not read."""
    from sim_tactile.cache import forget_process_memos
    from sim_tactile.slides import jobs

    table = tmp_path / "measured_errors.json"
    table.write_text('{"rows": []}')
    monkeypatch.setattr(jobs, "SLIDE_DATA", (table,))
    v1 = jobs.slide_code_version()
    assert v1 == jobs.slide_code_version()
    table.write_text('{"rows": [{"key": "x"}]}')
    assert jobs.slide_code_version() == v1  # the process still reads the table it read
    forget_process_memos()
    v2 = jobs.slide_code_version()
    assert v2 != v1
    table.unlink()
    forget_process_memos()
    assert jobs.slide_code_version() not in (v1, v2)
    assert jobs.SLIDE_DATA != (jobs.measured_errors.TABLE,)  # the patch took
    monkeypatch.undo()
    assert jobs.SLIDE_DATA == (jobs.measured_errors.TABLE,)


_SCRIPT = """
import json, sys
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.slides import SlideSet, run_slides
ss = SlideSet(("finger7/flat", "finger7/ridges-2"), "grid3x3",
              Protocol(duration_s=0.4, speed_jitter=0.05), slides=2, quick_slides=2)
recs, stats = run_slides(ss.jobs(seed=0), workers=1)
print(json.dumps({"simulated": stats["slides_simulated"], "ridges": recs[-1].data.tolist()}))
"""


@pytest.mark.slow
def test_an_edited_preset_is_simulated_again(tmp_path):
    """Edit a preset's ridge height in a copy of the package and its assets: that plate's
    slides are simulated again (their key holds the plate's parameters and the source of
    every module that makes them) and the other plate's are not, while an edit to a module
    no slide imports keeps them all cached."""
    src = Path(sim_tactile.__file__).parent
    pkg = tmp_path / "copy" / "sim_tactile"
    shutil.copytree(src, pkg)  # with its compiled caches (mtimes kept: numba reuses them)
    # the presets' files, where the copy imports them from (sim_tactile.assets)
    shutil.copytree(src.parent / "assets", pkg / "assets")
    env = {**os.environ, "PYTHONPATH": str(pkg.parent), "SIM_TACTILE_CACHE": str(tmp_path / "c")}

    def run() -> dict:
        p = subprocess.run(
            [sys.executable, "-c", _SCRIPT], env=env, capture_output=True, text=True, cwd=tmp_path
        )
        assert p.returncode == 0, p.stderr[-2000:]
        return json.loads(p.stdout)

    first = run()
    assert first["simulated"] == 4
    assert run()["simulated"] == 0  # cached
    learn = pkg / "learn" / "src.py"
    learn.write_text(learn.read_text() + "\n# an edit no slide can see\n")
    assert run()["simulated"] == 0
    preset = pkg / "assets" / "plates" / "finger7" / "ridges-2.toml"
    text = preset.read_text()
    old = "height_m = 0.0025"
    assert old in text
    preset.write_text(text.replace(old, "height_m = 0.001"))
    edited = run()
    assert edited["simulated"] == 2  # the ridges' two slides; flat's are kept
    assert edited["ridges"] != first["ridges"]  # and the lower ridges read differently


@pytest.mark.slow
def test_every_tasks_slides_keep_their_descriptions():
    """A slide's description (its cache key's content) on the per-step reference path is the
    one it had before ``Slide`` described it once (tests/data/slide_descriptions.json, written
    from SlideJob.describe at 4c60226 by ``python tools/slide_descriptions.py``): key for key,
    on every simulated task's quick and full slides. The default path (``auto``) differs from
    it only by the keys it adds: ``path`` exactly where the slide is read off a phase table,
    ``press`` exactly where it presses once under a held force, and the knobs it chose
    (``solve_tol``, ``solve_every``, ``skin_solver``, ``held_solve``), so nothing either path
    made is served for the other."""
    import json
    from dataclasses import replace
    from pathlib import Path

    from sim_tactile.hashing import content_hash
    from sim_tactile.tasks import get_task, task_ids

    released = json.loads((Path(__file__).parent / "data" / "slide_descriptions.json").read_text())
    chosen = {"path", "press", "solve_tol", "solve_every", "skin_solver", "held_solve"}
    for t, runs in released.items():
        ss = get_task(t).get_data
        for run, digest in runs.items():
            jobs = ss.jobs(seed=0, quick=run == "quick")
            reference = []
            for j in jobs:
                d = j.describe()
                assert ("path" in d) == (j.table_plan() is not None), j.label
                assert ("press" in d) == j.held_press, j.label
                ref = replace(j, options=replace(j.options, path="per-step")).describe()
                reference.append(ref)
                assert {k: x for k, x in d.items() if k not in chosen} == {
                    k: x for k, x in ref.items() if k not in chosen
                }, j.label
            assert content_hash(reference) == digest, (t, run)
    simulated = {t for t in task_ids() if isinstance(get_task(t).get_data, SlideSet)}
    assert set(released) == simulated, "a simulated task was added or removed"
