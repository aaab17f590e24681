"""The press-and-slide protocol on the papers' scenes: the grating law, a flat plate,
determinism, recordings, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from sim_tactile.errors import ConfigError, UnknownNameError
from sim_tactile.records import Recording
from sim_tactile.sensors import Finger
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.slide import simulate

MM = 1e-3
RIDGE_PITCH_M = 9 * MM  # finger7/ridges-4: 36 mm / 4
TAXEL_PITCH_M = 2.5 * MM  # grid3x3
RIDGE_SPAN_HALF_M = 13.5 * MM + 1.25 * MM  # outer ridge centres +-13.5 mm, 2.5 mm wide
#: The grating law's tolerances: pulse period within 2%, column delay within 15%.
PERIOD_RTOL = 0.02
DELAY_RTOL = 0.15
#: The flat plate's steady load may vary by less than 0.1%.
FLAT_RTOL = 1e-3
#: Under the held force a flat plate loads the taxels alike at every step: float32 round-off.
HELD_FLAT_RTOL = 1e-6


def _pulse_centroids(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Load-weighted mean time of each pulse (a run of non-zero load)."""
    lab, n = ndimage.label(y > 1e-3 * y.max())
    return np.array(
        [np.sum(t[lab == k] * y[lab == k]) / np.sum(y[lab == k]) for k in range(1, n + 1)]
    )


def _xcorr_lag(a: np.ndarray, b: np.ndarray, dt: float) -> float:
    """Delay of b after a [s], from the cross-correlation peak with parabolic refinement."""
    a, b = a - a.mean(), b - b.mean()
    c = np.correlate(b, a, "full")
    k = int(np.argmax(c))
    frac = 0.0
    if 0 < k < len(c) - 1:
        frac = (c[k - 1] - c[k + 1]) / (2 * (c[k - 1] - 2 * c[k] + c[k + 1]))
    return (k - (len(a) - 1) + frac) * dt


@pytest.fixture(
    scope="module",
    params=[(v, fc) for fc in ("dynamic", "quasi-static") for v in (0.03, 0.06, 0.12)],
    ids=lambda p: f"{p[0] * 1e3:.0f}mm/s-{p[1]}",
)
def ridges4(request, cache):
    v, fc = request.param
    proto = Protocol(speed_m_s=v, force_control=fc)
    return v, simulate(
        "finger7/ridges-4", "grid3x3", protocol=proto, ideal=True, cache=cache
    ).recording


def test_grating_law_pulses_and_period(ridges4):
    v, rec = ridges4
    t, pos = rec.times.astype(float), rec.taxels
    x0 = rec.meta["x_start_m"]
    middle = [i for i in range(rec.n_taxels) if abs(pos[i, 1]) < 1e-9]
    assert len(middle) == 3
    for i in middle:
        # while the taxel is over the ridges: outermost ridge edges at +-14.75 mm, plus the
        # taxel's half-width (1 mm) and 0.5 mm
        x = x0 + v * t + pos[i, 0]
        over = np.abs(x) < RIDGE_SPAN_HALF_M + 1.5 * MM
        c = _pulse_centroids(t[over], rec.data[over, i].astype(float))
        assert len(c) == 4, (i, c)
        assert np.median(np.diff(c)) == pytest.approx(RIDGE_PITCH_M / v, rel=PERIOD_RTOL)


def test_grating_law_column_delay(ridges4):
    v, rec = ridges4
    pos = rec.taxels
    middle = sorted(
        (i for i in range(rec.n_taxels) if abs(pos[i, 1]) < 1e-9), key=lambda i: pos[i, 0]
    )
    dt = 1.0 / rec.meta["rate_hz"]
    for lead, trail in zip(middle[1:], middle[:-1], strict=True):
        # the column ahead (larger x) meets each ridge first
        lag = _xcorr_lag(rec.data[:, lead].astype(float), rec.data[:, trail].astype(float), dt)
        assert lag == pytest.approx(TAXEL_PITCH_M / v, rel=DELAY_RTOL)


def test_flat_plate_steady_load(cache):
    rec = simulate(
        "finger7/flat",
        "grid3x3",
        protocol=Protocol(speed_m_s=0.06, duration_s=0.5),
        ideal=True,
        cache=cache,
    ).recording
    steady = rec.data[5:].astype(float)  # after the 20 ms speed ramp
    assert steady.min() > 0
    spread = (steady.max(axis=0) - steady.min(axis=0)) / steady.mean(axis=0)
    assert spread.max() < FLAT_RTOL
    total = np.asarray(rec.meta["normal_force_n"])[5:]
    assert np.allclose(total, 1.0, rtol=FLAT_RTOL)
    # held exactly (quasi-static force control, the default), the load does not move at all
    d = rec.data.astype(float)
    assert (np.ptp(d, axis=0) <= HELD_FLAT_RTOL * d.mean(axis=0)).all()


def test_same_seed_same_bits_and_jitter_follows_the_seed(cache):
    proto = Protocol(
        speed_m_s=0.06, duration_s=0.3, speed_jitter=0.1, force_jitter=0.1, offset_jitter_m=1e-3
    )
    a = simulate(
        "finger7/bumps-4x4", "grid3x3", protocol=proto, seed=7, ideal=True, cache=cache
    ).recording
    b = simulate(
        "finger7/bumps-4x4", "grid3x3", protocol=proto, seed=7, ideal=True, cache=cache
    ).recording
    c = simulate(
        "finger7/bumps-4x4", "grid3x3", protocol=proto, seed=8, ideal=True, cache=cache
    ).recording
    assert np.array_equal(a.data, b.data) and a.data.tobytes() == b.data.tobytes()
    assert a.meta["protocol"] == b.meta["protocol"]
    assert a.meta["protocol"]["speed_m_s"] != c.meta["protocol"]["speed_m_s"]


def test_recording_roundtrip(tmp_path, cache):
    rec = simulate(
        "finger7/ridges-2", "grid3x3", protocol=Protocol(duration_s=0.2), ideal=True, cache=cache
    ).recording
    path = rec.save(tmp_path / "r.npz")
    back = Recording.load(path)
    assert back.data.dtype == np.float32 and np.array_equal(back.data, rec.data)
    assert np.array_equal(back.times, rec.times) and np.array_equal(back.taxels, rec.taxels)
    assert back.meta == rec.meta and back.units == "N"
    with np.load(path, allow_pickle=False) as z:  # readable without pickle
        assert set(z.files) == {"data", "times", "taxels", "meta_json"}


def test_bad_input_is_refused():
    with pytest.raises(UnknownNameError, match="grid4x4"):
        simulate("finger7/flat", "grid4x4")
    with pytest.raises(ConfigError, match="speed_m_s"):
        Protocol(speed_m_s=-0.1)
    with pytest.raises(ConfigError, match="force_n"):
        Protocol(force_n=0.0)
    with pytest.raises(ConfigError, match="beyond the pad"):
        simulate(
            "finger7/flat", "dense-0.5mm", finger=Finger(size_m=(4e-3, 4e-3), edge_radius_m=0.5e-3)
        )
    with pytest.raises(ConfigError, match="fidelity"):
        simulate("finger7/flat", "grid3x3", fidelity="L9")


@pytest.mark.parametrize("force_control", ["quasi-static", "dynamic"])
def test_a_window_longer_than_the_plate_stops_the_pad_at_its_end(force_control, cache):
    """2 s at 60 mm/s would carry the pad 120 mm, off the 108 mm plate: the stroke stops with
    the pad wholly on the plate and says so (it once slid off the end and sank)."""
    res = simulate(
        "finger7/ridges-4",
        "grid3x3",
        protocol=Protocol(duration_s=2.0, force_control=force_control),
        ideal=True,
        cache=cache,
    )
    rec = res.recording
    x = np.asarray(rec.meta["x_pad_m"])
    assert x.max() <= 54e-3 - 8e-3 + 1e-4  # the 16 mm patch stays on the plate
    assert any("stopped at the plate's end" in w for w in res.warnings)
    tail = rec.data[-20:].astype(float)  # at rest on flat ground: a steady load
    assert tail.min() > 0 and np.ptp(tail, axis=0).max() < 1e-3 * tail.max()


# --- the finger's skin as a layer on its bone -------------------------------------------------


def _layered_grid3x3():
    from dataclasses import replace

    from sim_tactile.sensors import get_sensor
    from sim_tactile.sensors.stack import Layer, Stack

    s = get_sensor("grid3x3")
    f = s.finger
    return replace(s, finger=f.layered(Stack((Layer(f.thickness_m, f.young_pa, f.poisson),))))


def test_a_layered_skin_keeps_the_grating_law_and_the_held_force(cache):
    v = 0.06
    rec = simulate(
        "finger7/ridges-4",
        _layered_grid3x3(),
        protocol=Protocol(speed_m_s=v),
        ideal=True,
        cache=cache,
    ).recording
    np.testing.assert_allclose(rec.meta["normal_force_n"], 1.0, rtol=1e-9)
    t, pos, x0 = rec.times.astype(float), rec.taxels, rec.meta["x_start_m"]
    for i in [i for i in range(rec.n_taxels) if abs(pos[i, 1]) < 1e-9]:
        over = np.abs(x0 + v * t + pos[i, 0]) < RIDGE_SPAN_HALF_M + 1.5 * MM
        c = _pulse_centroids(t[over], rec.data[over, i].astype(float))
        assert len(c) == 4, (i, c)
        assert np.median(np.diff(c)) == pytest.approx(RIDGE_PITCH_M / v, rel=PERIOD_RTOL)


#: an independent spectral layered solution (itself checked against scikit-fem) read the
#: grid3x3 pad on a flat plate at 1 N: centre taxel 14% below the corners on the half-space,
#: 8% above them on the 4 mm layer on its bone. Ours at the default nodes, within 3 points.
FLAT_CENTRE_VS_CORNERS = {"half-space": -0.14, "layer": 0.08}
FLAT_CENTRE_ATOL = 0.03


def test_a_layer_on_its_bone_loads_the_pads_centre_not_its_rim(cache):
    """A half-space loads a flat pad's rim (the flat punch's edge); a thin layer on a rigid
    bone loads its centre, where the incompressible silicone cannot escape sideways."""
    from sim_tactile.sensors import get_sensor

    proto = Protocol(duration_s=0.5)
    for name, sensor in (("half-space", get_sensor("grid3x3")), ("layer", _layered_grid3x3())):
        rec = simulate("finger7/flat", sensor, protocol=proto, ideal=True, cache=cache).recording
        y = rec.data[20:].astype(float).mean(axis=0)
        centre_vs_corners = y[4] / y[[0, 2, 6, 8]].mean() - 1
        assert centre_vs_corners == pytest.approx(
            FLAT_CENTRE_VS_CORNERS[name], abs=FLAT_CENTRE_ATOL
        ), name


def test_sliding_tractions_load_each_taxel_from_its_nearer_rim_and_leave_the_force(cache):
    """With the skin carrying the sliding friction (mu 0.5, against the +x slide) the
    incompressible half-space's contact pressure is unchanged, and the buried taxels read
    Cerruti's stress of the tractions: on a flat plate, where the flat pad's pressure
    gathers at its rim, a taxel gains from the rim behind the tractions' direction (the
    leading, +x rim) and loses the same from the other: the left and right columns move by
    equal and opposite amounts of 2-4% (an independent estimate: 2-3% at the edges), the
    middle column not at all."""
    from dataclasses import replace

    from sim_tactile.sensors import get_sensor

    s0 = get_sensor("multilayer3x3x2")
    s0 = replace(s0, finger=replace(s0.finger, friction=0.5))
    s1 = replace(s0, finger=replace(s0.finger, skin_tractions=True))
    proto = Protocol(duration_s=0.5)
    r0, r1 = (
        simulate("finger7/flat", s, protocol=proto, ideal=True, seed=1, cache=cache).recording
        for s in (s0, s1)
    )
    np.testing.assert_allclose(r1.meta["normal_force_n"], r0.meta["normal_force_n"], rtol=1e-12)
    m0, m1 = (r.data[20:].astype(float).mean(axis=0) for r in (r0, r1))
    change = (m1 - m0) / m0
    x = r0.taxels[:, 0]
    ahead, behind, middle = x > 1e-3, x < -1e-3, np.abs(x) < 1e-9
    assert np.all(change[ahead] > 0.015) and np.all(change[ahead] < 0.05)
    np.testing.assert_allclose(change[behind], -change[ahead], atol=1e-3)
    np.testing.assert_allclose(change[middle], 0.0, atol=1e-3)


#: The commanded speed is held after the ramp (a robot arm holds its speed).
SPEED_RTOL = 1e-3


@pytest.mark.parametrize("force_control", ["quasi-static", "dynamic"])
def test_the_pad_holds_its_commanded_speed_and_the_period_is_pitch_over_speed(force_control, cache):
    """finger7/ridges-4 at 45 mm/s, jitter off: the pad's speed over the texture is the
    command within 0.1% (the skin's drag, mu N, once slowed it behind the velocity servo by
    0.9%), and the ridge period is pitch / commanded speed within 0.2%."""
    from sim_tactile.bench.closed_forms import probe_taxel, pulse_period
    from sim_tactile.plates import get_plate
    from sim_tactile.sensors import get_sensor

    v = 0.045
    proto = Protocol(
        speed_m_s=v,
        speed_jitter=0.0,
        force_jitter=0.0,
        offset_jitter_m=0.0,
        force_control=force_control,
    )
    rec = simulate("finger7/ridges-4", "grid3x3", protocol=proto, ideal=True, cache=cache).recording
    plate, sensor = get_plate("finger7/ridges-4"), get_sensor("grid3x3")
    m = pulse_period(
        rec,
        probe_taxel(sensor.layout),
        plate.area_length_m,
        RIDGE_PITCH_M,
        v,
        sensor.finger.patch_m[0],
    )
    assert m["pad_speed_m_s"] == pytest.approx(v, rel=SPEED_RTOL)
    assert m["period_s"] == pytest.approx(RIDGE_PITCH_M / v, rel=2e-3)
    assert rec.meta["mean_drag_n"] > 0.5  # the drag is still measured (mu 0.8 x 1 N)
