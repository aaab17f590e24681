"""``fidelity="auto"``: what it picks for a scene."""

from __future__ import annotations

import pytest

from sim_tactile.plates import get_plate
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import Finger, get_sensor
from sim_tactile.sim.fidelity import MAX_NODES, choose_fidelity
from sim_tactile.sim.protocol import Protocol


def _auto(plate: str, sensor: str = "grid3x3", finger: Finger | None = None, level="auto"):
    sen = get_sensor(sensor)
    f = finger or sen.finger
    return choose_fidelity(get_plate(plate), sen.layout, f, Protocol(), level), f


def test_ridges_under_a_flat_pad_get_nodes_along_the_slide():
    fid, finger = _auto("finger7/ridges-4")
    # 2.5 mm ridges: x at a fifth of them; y as coarse as the 2 mm taxels
    assert fid.pitch_m == pytest.approx(0.5e-3)
    assert fid.pitch_y_m == pytest.approx(2e-3)
    assert "0.5 x 2 mm" in fid.reason
    ref, _ = _auto("finger7/ridges-4", level="L2")
    assert (ref.pitch_m, ref.pitch_y_m) == pytest.approx((0.25e-3, 1e-3))
    assert skin_grid(finger, fid.pitch_m, fid.pitch_y_m).n <= MAX_NODES["L1"]


@pytest.mark.parametrize("plate", ["finger7/bumps-4x4", "finger7/flat"])
def test_two_dimensional_textures_keep_square_nodes(plate):
    fid, _ = _auto(plate)
    assert fid.pitch_y_m is None


def test_a_curved_pad_keeps_square_nodes_over_ridges():
    fid, _ = _auto(
        "finger7/ridges-4", finger=Finger(shape="sphere", radius_m=0.01, size_m=(0.012, 0.012))
    )
    assert fid.pitch_y_m is None
