"""Three independent views of every preset agree: the analytic definition, the exported STL
(z-buffered) and what MuJoCo's collider sees (probed with mj_geomDistance / contacts)."""

from __future__ import annotations

import pytest

from sim_tactile.plates import get_plate, preset_names
from sim_tactile.plates.make.verify import compare_views
from sim_tactile.plates.read.presets import LONG_FAMILY

MM = 1e-3
#: The issue's tolerance between collision geometry and CAD, away from walls [m].
VIEW_TOL_M = 0.01 * MM
#: Roughness must hit its target Ra within 5% (the plates' stated accuracy, README).
RA_RTOL = 0.05

# Expected counts and peaks, written out from the papers and the preset table (not derived
# from the code under test).
EXPECTED_FEATURES = {
    "finger7/flat": 0,
    "finger7/ridges-2": 2,
    "finger7/ridges-4": 4,
    "finger7/ridges-8": 8,
    "finger7/bumps-3x3": 9,
    "finger7/bumps-4x4": 16,
    "finger7/bumps-6x6": 36,
    "multilayer3/flat": 0,
    "multilayer3/grating-9": 9,
    "multilayer3/hemispheres-6x6": 36,
    "textures20/flat": 0,
    "textures20/grating-1.5mm": 24,
    "textures20/grating-2.0mm": 18,
    "textures20/grating-2.5mm": 14,
    "textures20/grating-3.0mm": 12,
    "textures20/grating-4.0mm": 9,
    "textures20/grating-6.0mm": 6,
    "textures20/grating-3.0mm-low": 12,
    "textures20/grating-3.0mm-high": 12,
    "textures20/grating-3.0mm-draft30": 12,
    "textures20/grating-3.0mm-narrow": 12,
    "textures20/boxes-3.0mm": 144,
    "textures20/boxes-4.5mm": 64,
    "textures20/cylinders-3.0mm": 144,
    "textures20/cylinders-4.5mm": 64,
    "textures20/hemispheres-3.0mm": 144,
    "textures20/hemispheres-4.5mm": 64,
    "textures20/hemispheres-6.0mm": 36,
}
EXPECTED_PEAK_MM = {
    "finger7": 2.5,
    "multilayer3/grating-9": 1.0,
    "multilayer3/hemispheres-6x6": 2.0,
    "textures20/grating-3.0mm-low": 0.25,
    "textures20/grating-3.0mm-high": 1.0,
    "textures20/hemispheres-3.0mm": 0.75,
    "textures20/hemispheres-4.5mm": 1.0,
    "textures20/hemispheres-6.0mm": 1.5,
    "textures20": 0.5,
}
FEATURED = list(EXPECTED_FEATURES)
#: The long strips are their short plates extended (``tests/test_textures20_v2.py``); one of
#: them is built and compared here, the rest would only repeat it at many times the cost.
LONG = [n for n in preset_names() if n.startswith(LONG_FAMILY)]
ROUGH = [n for n in preset_names() if n not in EXPECTED_FEATURES and n not in LONG]
#: The plates the fast lane (``make check``) compares; the others run in ``make test``.
FAST = ("finger7/ridges-4", "multilayer3/grating-9", "roughness8/ra-50")


def _lanes(names: list[str]) -> list:
    return [n if n in FAST else pytest.param(n, marks=pytest.mark.slow) for n in names]


def _expected_peak(name: str) -> float:
    if name.endswith("/flat"):
        return 0.0
    for key in (name, name.split("/")[0]):
        if key in EXPECTED_PEAK_MM:
            return EXPECTED_PEAK_MM[key] * MM
    raise KeyError(name)


def test_every_preset_is_covered():
    assert sorted(FEATURED + ROUGH + LONG) == sorted(preset_names())
    assert len(ROUGH) == 10 and len(LONG) == 20


@pytest.mark.slow
def test_three_views_agree_on_a_long_strip(cache):
    """textures20-long/grating-3.0mm: 52 ridges of the 3 mm grating over 156 mm."""
    r = compare_views(get_plate(LONG_FAMILY + "grating-3.0mm"), cache=cache)
    assert r.counts == {"analytic": 52, "stl": 52, "collider": 52}
    for view, peak in r.peak_m.items():
        assert peak == pytest.approx(0.5 * MM, abs=VIEW_TOL_M), view
    for pair, diff in r.max_diff_m.items():
        assert diff <= VIEW_TOL_M, pair


@pytest.mark.parametrize("name", _lanes(FEATURED))
def test_three_views_agree_on_featured_plates(name, cache):
    r = compare_views(get_plate(name), cache=cache)
    expected = EXPECTED_FEATURES[name]
    assert r.counts == {"analytic": expected, "stl": expected, "collider": expected}
    for view, peak in r.peak_m.items():
        assert peak == pytest.approx(_expected_peak(name), abs=VIEW_TOL_M), view
    assert r.checked_fraction > 0.3  # a good part of the surface is away from walls
    for pair, diff in r.max_diff_m.items():
        assert diff <= VIEW_TOL_M, pair


@pytest.mark.parametrize("name", _lanes(ROUGH))
def test_three_views_agree_on_roughness(name, cache):
    plate = get_plate(name)
    r = compare_views(plate, cache=cache)
    for view in ("analytic", "analytic_min", "stl", "stl_min", "collider"):
        assert r.ra_m[view] == pytest.approx(plate.texture.ra_m, rel=RA_RTOL), view
    for pair, diff in r.max_diff_m.items():
        assert diff <= VIEW_TOL_M, pair
