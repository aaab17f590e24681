"""A held slide's steps in one compiled call (sim.step.held_run): the records of the Python
loops over the runner (``_slide``, ``_slide_sampled``) bit for bit, its samples' means those of
the step-by-step averager bit for bit, the Python loop where the press joint moves under the
dynamics alone, and the per-step slide's errors."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from _scenes import ridges_on_shared_tables

from sim_tactile.cache import ArtefactCache
from sim_tactile.errors import PhysicsError
from sim_tactile.plates import get_plate
from sim_tactile.sim import Protocol, Slide, StepOptions, prepare, run
from sim_tactile.sim.slide import _slide, _slide_sampled
from sim_tactile.sim.step import tabled
from sim_tactile.sim.step.held_run import held_slide
from sim_tactile.sim.step.sampling import SampleAverager, sample_means

PROTO = Protocol(speed_m_s=0.06, force_n=1.0, duration_s=0.25, rate_hz=100.0, offset_jitter_m=5e-4)
PER_STEP = StepOptions(path="per-step")

CASES = [
    # L0's Winkler bed on a grid of bumps, the full problem
    ("finger7/bumps-4x4", "grid3x3", "L0", 1, PROTO),
    # a coupled skin in columns, mirror-halved, over ridges crossed from flat ground
    ("finger7/ridges-4", "grid3x3", "L1", 1, PROTO),
    # the multilayer's dense full problem at every 2nd step, sliding both ways
    (
        "multilayer3/hemispheres-6x6",
        "multilayer3x3x2",
        "auto",
        2,
        Protocol(
            speed_m_s=0.065,
            force_n=5.0,
            duration_s=0.3,
            start="texture",
            passes=2,
            return_stroke=True,
        ),
    ),
    # every 3rd step: the last solve closes a stretch shorter than the rest
    ("finger7/bumps-4x4", "grid3x3", "L1", 3, PROTO),
]


def _pair(plate, sensor, fid, proto, seed=3):
    slide = Slide(get_plate(plate), sensor, proto, seed, fid, options=PER_STEP)
    return prepare(slide), prepare(slide)


@pytest.mark.parametrize("plate,sensor,fid,every,proto", CASES)
def test_the_compiled_slide_is_the_python_loop_bit_for_bit(plate, sensor, fid, every, proto):
    a, b = _pair(plate, sensor, fid, proto)
    n_sub = a.fidelity.steps_per_sample
    if every == 1:
        ref = _slide(a.runner, a.window, a.protocol, n_sub)
    else:
        ref = _slide_sampled(a.runner, a.window, a.protocol, n_sub, every)
    got = held_slide(b.runner, b.window, b.protocol, n_sub, every)
    assert got is not None, "the compiled loop refused a held slide"
    loads, forces, x_pad, stopped, _ = got
    assert loads.tobytes() == ref.loads.tobytes()
    assert forces.tobytes() == ref.forces.tobytes()
    assert x_pad.tobytes() == ref.x_pad.tobytes()
    assert stopped == ref.stopped_at_s
    assert (
        b.runner.drag_sum == a.runner.drag_sum and b.runner.n_slide_steps == a.runner.n_slide_steps
    )
    assert a.runner.n_slide_steps > 0 and np.ptp(ref.loads) > 0  # it slid, and felt something
    assert b.runner.z_m == a.runner.z_m  # the pad left where the last held step put it


def test_a_slide_that_stops_at_the_plate_end_stops_alike():
    fast = Protocol(speed_m_s=0.12, force_n=1.0, duration_s=0.8, rate_hz=100.0)
    a, b = _pair("finger7/ridges-4", "grid3x3", "L0", fast)
    n_sub = a.fidelity.steps_per_sample
    ref = _slide(a.runner, a.window, a.protocol, n_sub)
    loads, _, x_pad, stopped, _ = held_slide(b.runner, b.window, b.protocol, n_sub, 1)
    assert ref.stopped_at_s is not None and stopped == ref.stopped_at_s
    assert loads.tobytes() == ref.loads.tobytes() and x_pad.tobytes() == ref.x_pad.tobytes()


@pytest.mark.parametrize("n_sub", [1, 3, 10, 17])
def test_sample_means_are_the_averagers_bit_for_bit(n_sub):
    rng = np.random.default_rng(n_sub)
    n, m = 7, 5
    loads = rng.standard_normal((n * n_sub + 1, m)) * 10.0 ** rng.integers(-6, 3, size=(1, m))
    forces = rng.random(n * n_sub + 1)
    avg = SampleAverager(n, m, n_sub)
    for i in range(n * n_sub):
        s, k = divmod(i, n_sub)
        avg.add(s, k, loads[i], forces[i])
        if k == n_sub - 1:
            avg.end_sample()
    avg.finish(loads[-1], forces[-1])
    got_l, got_f = sample_means(loads, forces, n, n_sub)
    assert got_l.tobytes() == avg.loads.tobytes()
    assert got_f.tobytes() == avg.forces.tobytes()


def test_a_press_joint_that_moves_alone_leaves_the_slide_to_the_python_loop():
    """The compiled slide refuses, and leaves the runner as it found it (its path was
    glided on the runner's own MuJoCo state, then put back): the Python loop then gives what
    it gives from an untouched twin, bit for bit."""
    p, q = _pair("finger7/bumps-4x4", "grid3x3", "L0", PROTO)
    for x in (p, q):
        m = copy.copy(x.runner._m_dyn)
        m.jnt_stiffness[x.runner._jz] = 50.0  # a spring on the press joint: it moves
        x.runner._m_dyn = m
    r, n_sub = p.runner, p.fidelity.steps_per_sample
    before = r.d_dyn.qpos.copy(), r.d_dyn.qvel.copy(), r.d_dyn.time
    assert held_slide(r, p.window, p.protocol, n_sub, 1) is None
    assert r.d_dyn.qpos.tobytes() == before[0].tobytes() and r.d_dyn.time == before[2]
    assert r.d_dyn.qvel.tobytes() == before[1].tobytes()
    got = _slide(r, p.window, p.protocol, n_sub)
    ref = _slide(q.runner, q.window, q.protocol, n_sub)
    assert got.loads.tobytes() == ref.loads.tobytes() and np.ptp(ref.loads) > 0
    assert got.forces.tobytes() == ref.forces.tobytes()
    assert got.x_pad.tobytes() == ref.x_pad.tobytes()


def test_a_skin_pressed_to_the_bottom_fails_as_the_per_step_slide_does():
    """The skin's limit set just below what the bumps press it to once the pad slides onto
    them from flat ground: both loops stop at the same step, with the same message."""
    msgs = []
    for compiled in (False, True):
        p = prepare(Slide(get_plate("finger7/bumps-4x4"), "grid3x3", PROTO, 1, "L0"))
        p.runner.max_pen_allowed = 1.5 * float(p.runner.hold.pen.max())  # pressed on flat
        n_sub = p.fidelity.steps_per_sample
        with pytest.raises(PhysicsError) as exc:
            if compiled:
                held_slide(p.runner, p.window, p.protocol, n_sub, 1)
            else:
                _slide(p.runner, p.window, p.protocol, n_sub)
        msgs.append(str(exc.value))
    assert msgs[0] == msgs[1] and "pressed to the bottom" in msgs[0], msgs


TABLED = [
    # shared tables by force level, crossed from flat ground: the runner's stretches off them
    ridges_on_shared_tables(),
    # a uniform stretch: every step read off its one phase, the path glided
    Slide(
        get_plate("multilayer3/flat"),
        "multilayer3x3x2",
        Protocol(speed_m_s=0.065, force_n=5.0, duration_s=0.3),
        7,
        ideal=True,
    ),
]


@pytest.mark.parametrize("slide", TABLED, ids=["ridges-off-and-on", "flat-glided"])
def test_a_tabled_slide_records_what_its_step_by_step_loop_records(slide, monkeypatch, tmp_path):
    cache = ArtefactCache(tmp_path)
    fast = run(slide, cache).recording
    monkeypatch.setattr(tabled, "glide", lambda *a, **k: None)  # the loop step by step
    monkeypatch.setattr(tabled, "glide_runner", lambda *a, **k: None)
    slow = run(slide, cache).recording
    steps = [r.meta["skin_problem"].split("; ")[-1] for r in (fast, slow)]  # steps off it
    assert steps[0] == steps[1], steps
    assert "phase table" in fast.meta["skin_problem"]
    assert fast.data.tobytes() == slow.data.tobytes()
    for key in ("x_pad_m", "normal_force_n", "mean_drag_n"):
        assert fast.meta[key] == slow.meta[key], key


def test_a_glided_slide_takes_its_scenes_own_dynamics_model(tmp_path):
    """The dynamics model alone (``dynamics_for``) is the scene's, byte for byte."""
    import mujoco

    from sim_tactile.sim.step.build import dynamics_for, scene_for

    cache = ArtefactCache(tmp_path)
    slide = TABLED[1]
    proto, fid, x0 = slide.drawn(), slide.resolved, slide.window.x_start_m
    scene, _ = scene_for(slide, proto, fid, x0, cache)
    m, jx, jz = dynamics_for(slide, proto, fid, x0, cache)

    def saved(model) -> bytes:
        buf = np.empty(mujoco.mj_sizeModel(model), dtype=np.uint8)
        mujoco.mj_saveModel(model, None, buf)
        return buf.tobytes()

    assert (jx, jz) == (scene.jx, scene.jz)
    assert saved(m) == saved(scene.m_dyn)


def test_the_glide_puts_back_the_runners_integration_state_and_warning_counters():
    """What the glide on a runner's own state keeps (held_run._kept) is put back whole: its
    integration state and every warning counter, number and last info."""
    import mujoco

    from sim_tactile.sim.step import held_run

    m = mujoco.MjModel.from_xml_string(
        "<mujoco><worldbody><body><joint type='slide'/><geom size='.1'/></body></worldbody>"
        "</mujoco>"
    )
    d = mujoco.MjData(m)
    d.qpos[0], d.qvel[0] = 0.25, -1.5
    d.warning.number[:] = np.arange(len(d.warning.number)) % 3
    d.warning.lastinfo[:] = 7 * np.arange(len(d.warning.lastinfo))
    want = (d.qpos.copy(), d.qvel.copy(), d.warning.number.copy(), d.warning.lastinfo.copy())
    kept = held_run._kept(m, d)
    for _ in range(5):
        mujoco.mj_step(m, d)
    d.warning.number[1] += 4
    d.warning.lastinfo[2] = 99
    assert d.qpos[0] != want[0][0]
    held_run._restore(m, d, kept)
    got = (d.qpos, d.qvel, d.warning.number, d.warning.lastinfo)
    for a, b in zip(got, want, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    "plate, sensor, fidelity",
    [("finger7/bumps-4x4", "grid3x3", "L0"), ("roughness8/ra-50", "pvdf2", "auto")],
)
def test_slides_of_one_scene_share_their_held_steps_reduced_probes(
    plate, sensor, fidelity, monkeypatch, tmp_path
):
    """The held step's reduced probes (their broad phase, their grouping by column) are
    computed from the collider's nodes and the plate alone, so the slides of one scene share
    them (``kept``: the primitive collider of a kept scene model, a rough plate's surface
    and the nodes); each slide is the same bit for bit as with its probes computed
    afresh."""
    from sim_tactile.sim.collide.height import SurfaceCollider
    from sim_tactile.sim.collide.primitive import PrimitiveCollider
    from sim_tactile.sim.step import build

    proto = Protocol(duration_s=0.2, offset_jitter_m=0.5e-3, force_jitter=0.1)
    slides = [
        Slide(get_plate(plate), sensor, proto, seed, fidelity=fidelity, ideal=True)
        for seed in (3, 4)
    ]
    holds = []
    made = build.make_held_step

    def keep(*args, **kwargs):
        holds.append(made(*args, **kwargs))
        return holds[-1]

    monkeypatch.setattr(build, "make_held_step", keep)
    cache = ArtefactCache(tmp_path)
    shared = [run(s, cache).recording.data for s in slides]
    a, b = holds[-2:]
    assert a.probes is b.probes and a.group is b.group
    for kind in (PrimitiveCollider, SurfaceCollider):
        monkeypatch.setattr(kind, "kept", lambda self, key, make: make())
    holds.clear()
    fresh = [run(s, cache).recording.data for s in slides]
    assert holds[-2].probes is not holds[-1].probes
    for x, y in zip(shared, fresh, strict=True):
        assert x.tobytes() == y.tobytes()
