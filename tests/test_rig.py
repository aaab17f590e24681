"""The probe rig (multilayer3-v2): the pass, the stationary contact against closed forms and
the library's own weights, the carriage in MuJoCo, directions, determinism and bad input."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.plates import get_plate
from sim_tactile.scene.layered import layered_subsurface_weights
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.plan.protocol import SPEED_RAMP_S, Protocol
from sim_tactile.sim.plan.rig import ProbePass, ProbeRig
from sim_tactile.sim.rig_sim import (
    _read_lines,
    probe_contact,
    probe_grid,
    reading_lines,
    simulate_rig,
)
from sim_tactile.slides import SlideSet
from sim_tactile.tasks import get_task

SENSOR = get_sensor("multilayer3x3x2")
SKIN = SENSOR.with_paper_stack().finger
PROTO = Protocol(speed_m_s=0.065, force_n=5.0, duration_s=5.0)
#: The interior of a wide rigid flat probe on a thin bonded stack is in uniaxial strain, so
#: the stress there is approach / sum(h_i / M_i), M the layers' constrained moduli. The
#: face (36 mm) is 14 stack thicknesses wide; the centre element's edges lie 2.8 thicknesses
#: from the face's: measured 0.3-0.4% from the closed form at 0.25 mm nodes.
THIN_LAYER_TOL = 0.01
#: The reading lines (FFT convolution, linear between quarter-pitch positions) against the
#: library's weights evaluated directly at off-lattice positions, in parts of the peak
#: reading: measured 0.04% at 0.25 mm nodes, 0.15% at 0.5 mm.
LINES_TOL = 0.005
#: A grating's pulse period against spacing / speed over the cruise (the speed drawn
#: without jitter here; the carriage's lag is micrometres).
PERIOD_TOL = 0.02


def _constrained_compliance(stack) -> float:
    """sum(h / M) [m/Pa] of the stack's layers, M = E (1 - nu) / ((1 + nu)(1 - 2 nu))."""
    return sum(
        la.thickness_m * (1 + la.poisson) * (1 - 2 * la.poisson) / (la.young_pa * (1 - la.poisson))
        for la in stack.layers
    )


def test_pass_position_integrates_its_speed_and_sits_in_the_middle():
    rig = ProbeRig()
    pas = ProbePass.of(rig, 0.036, 6.5e-3, 2.5e-3, 0.065, 5.0, -1.0)
    assert pas.x_from_m > 0 > pas.x_to_m and pas.sign == -1.0
    half = 6.5e-3 + 0.018 + 2e-3 + 2 * 2.5e-3
    assert pas.x_from_m == pytest.approx(half)
    t = np.linspace(0.0, 5.0, 200_001)
    v = pas.speed(t)
    x = pas.x_from_m + np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    np.testing.assert_allclose(x, pas.position(t), atol=1e-8)
    assert pas.position(5.0) == pytest.approx(pas.x_to_m, abs=1e-12)
    moving = np.flatnonzero(np.abs(v) > 0)
    before, after = t[moving[0]], 5.0 - t[moving[-1]]
    assert before == pytest.approx(after, abs=1e-4)
    assert pas.moving_s == pytest.approx(2 * half / 0.065 + SPEED_RAMP_S)
    assert np.max(np.abs(v)) == pytest.approx(0.065)


def test_bad_rig_input_names_the_parameter():
    with pytest.raises(ConfigError, match="rig node_pitch_m"):
        ProbeRig(node_pitch_m=1e-6)
    with pytest.raises(ConfigError, match="rig direction"):
        ProbeRig(direction="up")
    with pytest.raises(ConfigError, match=r"rig: unknown key\(s\) pitch; valid: node_pitch_m"):
        ProbeRig.from_json({"pitch": 1})
    with pytest.raises(ConfigError, match="duration_s >= "):
        ProbePass.of(ProbeRig(), 0.036, 6.5e-3, 2.5e-3, 0.065, 0.5, 1.0)
    with pytest.raises(ConfigError, match="does not tile"):
        probe_grid(get_plate("multilayer3/flat"), 0.7e-3)
    flat = "multilayer3/flat"
    with pytest.raises(ConfigError, match="force_control"):
        simulate_rig(flat, SENSOR, rig=ProbeRig(), protocol=replace(PROTO, force_control="dynamic"))
    with pytest.raises(ConfigError, match="duration_s"):
        simulate_rig(flat, SENSOR, rig=ProbeRig(), protocol=replace(PROTO, duration_s=None))
    with pytest.raises(ConfigError, match="micro-roughness"):
        simulate_rig("roughness8/ra-50", SENSOR, rig=ProbeRig(), protocol=PROTO)
    with pytest.raises(ConfigError, match="protocol.duration_s"):
        SlideSet(
            plates=(flat, "multilayer3/grating-9"),
            sensor="multilayer3x3x2",
            protocol=Protocol(),
            slides=2,
            quick_slides=2,
            rig=ProbeRig(),
        )


def test_flat_probe_interior_is_the_thin_layer_limit():
    """A flat probe's centre on the paper stack: the elements read the constrained-modulus
    stress of the solver's own approach (an independent closed form), and the face carries
    the force."""
    plate = get_plate("multilayer3/flat")
    grid = probe_grid(plate, 0.25e-3)
    p, approach, _ = probe_contact(plate, SKIN, grid, 5.0)
    assert p.sum() * grid.area_m2 == pytest.approx(5.0, rel=1e-9)
    assert (p > 0).all()  # a flat face touches everywhere
    sigma = approach / _constrained_compliance(SKIN.stack)
    lay = SENSOR.layout
    u, R = reading_lines(
        grid, p * grid.area_m2, SKIN, lay.sizes, lay.depth_m, lay.positions[:, 1], 0.03
    )
    centre = [m for m in range(lay.n) if np.allclose(lay.positions[m, :2], 0.0)]
    assert len(centre) == 2  # one per layer
    at0 = np.interp(0.0, u, R[centre[0]]), np.interp(0.0, u, R[centre[1]])
    for m, r in zip(centre, at0, strict=True):
        assert r / lay.sizes[m].prod() == pytest.approx(sigma, rel=THIN_LAYER_TOL)
    # 10 mm past the face's edge the element reads almost nothing (measured 0.13%)
    assert abs(np.interp(0.03, u, R[centre[1]])) < 5e-3 * max(at0)


def test_reading_lines_equal_the_library_weights_off_the_lattice():
    plate = get_plate("multilayer3/grating-9")
    grid = probe_grid(plate, 0.25e-3)
    p, _, _ = probe_contact(plate, SKIN, grid, 5.0)
    loads = p * grid.area_m2
    lay = SENSOR.layout
    pick = [4, 13]  # the centre element of each layer
    y = 0.3e-3
    u, R = reading_lines(grid, loads, SKIN, lay.sizes[pick], lay.depth_m[pick], np.full(2, y), 0.03)
    xs = np.array([0.0123e-3, 1.037e-3, 5.55e-3, 17.9e-3, -3.3e-3, 20.1e-3])
    for j, m in enumerate(pick):
        W = layered_subsurface_weights(
            grid.xy,
            grid.pitch_m,
            np.column_stack([xs, np.full(len(xs), y)]),
            np.tile(lay.sizes[m], (len(xs), 1)),
            np.full(len(xs), lay.depth_m[m]),
            SKIN.stack,
        )
        err = np.abs(W @ loads - np.interp(xs, u, R[j])).max()
        assert err < LINES_TOL * np.abs(R[j]).max(), (m, err)


@pytest.fixture(scope="module")
def grating_slides():
    out = {}
    for direction in ("+x", "-x"):
        out[direction] = simulate_rig(
            "multilayer3/grating-9",
            SENSOR,
            rig=ProbeRig(direction=direction),
            protocol=PROTO,
            finger=SKIN,
            seed=11,
            ideal=True,
        ).recording
    return out


def test_grating_period_is_spacing_over_speed(grating_slides):
    rec = grating_slides["+x"]
    rate = rec.meta["rate_hz"]
    x = np.asarray(rec.meta["x_probe_m"])
    centre = int(np.flatnonzero(np.all(SENSOR.layout.positions[:, :2] == 0, axis=1))[0])
    sig = rec.data[:, centre].astype(float)
    # the cruise with the element wholly under the face's ridges (9 ridges of 4 mm)
    inside = np.abs(x) < 0.018 - 1.5e-3 - 2.5e-3
    s = sig[inside] - sig[inside].mean()
    spec = np.abs(np.fft.rfft(s, 8 * len(s)))
    f = np.fft.rfftfreq(8 * len(s), 1 / rate)
    f_peak = f[np.argmax(spec[1:]) + 1]
    assert f_peak == pytest.approx(0.065 / 4e-3, rel=PERIOD_TOL)


def test_the_carriage_follows_its_command_and_directions_mirror(grating_slides):
    plus, minus = grating_slides["+x"], grating_slides["-x"]
    assert plus.meta["direction"] == 1.0 and minus.meta["direction"] == -1.0
    rig = ProbeRig()
    pas = ProbePass.of(rig, 0.036, 6.5e-3, 2.5e-3, 0.065, 5.0, 1.0)
    t = (np.arange(len(plus.data)) + 0.5) / plus.meta["rate_hz"]
    x = np.asarray(plus.meta["x_probe_m"])
    assert np.max(np.abs(x - pas.position(t))) < 0.05e-3  # MuJoCo's carriage, on its path
    assert np.abs(np.asarray(minus.meta["x_probe_m"]) + x).max() < 0.05e-3
    # the grating and the element grid are symmetric about x = 0: the -x slide is the +x
    # slide mirrored, element for mirrored element
    pos = SENSOR.layout.positions
    mirror = [
        int(np.flatnonzero(np.all(np.isclose(pos, pos[m] * [-1, 1, 1]), axis=1))[0])
        for m in range(len(pos))
    ]
    a = plus.data.astype(float)
    b = minus.data[:, mirror].astype(float)
    assert np.abs(a - b).max() < 0.01 * np.abs(a).max()
    # at rest the probe's edge is 7 mm (2.8 stack thicknesses) from the nearest element's:
    # the elements read almost nothing (measured: 0.26% of the peak at most)
    assert np.abs(a[:50]).max() < 5e-3 * np.abs(a).max()


def test_rig_slides_are_deterministic_and_go_both_ways():
    ss = get_task("multilayer3-v2").get_data
    assert ss.rig is not None and ss.finger.stack is not None
    jobs = ss.jobs(seed=0, quick=True)
    signs = {ss.rig.sign(j.seed) for j in jobs}
    assert signs == {1.0, -1.0}
    job = jobs[0]
    a, b = job.simulate().recording, job.simulate().recording
    assert a.data.tobytes() == b.data.tobytes()
    assert a.meta["scene"] == "probe rig" and a.data.shape == (job.n_samples(), 18)
    assert "rig" in job.describe() and job.key() != replace(job, rig=ProbeRig(margin_m=0)).key()
    finger_job = get_task("multilayer3-v1").get_data.jobs(seed=0, quick=True)[0]
    assert "rig" not in finger_job.describe()


def test_the_rig_reads_its_lines_as_numpy_interpolates_them():
    rng = np.random.default_rng(3)
    u = np.cumsum(rng.uniform(0.5e-4, 1.5e-4, 400)) - 0.02
    R = rng.normal(size=(18, u.size))
    xt = rng.uniform(-0.01, 0.01, 18)
    out = np.empty(18)
    xs = np.concatenate(
        [
            rng.uniform(-0.04, 0.04, 300),
            xt[:1] - u[[0, 5, -1]],  # exactly on a knot, the first, the last
            xt[:1] - u[0] + 1e-12,  # just beyond the first knot
            [np.nan],
        ]
    )
    for x in xs:
        _read_lines(xt, float(x), u, R, out)
        ref = np.array([np.interp(xt[i] - x, u, R[i], left=0.0, right=0.0) for i in range(18)])
        assert out.tobytes() == ref.tobytes(), x
