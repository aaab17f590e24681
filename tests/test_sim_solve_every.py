"""The skin solved at every n-th step (StepOptions.solve_every): the same machinery at n = 1
is the per-step slide bit for bit, a larger n stays close to it (the loads between solves on
the line between them), and it is refused or ignored where it does not apply."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.plates import get_plate
from sim_tactile.sim import Protocol, Slide, StepOptions, prepare, simulate
from sim_tactile.sim.slide import _slide, _slide_sampled

PROTO = Protocol(speed_m_s=0.06, force_n=1.0, duration_s=0.3, start="texture", rate_hz=100.0)
#: On a 2.5 mm ridge plate under 2 mm taxels at L0 (1 mm nodes: the per-step loads jump
#: as node rows cross the walls, 0.12 mm of travel a step) the line between solves misses
#: those jumps: 3.3% rel L2 over 0.3 s on the texture at 2 steps, 3.6% at 4. Over whole slides
#: of smooth scenes it does far better (perf/bench_response.py: the BioTac's 1.0% and the
#: iCub's 1.1% at 4 steps); this only bounds the jumpy case and its growth.
REL_L2_JUMPY = 0.06


def _pressed(fidelity: str = "L0"):
    return prepare(Slide(get_plate("finger7/ridges-4"), "grid3x3", PROTO, 2, fidelity))


def test_one_solve_every_step_is_the_per_step_slide_bit_for_bit():
    a, b = _pressed(), _pressed()
    n_sub = a.fidelity.steps_per_sample
    ref = _slide(a.runner, a.window, a.protocol, n_sub)
    got = _slide_sampled(b.runner, b.window, b.protocol, n_sub, 1)
    assert ref.loads.tobytes() == got.loads.tobytes()
    assert ref.forces.tobytes() == got.forces.tobytes()
    assert ref.x_pad.tobytes() == got.x_pad.tobytes()


def test_fewer_solves_stay_close_to_the_per_step_solve():
    kw = dict(protocol=PROTO, fidelity="L0", seed=2, ideal=True)
    ref = simulate("finger7/ridges-4", "grid3x3", **kw)
    b = ref.recording.data.astype(float)
    err = {}
    for n in (2, 4):
        res = simulate("finger7/ridges-4", "grid3x3", options=StepOptions(solve_every=n), **kw)
        a = res.recording.data.astype(float)
        assert res.recording.meta["solve_every"] == n
        assert res.recording.meta["x_pad_m"] == ref.recording.meta["x_pad_m"]  # same dynamics
        assert not np.array_equal(a, b)  # it did solve less often
        err[n] = np.linalg.norm(a - b) / np.linalg.norm(b)
    assert ref.recording.meta["solve_every"] == 1
    assert err[2] <= err[4] < REL_L2_JUMPY, err


def test_position_control_solves_every_step_whatever_is_asked():
    proto = Protocol(speed_m_s=0.06, force_n=0.5, duration_s=0.1, force_control="position")
    res = simulate(
        "finger7/flat", "grid3x3", protocol=proto, fidelity="L0", options=StepOptions(solve_every=4)
    )
    assert res.recording.meta["solve_every"] == 1


@pytest.mark.parametrize("bad", [0, -1, 65, 2.5, "4"])
def test_a_bad_solve_every_names_its_range(bad):
    with pytest.raises(ConfigError, match="solve_every"):
        StepOptions(solve_every=bad)
