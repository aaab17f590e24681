"""The presets' skins as their papers describe them: every number sourced, every stack
usable end to end."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.errors import UnknownNameError
from sim_tactile.sensors import get_sensor, sensor_names
from sim_tactile.sensors.paper_stacks import PAPER_STACKS, paper_stack
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.slide import simulate

#: each preset's task scene: the plate it slides over and its nominal force [N]
SCENES = {
    "grid3x3": ("finger7/ridges-4", 1.0),
    "multilayer3x3x2": ("multilayer3/flat", 5.0),
    "biotac19": ("textures20/grating-3.0mm", 0.5),
    "icub60": ("textures20/flat", 1.0),
    "pvdf2": ("roughness8/ra-50", 1.0),
}


def test_every_preset_has_a_paper_stack_and_every_number_a_source():
    assert set(PAPER_STACKS) == set(sensor_names())
    for name, ps in PAPER_STACKS.items():
        assert ps.sensor == name
        for x in ps.numbers():
            assert x.source.startswith(("paper 00", "assumption: ")), (name, x)
        assert ps.backing_source.startswith(("paper 00", "assumption: ")), name
        for la in ps.layers:
            assert la.what.startswith(("paper 00", "assumption: ")), (name, la.what)
    with pytest.raises(UnknownNameError, match="no paper stack for sensor 'nope'"):
        paper_stack("nope")


@pytest.mark.parametrize("name", sorted(PAPER_STACKS))
def test_the_taxels_lie_inside_the_papers_stack(name):
    """Each preset's taxels lie above the backing of its paper's stack (a taxel in a rigid
    bone would read nothing)."""
    s = get_sensor(name).with_paper_stack()
    st = s.finger.stack
    assert s.finger.thickness_m == pytest.approx(st.thickness_m)
    assert (s.layout.depth_m < st.thickness_m).all()
    # the rest of the sensor is the preset's
    base = get_sensor(name)
    assert s.layout is not None and s.transducer_json() == base.transducer_json()
    assert base.finger.stack is None  # the -v1 presets keep the half-space


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(PAPER_STACKS))
def test_every_paper_stack_slides_over_its_task_plate(name, cache):
    """A short slide of each preset on its paper's stack over its task's plate: the force
    held, every taxel finite, and the skin read through the stack (the loads differ from
    the half-space's)."""
    plate, force = SCENES[name]
    proto = Protocol(duration_s=0.3, force_n=force)
    paper = get_sensor(name).with_paper_stack()
    runs = [
        simulate(plate, s, protocol=proto, ideal=True, seed=0, cache=cache)
        for s in (get_sensor(name), paper)
    ]
    half, layered = (r.recording for r in runs)
    assert layered.meta["finger"]["stack"] == paper.finger.stack.to_json()
    np.testing.assert_allclose(layered.meta["normal_force_n"], force, rtol=1e-6)
    assert np.isfinite(layered.data).all() and layered.data.max() > 0
    assert not np.allclose(layered.data, half.data, rtol=1e-3)
