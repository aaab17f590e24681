"""Hard cases end in a measured result or a clear PhysicsError naming the cause; never a
crash, a NaN or a silent auto-reset."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.errors import PhysicsError
from sim_tactile.plates import Bumps, Plate
from sim_tactile.sensors import Finger
from sim_tactile.sim.protocol import Protocol
from sim_tactile.sim.simulate import simulate


def _ok(res):
    d = res.recording.data
    assert np.isfinite(d).all() and d.max() > 0
    return res


@pytest.mark.parametrize("force_control", ["quasi-static", "dynamic"])
def test_fast_slide_200mm_s(force_control, cache):
    proto = Protocol(speed_m_s=0.2, force_control=force_control)
    res = _ok(simulate("finger7/ridges-4", "grid3x3", protocol=proto, ideal=True, cache=cache))
    assert res.fidelity.dt_s <= 2.5e-3 / 0.2 / 20 + 1e-12  # 20 steps per ridge crossing
    force = np.asarray(res.recording.meta["normal_force_n"])
    if force_control == "quasi-static":  # the force is held at any speed
        np.testing.assert_allclose(force, 1.0, rtol=1e-9)
        assert not any("mean normal force" in w for w in res.warnings)
        return
    # the dynamic pad skims the ridge tops: the mean press force is off, and said so
    assert float(np.mean(force)) > 1.05
    assert any("mean normal force over the slide" in w for w in res.warnings), res.warnings


def test_strong_press_5n(cache):
    res = _ok(
        simulate(
            "finger7/ridges-4",
            "grid3x3",
            protocol=Protocol(force_n=5.0, duration_s=0.4),
            ideal=True,
            cache=cache,
        )
    )
    assert np.mean(res.recording.meta["normal_force_n"]) == pytest.approx(5.0, rel=0.05)


def test_sharp_ridge_edges(cache):
    _ok(
        simulate(
            "finger7/ridges-4", "grid3x3", finger=Finger(edge_radius_m=0.0), ideal=True, cache=cache
        )
    )


def test_features_below_the_node_pitch_warn(cache):
    plate = Plate(
        texture=Bumps(
            rows=30, cols=30, shape="box", size_m=0.3e-3, height_m=0.3e-3, spacing_m=1.2e-3
        )
    )
    res = _ok(
        simulate(plate, "grid3x3", protocol=Protocol(duration_s=0.1), ideal=True, cache=cache)
    )
    assert any("smeared" in w for w in res.warnings)
    assert any("aliases the texture" in w for w in res.warnings)


def test_too_coarse_time_step_stops_with_the_limit(cache):
    with pytest.raises(PhysicsError, match=r"time step too coarse.*omega\*dt.*dt <="):
        simulate(
            "finger7/ridges-4",
            "grid3x3",
            dt_s=0.01,
            protocol=Protocol(force_control="dynamic"),
            ideal=True,
            cache=cache,
        )


def test_skin_pressed_to_the_bottom_stops(cache):
    with pytest.raises(PhysicsError, match="pressed to the bottom"):
        simulate(
            "finger7/ridges-4",
            "grid3x3",
            finger=Finger(thickness_m=0.3e-3),
            protocol=Protocol(force_n=5.0),
            ideal=True,
            cache=cache,
        )


def test_press_beyond_what_the_skin_carries_stops_as_bottomed_not_runaway(cache):
    """20 N on the 4 mm skin over 2.5 mm ridges: the nodes end up inside the narrow ridges
    and the base box, where the collider reads depth from the nearest other face, so only the
    pad's own depth shows the skin bottomed out (it once fell through as a 'runaway')."""
    with pytest.raises(PhysicsError, match=r"pressed to the bottom.*half the plate's 5 mm base"):
        simulate(
            "finger7/ridges-4",
            "grid3x3",
            protocol=Protocol(force_n=20.0, duration_s=0.3),
            ideal=True,
            cache=cache,
        )
