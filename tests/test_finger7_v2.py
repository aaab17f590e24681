"""finger7-v2: the curved finger under position control (lowered to a touch, then held at that
height while the load follows the texture), and the slide set's fixed node pitch."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.slide import simulate
from sim_tactile.slides import SlideSet
from sim_tactile.tasks import get_task
from sim_tactile.tasks.defs.finger7 import FINGER7_PLATES, FINGER7_V2_FINGER

TOUCH_N = 0.05
PROTO = Protocol(speed_m_s=0.06, force_n=TOUCH_N, duration_s=1.4, force_control="position")


def _slide(plate: str):
    return simulate(
        plate, "grid3x3", protocol=PROTO, finger=FINGER7_V2_FINGER, pitch_m=0.5e-3, ideal=True
    ).recording


def test_position_control_touches_then_keeps_its_height():
    flat = _slide("finger7/flat")
    f = np.asarray(flat.meta["normal_force_n"])
    # lowered until the skin carries the touch force (its height bisected to it)...
    assert TOUCH_N <= f[0] < (1 + 1e-5) * TOUCH_N
    # ...and on flat ground the height, so the load, stays where it was
    np.testing.assert_allclose(f, f[0], rtol=1e-6)
    ridges = _slide("finger7/ridges-4")
    g = np.asarray(ridges.meta["normal_force_n"])
    # the 2.5 mm ridges press into the finger: the load follows them, nothing holds it
    assert g.max() > 20 * TOUCH_N
    assert g[:5] == pytest.approx(f[:5], rel=1e-6)  # the same touch on the same ground
    # the ridges come and go under the centre taxel (4 ridges, 7.5 mm apart)
    c = ridges.data[:, 4].astype(float)
    assert (np.diff(np.sign(c - 0.5 * c.max())) > 0).sum() == 4


def test_position_is_a_force_control_and_bad_names_are_refused():
    assert Protocol(force_control="position").force_control == "position"
    with pytest.raises(ConfigError, match="force_control = 'held'.*position"):
        Protocol(force_control="held")
    with pytest.raises(ConfigError, match="pitch_m = 0.01 m is out of range"):
        SlideSet(
            plates=FINGER7_PLATES[:2],
            sensor="grid3x3",
            protocol=PROTO,
            slides=2,
            quick_slides=2,
            pitch_m=0.01,
        )


def test_finger7_v2_slides_use_its_pitch_and_finger():
    ss = get_task("finger7-v2").get_data
    job = ss.jobs(seed=0, quick=True)[0]
    assert job.pitch_m == 0.25e-3 and job.describe()["pitch_m"] == 0.25e-3
    assert job.finger.shape == "ellipsoid" and job.finger.stack is not None
    assert job.protocol.force_control == "position" and job.n_samples() == 900
    v1 = get_task("finger7-v1").get_data.jobs(seed=0, quick=True)[0]
    assert "pitch_m" not in v1.describe()  # the other tasks' slide keys are unchanged
