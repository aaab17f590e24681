"""The half-space skin against an independent boundary-element solver (Tamaas, a test extra).

``perf/ref_halfspace_tamaas.py`` measures the node grid's error over several pad
offsets on two task scenes (the README's table); these tests pin the reference itself and
the agreement where the grid resolves the contact."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("tamaas")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "perf"))
import ref_halfspace_tamaas as ref  # noqa: E402

from sim_tactile.bench import physics  # noqa: E402
from sim_tactile.plates import get_plate  # noqa: E402
from sim_tactile.sensors import get_sensor  # noqa: E402
from sim_tactile.sim.static_press import hertz  # noqa: E402

#: Tamaas on Hertz's sphere (a 32 mm periodic cell at 0.0625 mm): its own discretisation
HERTZ_RTOL = 5e-3
#: that cell and its grid
HERTZ_CELL_M, HERTZ_CELL_N = 32e-3, 512
#: the project's half-space solve against Tamaas where a ridge lies under the taxel column
#: (pad offset 2.25 mm on finger7/ridges-4), in % of the largest taxel load: at the default
#: nodes and at 0.25 mm (measured: 4.2% and 6.3% at the surface against the reference with
#: its cell faces on the grid, since 0dbeee0; 1.7% and 1.1% before, when a row of cell
#: centres ran along the ridge's wall, which here is also the taxel's edge, and split the
#: wall's singular strip between the taxels)
RESOLVED_ATOL = 0.07
#: at 1 mm, 0.25 mm nodes against Tamaas (measured 4.9%; 3.8% before 0dbeee0)
DEEP_FINE_ATOL = 0.06


@pytest.mark.slow
def test_tamaas_reproduces_hertz():
    """The reference itself: a paraboloid (R 8 mm) at 1 N on the 64 mm cell."""
    import tamaas as tm

    tm.set_log_level(tm.LogLevel.warning)
    n, L, R, E = HERTZ_CELL_N, HERTZ_CELL_M, 8e-3, 0.3e6
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [L, L], [n, n])
    model.E, model.nu = E, 0.5
    x = (np.arange(n) - n // 2) * L / n
    X, Y = np.meshgrid(x, x, indexing="ij")
    solver = tm.PolonskyKeerRey(
        model,
        -(X**2 + Y**2) / (2 * R),
        1e-12,
        tm.PolonskyKeerRey.pressure,
        tm.PolonskyKeerRey.pressure,
    )
    solver.solve(ref.FORCE_N / L**2)
    p = np.asarray(model.traction).ravel()
    h = hertz(R, E / 0.75, ref.FORCE_N)
    assert p.sum() * (L / n) ** 2 == pytest.approx(ref.FORCE_N, rel=1e-9)
    assert p.max() == pytest.approx(h["peak_pressure_pa"], rel=HERTZ_RTOL)
    a = np.sqrt(np.count_nonzero(p) * (L / n) ** 2 / np.pi)
    assert a == pytest.approx(h["contact_radius_m"], rel=HERTZ_RTOL)


@pytest.fixture(scope="module")
def resolved_ridge():
    """Tamaas's taxel loads with a ridge under the taxel column at x = +2.5 mm (the pad
    2.25 mm off centre on finger7/ridges-4), at the surface and 1 mm deep."""
    plate = get_plate("finger7/ridges-4")
    s = get_sensor("grid3x3")
    fine = physics.tamaas_press(plate, s.finger, ref.FORCE_N, 2.25e-3, physics.REF_SPACING_M)
    want = {d: physics.taxel_loads(*fine, s.layout, d) for d in (0.0, 1e-3)}
    got = {}
    for grid, (px, py) in ref.NODE_GRIDS.items():
        xy, p, qx, qy = physics.grid_press(plate, s.finger, ref.FORCE_N, 2.25e-3, "L1", px, py)
        got[grid] = {d: physics.taxel_loads(xy, p, qx, qy, s.layout, d) for d in want}
    return want, got


@pytest.mark.slow
def test_the_half_space_solve_agrees_with_tamaas_where_the_grid_resolves_the_ridge(
    resolved_ridge,
):
    """At the surface both grids read the ridge's load within 7% (its walls lie on the
    taxels' edges, the worst place for whole patches). At 1 mm the taxel beside the ridge
    feels the pressure concentrated at the ridge's edge, which the default nodes smear
    (measured: 10.0% off); 0.25 mm nodes come within 6% (4.9%)."""
    want, got = resolved_ridge
    scale = want[0.0].max()
    for grid in ref.NODE_GRIDS:
        np.testing.assert_allclose(got[grid][0.0], want[0.0], atol=RESOLVED_ATOL * scale)
    deep = {g: np.abs(got[g][1e-3] - want[1e-3]).max() / want[1e-3].max() for g in got}
    assert deep["0.25 x 0.25 mm"] < DEEP_FINE_ATOL
    assert deep["0.25 x 0.25 mm"] < deep["default 0.5 x 2 mm"]
