"""The phase table (sim/plan/phase.py, sim/step/phase_table.py, sim/step/tabled.py): a held
slide's loads solved over one texture period and read off by phase.

Against the per-step solve, the reference: on a plate of every task whose protocol holds
its force, the taxel loads of a slide read off the table are within the 2% the path is
chosen by (relative L2 over the slide), the pad's path is the per-step slide's bit for bit,
and a flat plate (one phase) is the per-step slide to the solver's tolerance. The table is
the same bit for bit whichever slide asks for it first, from the process, from the disk
cache or solved afresh; a damaged cache entry is solved again with a warning. Where the scene
does not allow it (no period, no held force), asking for it by name is one clear error.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest
from _scenes import task_slide

from sim_tactile.cache import ArtefactCache, forget_process_memos
from sim_tactile.errors import CacheWarning, ConfigError
from sim_tactile.plates import get_plate
from sim_tactile.sim import Protocol, Slide, StepOptions, run
from sim_tactile.sim.plan import phase, span
from sim_tactile.sim.plan.phase import (
    LEVELS_PER_OCTAVE,
    PhasePlan,
    force_levels,
    phase_plan,
    travel,
)
from sim_tactile.sim.plan.protocol import START_MARGIN_M
from sim_tactile.sim.plan.span import span_plan
from sim_tactile.sim.step.phase_table import PhaseTable
from sim_tactile.sim.step.shared_tables import TABLE_EXT, _from_arrays, _to_arrays

#: The table path is the default where its error against the per-step solve is at most
#: this (relative L2 of the taxel loads over a slide; the issue's and the manual's target).
REL_L2_TARGET = 0.02
#: A flat plate is one phase: the per-step slide's loads to the spectral or dense solve's
#: convergence (1e-10 of the pressures' sum per iteration; float32 data).
FLAT_RTOL = 1e-6

TABLE = StepOptions(path="phase-table")
STEP = StepOptions(path="per-step")


def _both(slide: Slide, cache):
    table = run(replace(slide, options=TABLE), cache).recording
    step = run(replace(slide, options=STEP), cache).recording
    return table, step


def _rel_l2(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


CASES = [
    # task, plate, window [s], protocol changes (a slide that starts on the texture is read
    # wholly off the table; one from flat ground is approached and solved per step off it)
    pytest.param("finger7-v1", "finger7/ridges-4", 0.9, {}, id="finger7-ridges-from-flat"),
    pytest.param("finger7-v1", "finger7/bumps-6x6", 0.25, {"start": "texture"}, id="finger7-bumps"),
    pytest.param(
        "multilayer3-v1",
        "multilayer3/grating-9",
        0.22,
        {"start": "texture"},
        id="multilayer3-grating",
    ),
    pytest.param(
        "textures20-biotac19-v2",
        "textures20-long/grating-3.0mm",
        0.5,
        {},
        id="biotac-grating",
        marks=pytest.mark.slow,
    ),
    pytest.param(
        "textures20-icub60-v2",
        "textures20-long/boxes-4.5mm",
        0.3,
        {},
        id="icub-boxes",
        marks=pytest.mark.slow,
    ),
]


@pytest.mark.parametrize(("task", "plate", "duration", "changes"), CASES)
def test_the_table_is_within_its_target_of_the_per_step_solve(
    task, plate, duration, changes, cache
):
    slide = task_slide(task, plate, duration, **changes)
    table, step = _both(slide, cache)
    assert "phase table" in table.meta["skin_problem"]
    assert np.abs(step.data).max() > 0  # the pad touched the texture
    assert _rel_l2(table.data, step.data) <= REL_L2_TARGET
    # the pad's path is the per-step slide's: MuJoCo steps the same servo either way
    assert np.array_equal(table.meta["x_pad_m"], step.meta["x_pad_m"])
    assert np.allclose(table.meta["normal_force_n"], step.meta["normal_force_n"], rtol=1e-6)


def test_a_flat_plate_is_one_phase_and_the_per_step_slide(cache):
    slide = task_slide("textures20-biotac19-v2", "textures20-long/flat", 0.3)
    table, step = _both(slide, cache)
    assert "1 phase" in table.meta["skin_problem"]
    assert np.allclose(table.data, step.data, rtol=FLAT_RTOL, atol=1e-9)
    assert table.meta["mean_drag_n"] == pytest.approx(step.meta["mean_drag_n"], rel=1e-9)


def test_auto_takes_the_table_where_the_window_lies_on_the_texture_and_says_so():
    on = task_slide("finger7-v1", "finger7/bumps-6x6", 0.25, start="texture")
    assert on.table_plan() is not None and on.describe()["path"] == "phase-table"
    # from flat ground, each slide its own table, over a plate-anchored lattice (cheap dense
    # steps): per step, and the description, hence the key, is the per-step slide's
    across = task_slide("finger7-v1", "finger7/bumps-4x4", 0.9)
    assert across.table_plan() is None and "path" not in across.describe()
    # from flat ground over ridges across the whole pad: the set's slides share the tables
    # (force levels), so they pay for the stretch on the texture even over cheap steps
    ridges = task_slide("finger7-v1", "finger7/ridges-4", 0.9)
    lo, hi = travel(ridges.window, ridges.drawn())
    plan = ridges.table_plan()
    assert plan is not None and not (plan.covers(lo) and plan.covers(hi))
    assert ridges.describe()["path"] == "phase-table"
    # a flat plate the pad is not wholly on at first: a uniform stretch, its table one solve
    flat = task_slide("textures20-icub60-v1", "textures20/flat", None)
    assert not flat.spectral and flat.table_plan().period_m is None
    # the same slides with a fixed force and no offset jitter share nothing: per step
    fixed = replace(ridges.protocol, force_jitter=0.0)
    assert replace(ridges, protocol=fixed).table_plan() is None
    assert replace(on, options=STEP).table_plan() is None
    assert "path" not in replace(on, options=STEP).describe()


def test_a_rough_profile_asked_for_by_name_is_read_off_a_table_along_it(cache):
    """A profile with no period that does not vary across the slide: one table of positions
    along the whole stretch, shared by the slides of a force level whatever their offset;
    within the target of the per-step solve (measured on the iCub's rough strips: 0.07-0.24%
    relative L2, perf/bench_every_plate.py --settings table). ``auto`` does not take it for
    a slide alone (it pays over many slides a plate)."""
    protocol = Protocol(duration_s=0.2, start="texture", force_jitter=0.1)
    slide = Slide(get_plate("roughness8/ra-50"), "grid3x3", protocol)
    assert slide.table_plan() is None and "path" not in slide.describe()
    plan = replace(slide, options=TABLE).table_plan()
    assert plan.span and plan.period_m is None and plan.y_m == 0.0
    table, step = _both(slide, cache)
    assert "position table" in table.meta["skin_problem"]
    assert "shared force levels" in table.meta["skin_problem"]
    assert np.abs(step.data).max() > 0
    assert _rel_l2(table.data, step.data) <= REL_L2_TARGET
    assert np.array_equal(table.meta["x_pad_m"], step.meta["x_pad_m"])
    # another offset reads the same tables: none is solved for it
    other = replace(slide, protocol=replace(protocol, offset_y_m=2e-3), options=TABLE)
    assert "(its tables reused)" in run(other, cache).recording.meta["skin_problem"]


def test_a_profile_crossed_from_flat_ground_is_tabulated_along_the_whole_plate(cache):
    """A slide that starts on flat ground and runs onto the profile: its table covers the
    whole plate (the flat base either side of the profile is the same at every offset too),
    so every step is read off it, within the target of the per-step solve, the pad's path
    the per-step slide's, to the plate's end, where the stroke stops on the step past its
    limit; a slide that stays on the profile keeps the profile's interior."""
    plate = get_plate("roughness8/ra-50")
    protocol = Protocol(duration_s=1.5, force_jitter=0.1)
    slide = replace(Slide(plate, "grid3x3", protocol), options=TABLE)
    plan = slide.table_plan()
    # every pad centre a window reaches: the pad at the plate's end, or its start
    pad = slide.pad.patch_m[0]
    reach = max(plate.length_m / 2 - pad / 2, plate.area_length_m / 2 + pad / 2 + START_MARGIN_M)
    reach += phase.REACH_MARGIN_M  # past the step that passes a stroke's limit
    assert plan.span and math.isclose(plan.x_hi, reach) and math.isclose(plan.x_lo, -reach)
    lo, hi = travel(slide.window, slide.drawn())
    assert lo < -plate.area_length_m / 2 < hi and plan.covers(lo) and plan.covers(hi)
    on = replace(slide, protocol=replace(protocol, start="texture"))
    rx = pad / 2 + phase.REACH_MARGIN_M
    assert math.isclose(on.table_plan().x_hi, plate.area_length_m / 2 - rx)
    table, step = _both(slide, cache)
    steps = slide.window.n_samples * slide.resolved.steps_per_sample + 1
    assert f"{steps} of {steps} steps read off it" in table.meta["skin_problem"]
    assert np.abs(step.data).max() > 0
    assert _rel_l2(table.data, step.data) <= REL_L2_TARGET
    assert np.array_equal(table.meta["x_pad_m"], step.meta["x_pad_m"])
    assert np.max(step.meta["x_pad_m"]) > slide.window.x_limit_m - 1e-3  # to the end


def test_ridges_across_the_pad_too_short_for_two_periods_are_tabulated_along_the_plate(cache):
    """Ridges across the whole pad that it never covers for two periods (finger7's ridges-2):
    no period's table serves, but the loads are a function of the position along the slide
    whatever the offset, so the same table of positions serves them, within the target of
    the per-step solve; bumps in rows, which vary across the slide, have none."""
    protocol = Protocol(duration_s=0.3, force_jitter=0.1)
    slide = Slide(get_plate("finger7/ridges-2"), "grid3x3", protocol, options=TABLE)
    plan = slide.table_plan()
    assert plan.span and plan.period_m is None and plan.y_m == 0.0
    assert "position by position" in plan.describe()
    table, step = _both(slide, cache)
    assert "position table" in table.meta["skin_problem"]
    assert np.abs(step.data).max() > 0
    assert _rel_l2(table.data, step.data) <= REL_L2_TARGET
    assert np.array_equal(table.meta["x_pad_m"], step.meta["x_pad_m"])
    bumps = get_plate("finger7/bumps-4x4")
    assert span_plan(bumps, slide.pad.patch_m, 0.0, "quasi-static") is None


def test_auto_takes_a_profiles_table_where_the_set_has_slides_enough_to_pay_for_it():
    """``auto`` takes a rough profile's table where the slides of its plate in the set
    (``plate_slides``) take more solves step by step than its tables' estimated positions at
    every force level they read; a slide alone stays per step. The description records the
    path, so the two are two cache entries. (The BioTac's impedance reports the load; a
    piezoelectric sensor, which reports its vibration, is solved at every step:
    tests/test_sim_auto_path.py.)"""
    protocol = Protocol(force_jitter=0.25)
    alone = Slide(get_plate("roughness8/ra-50"), "biotac19", protocol)
    assert alone.table_plan() is None and "path" not in alone.describe()
    many = replace(alone, plate_slides=60)
    plan = many.table_plan()
    assert plan is not None and plan.span and many.describe()["path"] == "phase-table"
    assert many.describe()["press"] == "held" and alone.describe() != many.describe()
    # the threshold: the estimate's solves against the slides' own, both ways of it
    few = [n for n in range(2, 61) if replace(alone, plate_slides=n).table_plan() is None]
    assert few and max(few) < 60
    n = max(few) + 1
    # counted on the set's nominal slide: slides of other draws decide alike
    for seed in range(1, 6):
        assert replace(many, seed=seed, plate_slides=n).table_plan() is not None
        assert replace(many, seed=seed, plate_slides=n - 1).table_plan() is None
    fid = alone.resolved
    steps = alone.window.n_samples * fid.steps_per_sample
    args = (plan, alone.plate, alone.pad.patch_m, protocol, fid.pitch_m, steps)
    assert span.span_pays(*args, n, False) and not span.span_pays(*args, n - 1, False)
    assert span.span_pays(*args, n - 1, True)  # a spectral skin's positions cost less
    # one level where the force does not vary, more the wider it varies
    assert span.levels_read(replace(protocol, force_jitter=0.0)) == 1
    assert span.levels_read(replace(protocol, force_jitter=0.1)) < span.levels_read(protocol)
    with pytest.raises(ConfigError, match=r"plate_slides = 0 is out of range; valid: \[1, inf\]"):
        replace(alone, plate_slides=0)


def test_a_position_table_reads_the_line_between_positions_and_holds_its_ends():
    """Positions along a stretch do not wrap round (a period's phases do); past an end the
    end's row is read; the plan's kind survives the cache's arrays."""
    plan = PhasePlan(None, -5e-3, 5e-3, -5e-3, 0.0, span=True)
    phases = np.array([0.0, 1e-3, 3e-3, 10e-3])
    loads = np.array([[0.0, 1.0], [1.0, 1.0], [3.0, 0.0], [10.0, 2.0]])
    ones = np.ones(4)
    table = PhaseTable(plan, phases, loads, ones, ones, ones, 4, 0.0)
    got, *_ = table.at(np.array([-5e-3, -3e-3, 4.5e-3, 5e-3, 9e-3, -9e-3]))
    want = np.array([[0.0, 1.0], [2.0, 0.5], [9.5, 1.857142857142857], [10.0, 2.0]])
    np.testing.assert_allclose(got[:4], want, rtol=1e-12)
    np.testing.assert_array_equal(got[4], loads[-1])  # past the far end: its row
    np.testing.assert_array_equal(got[5], loads[0])
    back = _from_arrays(_to_arrays(table))
    assert back.plan == plan and "position table" in back.describe()
    assert span_plan(get_plate("finger7/bumps-4x4"), (0.016, 0.016), 0.0, "quasi-static") is None


@pytest.mark.parametrize(
    ("plate", "sensor", "proto", "why"),
    [
        # a profile is tabulated along it where it does not vary across the pad's reach;
        # here the reach runs off the profile's side
        ("roughness8/ra-12.5", "grid3x3", {"offset_y_m": 0.01}, "no period along the slide"),
        ("finger7/ridges-4", "grid3x3", {"force_control": "position"}, "not quasi-statically"),
        # boxes in rows vary across the slide: no table along it; the iCub's pad is never
        # wholly on two periods of textures20-v1's 36 mm texture
        ("textures20/boxes-4.5mm", "icub60", {}, "under 2 periods"),
    ],
)
def test_asking_for_the_table_where_the_scene_has_none_is_one_clear_error(
    plate, sensor, proto, why
):
    slide = Slide(get_plate(plate), sensor, Protocol(**proto), options=TABLE)
    with pytest.raises(ConfigError, match=f"path = 'phase-table' does not serve.*{why}"):
        slide.table_plan()


def test_a_table_is_the_same_whichever_slide_asks_first_and_wherever_it_comes_from(tmp_path):
    """Two slides of one plate at other speeds and offsets share the tables of their force
    levels (ridges across the whole pad: the offset does not matter); the tables are solved
    in a scene of their own, so the second slide reads the first one's tables, and a fresh
    process solving them again, or reading them from disk, gives the same bits."""
    base = task_slide("finger7-v1", "finger7/ridges-8", 0.2, start="texture")
    a = replace(base, seed=11, options=TABLE)
    b = replace(base, seed=12, options=TABLE)
    assert a.drawn().speed_m_s != b.drawn().speed_m_s
    cache = ArtefactCache(tmp_path / "c")
    forget_process_memos()
    first = run(a, cache).recording
    again_b = run(b, cache).recording
    assert "its tables reused" in again_b.meta["skin_problem"] or "0 of" in str(
        again_b.meta["skin_problem"]
    )
    entries = sorted((tmp_path / "c").rglob(f"*.{TABLE_EXT}"))
    assert entries, "the tables were not kept in the cache"
    forget_process_memos()  # a new worker: read from disk
    from_disk = run(a, cache).recording
    assert np.array_equal(from_disk.data, first.data)
    forget_process_memos()  # solved afresh, nothing kept
    fresh = run(a, ArtefactCache(tmp_path / "other")).recording
    assert np.array_equal(fresh.data, first.data)


def test_a_damaged_table_in_the_cache_is_solved_again_with_a_warning(tmp_path):
    slide = replace(
        task_slide("finger7-v1", "finger7/ridges-8", 0.2, start="texture"), options=TABLE
    )
    cache = ArtefactCache(tmp_path)
    forget_process_memos()
    good = run(slide, cache).recording
    for entry in tmp_path.rglob(f"*.{TABLE_EXT}"):
        data = bytearray(entry.read_bytes())
        data[len(data) // 2] ^= 0xFF
        entry.write_bytes(bytes(data))
    forget_process_memos()
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        again = run(slide, cache).recording
    assert any(issubclass(w.category, CacheWarning) for w in seen)
    assert np.array_equal(again.data, good.data)


def test_force_levels_bracket_the_force_on_a_fixed_grid():
    for f in (0.37, 1.0, 1.2345, 4.9):
        levels = force_levels(f)
        assert math.isclose(sum(w for _, w in levels), 1.0)
        assert math.isclose(sum(F * w for F, w in levels), f, rel_tol=1e-12)
        assert all(F > 0 for F, _ in levels)
        if len(levels) == 2:
            (lo, _), (hi, _) = levels
            assert lo < f < hi and hi / lo == pytest.approx(2 ** (1 / LEVELS_PER_OCTAVE))
    assert force_levels(1.0) == [(1.0, 1.0)]
    assert force_levels(0.5) == [(0.5, 1.0)]


def test_the_plan_checks_the_repetition_on_the_plates_own_features():
    plate = get_plate("textures20-long/grating-3.0mm")
    plan, why = phase_plan(plate, (0.032, 0.022), 0.0, "quasi-static")
    assert plan is not None and plan.period_m == pytest.approx(3e-3) and why == ""
    assert plan.y_m == 0.0  # ridges across the whole pad: every offset shares the table
    bumps, _ = phase_plan(
        get_plate("textures20-long/boxes-3.0mm"), (0.032, 0.022), 1e-3, "quasi-static"
    )
    assert bumps is not None and bumps.y_m == 1e-3  # a grid of bumps: the offset's own
    # a plate whose features do not repeat: one ridge moved
    from sim_tactile.plates import surface_of

    feats = list(surface_of(plate).features)
    feats[len(feats) // 2] = replace(feats[len(feats) // 2], x=feats[len(feats) // 2].x + 1e-4)
    from sim_tactile.sim.plan import phase

    a, b = phase._repeating_span(feats, surface_of(plate).period_m)
    assert a >= b  # no span repeats


def test_auto_presses_once_to_the_equilibrium_the_per_step_press_reaches(cache):
    """Under a held force, ``auto`` presses the pad once to its equilibrium (the held step
    at the force, taken again until its height holds) where the per-step reference
    approaches, ramps and settles over some 150-300 held steps; the slide is the same: the
    dense skin's equilibrium is unique, and here the recordings are equal bit for bit. The
    description says so (another key)."""
    slide = task_slide("finger7-v1", "finger7/ridges-4", 0.4)
    assert slide.held_press and slide.describe()["press"] == "held"
    step = replace(slide, options=STEP)
    assert not step.held_press and "press" not in step.describe()
    a, b = run(slide, cache).recording, run(step, cache).recording
    assert np.abs(b.data).max() > 0
    np.testing.assert_allclose(a.data, b.data, rtol=1e-9, atol=1e-12)
    assert np.array_equal(a.meta["x_pad_m"], b.meta["x_pad_m"])
