"""Node patches clipped at the plate's walls and the taxels' edges (sim.skin.clipped)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.signal import find_peaks

from sim_tactile.bench import physics
from sim_tactile.errors import ConfigError
from sim_tactile.plates import get_plate, surface_of
from sim_tactile.scene.elastic import compliance_matrix
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import Finger, Sensor, get_sensor
from sim_tactile.sensors.layouts import grid_layout
from sim_tactile.sensors.stack import Layer, Stack
from sim_tactile.sim import StepOptions
from sim_tactile.sim.plan import measured_errors as me
from sim_tactile.sim.plan.fidelity import choose_fidelity
from sim_tactile.sim.plan.lattices import check_clippable
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.skin.clipped import (
    ClippedPatches,
    assemble,
    rect_compliance,
)
from sim_tactile.sim.slide import simulate

#: A clipped 1 mm lattice's taxel loads against Tamaas on finger7/bumps-4x4 (grid3x3, 1 N):
#: measured 2.7% over the four offsets (0.3% to 3.0% each; docs/physics.md); whole patches at
#: that grid are 100% off.
CLIPPED_VS_TAMAAS = 0.05
#: Identical bumps passing under the centre taxel give the same peak: measured within 0.9%
#: clipped (whole patches: 0.037 to 0.057 N, 50% apart).
SAME_BUMP_PEAKS = 0.02


def _cp(plate="finger7/bumps-4x4", pitch=1e-3, sensor="grid3x3", y0=0.0):
    s = get_sensor(sensor)
    return ClippedPatches(skin_grid(s.finger, pitch), s.finger, s.layout, get_plate(plate), y0), s


def test_the_clipped_solve_takes_the_whole_patch_solvers_tolerance():
    from sim_tactile.sim.skin import clipped, contact

    assert (clipped.TOL_REL, clipped.MAX_ITER) == (contact.TOL_REL, contact.MAX_ITER)


def test_rect_compliance_is_loves_solution_on_a_lattice():
    g = skin_grid(Finger(), 1e-3)
    n = g.n
    C = rect_compliance(g.xy[:, 0], g.xy[:, 1], np.full(n, 5e-4), np.full(n, 5e-4), 4e5)
    np.testing.assert_allclose(C, compliance_matrix(g.xy, 1e-3, 4e5), rtol=1e-12, atol=0)


def test_the_assembled_compliance_equals_the_direct_one():
    cp, _ = _cp()
    cx, cy, hx, hy, cell, split = cp.patches(0.37e-3)
    assert split.any() and not split.all()
    sel = np.flatnonzero(np.abs(cy) < 6e-3)
    args = (cx[sel], cy[sel], hx[sel], hy[sel])
    A = assemble(*args, cell[sel], split[sel], cp.C_cells, cp.e_star)
    np.testing.assert_allclose(A, rect_compliance(*args, cp.e_star), rtol=1e-13, atol=0)


@pytest.mark.parametrize("x_pad", [0.0, 0.37e-3, 1.25e-3, 3.1e-3])
def test_no_patch_straddles_a_wall_or_a_taxel_edge(x_pad):
    cp, s = _cp()
    plate = get_plate("finger7/bumps-4x4")
    cx, cy, hx, hy, cell, _ = cp.patches(x_pad)
    px, py = s.finger.patch_m
    # the patches tile the lattice's extent
    assert np.isclose((4 * hx * hy).sum(), (cp.sx[-1] - cp.sx[0]) * (cp.sy[-1] - cp.sy[0]))
    assert cp.sx[-1] - cp.sx[0] >= px - 1e-12 and cp.sy[-1] - cp.sy[0] >= py - 1e-12
    # the plate's height is the same all over each patch (sampled just inside its corners)
    e = 1e-7
    z0 = surface_of(plate).height(cx + x_pad, cy)
    for sx in (-1, 1):
        for sy in (-1, 1):
            z = surface_of(plate).height(cx + x_pad + sx * (hx - e), cy + sy * (hy - e))
            np.testing.assert_array_equal(z, z0)
    # each patch lies in a taxel wholly or not at all
    pos, size = s.layout.positions, s.layout.sizes
    for t in range(s.layout.n):
        ox = np.clip(
            np.minimum(cx + hx, pos[t, 0] + size[t, 0] / 2)
            - np.maximum(cx - hx, pos[t, 0] - size[t, 0] / 2),
            0,
            None,
        )
        oy = np.clip(
            np.minimum(cy + hy, pos[t, 1] + size[t, 1] / 2)
            - np.maximum(cy - hy, pos[t, 1] - size[t, 1] / 2),
            0,
            None,
        )
        frac = ox * oy / (4 * hx * hy)
        assert np.all(np.isclose(frac, 0, atol=1e-9) | np.isclose(frac, 1, atol=1e-9)), t


def test_wall_lines_are_the_box_faces():
    xs, ys = surface_of(get_plate("finger7/bumps-4x4")).walls
    assert xs.size == 8 and ys.size == 8
    np.testing.assert_allclose(np.diff(xs)[::2], 2.5e-3)  # each bump 2.5 mm wide
    np.testing.assert_allclose(np.diff(xs)[1::2], 9e-3 - 2.5e-3)  # 9 mm pitch
    assert surface_of(get_plate("finger7/flat")).walls[0].size == 0
    # hemispheres have no walls
    assert surface_of(get_plate("multilayer3/hemispheres-6x6")).walls[0].size == 0


def _aligned_sensor() -> Sensor:
    """A 3x3 layout whose taxel edges (3 mm squares at 3 mm) lie on the 1 mm lattice's lines
    (odd count: lines at +-0.5, +-1.5, ... mm)."""
    base = get_sensor("grid3x3")
    layout = grid_layout("aligned3x3", 3, 3, 3e-3, 3e-3)
    return dataclasses.replace(base, name="aligned3x3", layout=layout)


def test_with_nothing_to_cut_the_patches_are_the_lattice_and_the_press_is_the_dense_one():
    s = _aligned_sensor()
    plate = get_plate("finger7/flat")
    grid = skin_grid(s.finger, 1e-3)
    cp = ClippedPatches(grid, s.finger, s.layout, plate, 0.0)
    cx, cy, hx, hy, cell, split = cp.patches(0.0)
    assert cx.size == grid.n and not split.any()
    order = np.lexsort((grid.xy[:, 0], grid.xy[:, 1]))
    np.testing.assert_allclose(np.column_stack([cx, cy]), grid.xy[order], atol=1e-15)
    (_, _, hx, hy, cell, _), cand, p, d = cp.solve(0.0, 1e-3, 1.0)
    got = cp.taxel_loads(cell[cand], p * 4 * hx[cand] * hy[cand])
    want = physics.taxel_loads(*physics.grid_press(plate, s.finger, 1.0, 0.0, "L1", 1e-3), s.layout)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    assert np.isclose(got.sum(), 9 * 9e-6 / 144e-6 * 1.0, rtol=0.5)  # sanity: a share of 1 N


def test_a_clipped_slide_with_nothing_to_cut_equals_the_whole_patch_slide():
    s = _aligned_sensor()
    proto = Protocol(duration_s=0.3)
    fid = choose_fidelity(get_plate("finger7/flat"), s.layout, s.finger, proto, "L1")
    step = StepOptions(path="per-step")  # the held steps themselves, not a table of either
    whole = simulate("finger7/flat", s, protocol=proto, fidelity=fid, ideal=True, options=step)
    clip = simulate(
        "finger7/flat",
        s,
        protocol=proto,
        fidelity=dataclasses.replace(fid, clipped=True),
        ideal=True,
        options=step,
    )
    assert "clipped" in clip.recording.meta["skin_problem"]
    assert clip.recording.meta["fidelity"]["clipped"] is True
    assert "clipped" not in whole.recording.meta["fidelity"]
    np.testing.assert_allclose(clip.recording.data, whole.recording.data, rtol=1e-6, atol=1e-9)


def test_identical_bumps_read_alike_and_the_slide_is_mirror_symmetric():
    s = get_sensor("grid3x3")
    plate = get_plate("finger7/bumps-4x4")
    proto = Protocol(duration_s=1.0, speed_m_s=0.06).at_rate(s.layout.rate_hz)
    fid = choose_fidelity(plate, s.layout, s.finger, proto, "auto", refine=False)
    assert fid.pitch_m == pytest.approx(1e-3)
    r = simulate(
        plate, s, protocol=proto, fidelity=dataclasses.replace(fid, clipped=True), ideal=True
    )
    y = r.recording.data.astype(float)
    centre = y[:, 7]  # the middle taxel of the row that meets the bumps
    pk, _ = find_peaks(centre, height=0.5 * centre.max(), distance=5)
    assert len(pk) == 4  # four bump columns pass
    peaks = centre[pk]
    assert peaks.max() / peaks.min() - 1 < SAME_BUMP_PEAKS, peaks
    # the plate is symmetric about x = 0: taxel 6's record is taxel 8's, reversed in x
    x = np.asarray(r.recording.meta["x_pad_m"])
    rev = np.interp(-x, x, y[:, 8])
    inside = np.abs(x) < 0.8 * np.abs(x).max()
    err = np.abs(y[inside, 6] - rev[inside]).max() / y[:, 6].max()
    assert err < 0.1, err


@pytest.mark.slow
def test_clipped_patches_come_close_to_tamaas_where_whole_ones_do_not():
    pytest.importorskip("tamaas")
    plate = get_plate("finger7/bumps-4x4")
    s = get_sensor("grid3x3")
    ref = physics.reference(plate, s, 1.0, 4)
    cp = ClippedPatches(skin_grid(s.finger, 1e-3), s.finger, s.layout, plate, 0.0)
    loads = []
    for off in ref.offsets_m:
        (_, _, hx, hy, cell, _), cand, p, _ = cp.solve(off, 1e-2, 1.0)
        loads.append(cp.taxel_loads(cell[cand], p * 4 * hx[cand] * hy[cand]))
    clipped, _ = ref.error(np.array(loads))
    whole, _ = ref.error(physics.configuration_loads(ref, plate, s, 1.0, "L1", 1e-3, None))
    assert clipped < CLIPPED_VS_TAMAAS, clipped
    assert whole > 4 * CLIPPED_VS_TAMAAS, whole
    # the stored row auto reads is this measurement
    row = me.expected_error(plate, s.layout, s.finger, 1.0, "L1", 1e-3, None, clipped=True)
    assert row is not None and row.clipped
    assert clipped == pytest.approx(row.error, abs=0.002)


def test_clipping_refuses_the_skins_it_does_not_serve():
    f = Finger()
    check_clippable("L1", f)
    with pytest.raises(ConfigError, match="level 'L0'"):
        check_clippable("L0", f)
    stack = Stack((Layer(4e-3, 3e5, 0.5),), backing="rigid")
    with pytest.raises(ConfigError, match="layered stack"):
        check_clippable("L1", f.layered(stack))
    with pytest.raises(ConfigError, match="skin_tractions"):
        check_clippable("L1", dataclasses.replace(f, friction=0.5, skin_tractions=True))
    with pytest.raises(ConfigError, match="dynamic force control"):
        check_clippable("L1", f, quasi_static=False)
