"""What a slide says about itself: a drag the friction's regularisation holds low is
reported as such, and a pad pressed to the bottom names the force commanded and the load
it carried there."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from sim_tactile.errors import PhysicsError
from sim_tactile.plates import get_plate
from sim_tactile.sensors import Finger
from sim_tactile.sim import StepOptions
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.slide import simulate
from sim_tactile.sim.step.runner import DRAG_FULL, V_STICK, drag_factor, drag_warning

#: The slide's speed ramp and the force loop keep the measured drag a little under the
#: steady one (0.94 of it at 0.1 mm/s, 0.99 at 60 mm/s over 0.2 s).
DRAG_RTOL = 0.1


def _slide(speed_m_s: float):
    proto = Protocol(
        speed_m_s=speed_m_s, force_n=1.0, duration_s=0.2, speed_jitter=0.0, force_jitter=0.0
    )
    return simulate("finger7/flat", "grid3x3", protocol=proto)


def test_the_regularised_drag_factor_and_where_it_is_reported():
    assert drag_factor(1e-4) == pytest.approx(math.tanh(0.1))
    assert drag_factor(-2e-3) == pytest.approx(math.tanh(2.0))
    edge = V_STICK * math.atanh(DRAG_FULL)  # 4.95 mm/s
    assert 4.9e-3 < edge < 5e-3
    assert drag_warning(0.99 * edge) is not None and drag_warning(1.01 * edge) is None
    assert drag_warning(0.0) is None  # nothing slides, no drag to report
    w = drag_warning(1e-4)
    for words in ("0.1 mm/s", "V_STICK = 1 mm/s", "0.09967 of mu N", "10x low", "4.95 mm/s"):
        assert words in w, w


def test_a_slow_slide_says_its_drag_is_regularised_and_by_how_much():
    """At 0.1 mm/s the drag mu N tanh(v / V_STICK) is a tenth of mu N: the recording says
    so in a warning and its meta, and its mean drag is that share of mu N; at 60 mm/s
    neither."""
    slow = _slide(1e-4)
    meta = slow.recording.meta
    assert meta["drag_regularised"] is True
    assert meta["drag_factor"] == pytest.approx(math.tanh(0.1))
    assert any("regularised" in w and "0.1 mm/s" in w for w in slow.warnings)
    mu_n = Finger().friction * 1.0
    assert meta["mean_drag_n"] == pytest.approx(meta["drag_factor"] * mu_n, rel=DRAG_RTOL)
    fast = _slide(0.06)
    assert fast.recording.meta["drag_regularised"] is False
    assert fast.recording.meta["drag_factor"] == pytest.approx(1.0)
    assert not any("regularised" in w for w in fast.warnings)
    assert fast.recording.meta["mean_drag_n"] == pytest.approx(mu_n, rel=DRAG_RTOL)


def test_a_pad_pressed_to_the_bottom_names_the_commanded_force_and_its_load():
    """A soft skin approaching a plate of a 1 mm base reaches half the base before it
    carries the fifth of the force the approach stops at: the error named "0 N" (the
    approach's own command); it names the 1 N commanded and the 0.02 N carried there."""
    thin = replace(get_plate("finger7/flat"), thickness_m=1e-3)
    proto = Protocol(force_n=1.0, duration_s=0.2)
    soft = Finger(young_pa=2e3)
    step = StepOptions(path="per-step")  # the approach, which the flat plate's table skips
    with pytest.raises(PhysicsError) as exc:
        simulate(thin, "grid3x3", finger=soft, protocol=proto, options=step)
    msg = str(exc.value)
    assert "of the 1 N commanded" in msg and " 0 N " not in msg, msg
    carried = float(msg.split("the pad carries ")[1].split(" N")[0])
    assert 0.0 < carried < 0.2  # short of the fifth of 1 N that ends the approach
    # read off its one-phase table, the held press is checked as a held step is
    with pytest.raises(PhysicsError, match="skin pressed to the bottom"):
        simulate(thin, "grid3x3", finger=soft, protocol=proto)
