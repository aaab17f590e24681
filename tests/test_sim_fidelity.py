"""``fidelity="auto"``: what it picks for a scene."""

from __future__ import annotations

import math

import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.plates import Bumps, Plate, get_plate
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import Finger, get_sensor
from sim_tactile.sim.plan.fidelity import (
    AUTO_OMEGA_DT,
    DT_MAX_S,
    MAX_NODES,
    MAX_OMEGA_DT,
    STEPS_PER_FEATURE,
    choose_fidelity,
    flat_stiffness,
)
from sim_tactile.sim.plan.protocol import Protocol


def _auto(
    plate: str, sensor: str = "grid3x3", finger: Finger | None = None, level="auto", refine=True
):
    sen = get_sensor(sensor)
    f = finger or sen.finger
    return choose_fidelity(get_plate(plate), sen.layout, f, Protocol(), level, refine=refine), f


def test_ridges_under_a_flat_pad_get_nodes_along_the_slide():
    fid, finger = _auto("finger7/ridges-4", refine=False)
    # 2.5 mm ridges: x at a tenth of them (the node cap leaves room); y as coarse as the
    # 2 mm taxels (the grid that resolves them; measured 13.5% from the physics, auto refines
    # it to 0.125 x 1 mm, tests/test_sim_measured_errors.py)
    assert fid.pitch_m == pytest.approx(0.25e-3)
    assert fid.pitch_y_m == pytest.approx(2e-3)
    assert "0.25 x 2 mm" in fid.reason
    ref, _ = _auto("finger7/ridges-4", level="L2")
    assert (ref.pitch_m, ref.pitch_y_m) == pytest.approx((0.125e-3, 1e-3))
    assert skin_grid(finger, fid.pitch_m, fid.pitch_y_m).n <= MAX_NODES["L1"]


@pytest.mark.parametrize("plate", ["finger7/bumps-4x4", "finger7/flat"])
def test_two_dimensional_textures_keep_square_nodes(plate):
    # the grid that resolves them (bumps-4x4's is far from the physics, and auto takes the
    # lattice anchored to its walls, tests/test_sim_anchored.py)
    fid, _ = _auto(plate, refine=False)
    assert fid.pitch_y_m is None


def test_a_curved_pad_keeps_square_nodes_over_ridges():
    fid, _ = _auto(
        "finger7/ridges-4", finger=Finger(shape="sphere", radius_m=0.01, size_m=(0.012, 0.012))
    )
    assert fid.pitch_y_m is None


def test_auto_steps_let_every_feature_take_twenty_steps():
    """2.5 mm ridges at 60 mm/s: a feature takes >= STEPS_PER_FEATURE steps; the step is a
    whole fraction of the 10 ms sample, and the one simulate() takes."""
    fid, _ = _auto("finger7/ridges-4")
    speed, scale = 0.06, 2.5e-3
    assert scale / (speed * fid.dt_s) >= STEPS_PER_FEATURE
    assert fid.dt_s <= DT_MAX_S
    assert fid.dt_s == 1.0 / (100.0 * fid.steps_per_sample) == 1.0 / (100.0 * 5)
    fast = choose_fidelity(
        get_plate("finger7/ridges-4"),
        get_sensor("grid3x3").layout,
        Finger(),
        Protocol(speed_m_s=0.2),
        "auto",
    )
    assert scale / (0.2 * fast.dt_s) >= STEPS_PER_FEATURE > scale / (0.2 * fast.dt_s) / 2


def test_the_dynamic_loop_keeps_its_coupling_stable():
    """Under the dynamic force loop auto keeps omega * dt at AUTO_OMEGA_DT on a flat plate
    (the stiffest contact the bone meets); quasi-static control has no such limit."""
    sen = get_sensor("grid3x3")
    plate = get_plate("finger7/flat")
    dyn = choose_fidelity(plate, sen.layout, sen.finger, Protocol(force_control="dynamic"), "L1")
    qs = choose_fidelity(plate, sen.layout, sen.finger, Protocol(), "L1")
    k = flat_stiffness(sen.finger, True, dyn.winkler_k_pa_per_m)
    omega = math.sqrt(k / sen.finger.bone_mass_kg)
    assert omega * dyn.dt_s <= AUTO_OMEGA_DT < MAX_OMEGA_DT
    assert qs.dt_s > dyn.dt_s and qs.dt_s == pytest.approx(DT_MAX_S)


def test_the_node_count_is_capped_and_says_so():
    """0.3 mm bumps want 0.12 mm nodes; on the 16 mm pad that is over MAX_NODES: the pitch
    is raised to the floor, with a warning that the smaller features are smeared."""
    plate = Plate(
        Bumps(rows=30, cols=30, shape="box", size_m=0.3e-3, height_m=0.3e-3, spacing_m=1.2e-3)
    )
    sen = get_sensor("multilayer3x3x2")
    fid = choose_fidelity(plate, sen.layout, sen.finger, Protocol(), "auto")
    assert skin_grid(sen.finger, fid.pitch_m, fid.pitch_y_m).n <= MAX_NODES["L1"] * 1.05
    assert any("node pitch raised" in w for w in fid.warnings)
    assert any("smeared" in w for w in fid.warnings)


@pytest.mark.parametrize(
    ("plate", "sensor", "kw", "words", "remedy"),
    [
        (
            "multilayer3/grating-9",
            "multilayer3x3x2",
            {},
            "aliases the texture",
            "taxels at most 2 mm apart would sample it",
        ),
        (
            "textures20/grating-1.5mm",
            "icub60",
            {},
            "larger than the texture period",
            "taxels smaller than 1.5 mm",
        ),
        ("roughness8/ra-50", "pvdf2", {}, "micro-roughness", "nothing to change"),
        (
            "finger7/ridges-4",
            "grid3x3",
            {"dt_s": 0.01},
            "time step 0.01 s is too coarse",
            "pass dt_s at most",
        ),
        (
            "finger7/ridges-4",
            "grid3x3",
            {"pitch_m": 2e-3},
            "node pitch 2 mm is too coarse",
            "pass pitch_m at most 1.25 mm",
        ),
    ],
)
def test_each_warning_names_its_remedy(plate, sensor, kw, words, remedy):
    sen = get_sensor(sensor)
    fid = choose_fidelity(get_plate(plate), sen.layout, sen.finger, Protocol(), "auto", **kw)
    said = [w for w in fid.warnings if words in w]
    assert said, fid.warnings
    assert remedy in said[0], said[0]


def test_a_raised_node_pitch_names_its_remedy_and_only_where_it_was_raised():
    """The BioTac on a 2 mm grating: its features ask for 0.4 mm nodes, L1's node cap raises
    them to 0.709 mm, and the warning says how to get finer ones. L2 halves that pitch
    (0.354 mm, finer than asked): nothing was raised, and nothing is said; nor where the
    caller forces a pitch."""
    plate, sen = get_plate("textures20/grating-2.0mm"), get_sensor("biotac19")
    l1 = choose_fidelity(plate, sen.layout, sen.finger, Protocol(), "auto")
    raised = [w for w in l1.warnings if "node pitch raised" in w]
    assert raised and f"to {l1.pitch_m * 1e3:.3g} mm" in raised[0]
    assert "fidelity L2" in raised[0] and "pitch_m" in raised[0]
    l2 = choose_fidelity(plate, sen.layout, sen.finger, Protocol(), "L2")
    assert l2.pitch_m < 0.4e-3
    assert not any("node pitch raised" in w for w in l2.warnings), l2.warnings
    forced = choose_fidelity(plate, sen.layout, sen.finger, Protocol(), "L1", pitch_m=0.3e-3)
    assert not any("node pitch raised" in w for w in forced.warnings)


def test_levels_and_bad_input():
    l0, _ = _auto("finger7/ridges-4", level="L0")
    l1, _ = _auto("finger7/ridges-4", level="L1")
    assert (l0.level, l0.coupled, l1.coupled) == ("L0", False, True)
    assert (l0.pitch_m, l0.dt_s) == (l1.pitch_m, l1.dt_s)
    with pytest.raises(ConfigError, match="fidelity = 'L3' is not valid; valid: auto, L0"):
        _auto("finger7/ridges-4", level="L3")


@pytest.mark.parametrize(
    "sensor, dt_s, warned",
    [
        ("pvdf2", None, True),  # 1 step a 1 ms sample: the vibration under-resolved
        ("pvdf2", 1.25e-4, False),  # 8 steps a sample: resolved to a few percent
        ("icub60", None, False),  # a capacitive sensor reports the load itself
    ],
)
def test_a_piezoelectric_sensor_on_a_rough_plate_is_warned_of_its_step(sensor, dt_s, warned):
    from sim_tactile.sim import Slide

    slide = Slide(plate=get_plate("roughness8/ra-6.3"), sensor=sensor, seed=0, dt_s=dt_s)
    got = [w for w in slide.resolved.warnings if "piezoelectric" in w]
    assert bool(got) == warned
    if warned:
        assert slide.resolved.steps_per_sample == 1
        assert "dt_s at most 0.000125 s" in got[0]  # the remedy, with its value


def test_no_vibration_warning_on_a_plate_without_roughness():
    from sim_tactile.sim import Slide

    slide = Slide(plate=get_plate("finger7/ridges-4"), sensor="pvdf2", seed=0)
    assert not [w for w in slide.resolved.warnings if "piezoelectric" in w]
