"""One surface per kind of texture: the plate answers its own geometry (its height, the
kernels' arrays, its scales, its collider margin), and nothing outside the plate's definition
(plates/define/) asks the texture its kind: not the simulator, not the plate's artefacts."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import numpy as np
import pytest

import sim_tactile
from sim_tactile.plates import Plate, get_plate, surface_of
from sim_tactile.plates.define.spec import Grating
from sim_tactile.plates.define.surface import (
    QS_MARGIN_M,
    QS_MARGIN_MUJOCO_M,
    FeatureSurface,
    MapArrays,
    MapSurface,
    ProfileArrays,
    ProfileSurface,
    samples_apart,
)
from sim_tactile.sim.plan.lattices import SOLO_PERIOD_M, period_of

ROOT = Path(sim_tactile.__file__).parent

#: A switch on the texture's kind: its ``kind`` read, an ``isinstance`` of the texture or of
#: a texture class, or a kind's name compared.
_SWITCH = re.compile(
    r"texture\.kind\b"
    r"|isinstance\([^)]*\btexture\b"
    r"|isinstance\([^)]*\b(Flat|Ridges|Grating|Bumps|Roughness|HeightMap)\b"
    # a kind's name compared ("flat" is a pad's shape too: not counted)
    r"|[=!]=\s*[\"'](ridges|grating|bumps|roughness|heightmap)[\"']"
)


def _switches(root: Path) -> list[str]:
    """The lines of ``root``'s modules outside plates/define/ that switch on the texture's
    kind."""
    out = []
    for p in sorted(root.rglob("*.py")):
        rel = p.relative_to(root).as_posix()
        if rel.startswith("plates/define/"):
            continue
        for n, line in enumerate(p.read_text().splitlines(), 1):
            if _SWITCH.search(line.split("#")[0]):
                out.append(f"{rel}:{n}: {line.strip()}")
    return out


def test_nothing_outside_the_definition_switches_on_the_texture_kind():
    assert _switches(ROOT) == []


def test_the_switch_finder_finds_each_form(tmp_path):
    lines = [
        'if plate.texture.kind == "roughness":',
        "if isinstance(plate.texture, Roughness):",
        "ok = isinstance(t, HeightMap)",
        'if params["kind"] != "heightmap":',
        "z = surface_of(plate).height(x, y)  # texture.kind no longer read",
    ]
    (tmp_path / "sim").mkdir()
    (tmp_path / "sim" / "m.py").write_text("\n".join(lines) + "\n")
    (tmp_path / "plates" / "define").mkdir(parents=True)
    (tmp_path / "plates" / "define" / "spec.py").write_text(lines[0] + "\n")  # define/ may
    (tmp_path / "plates" / "make").mkdir()
    (tmp_path / "plates" / "make" / "mjcf.py").write_text(lines[1] + "\n")  # make/ may not
    found = [s.split(":")[:2] for s in _switches(tmp_path)]
    assert found == [["plates/make/mjcf.py", "1"]] + [["sim/m.py", n] for n in "1234"]


@pytest.mark.parametrize(
    ("name", "kind", "margin"),
    [
        ("finger7/bumps-4x4", FeatureSurface, QS_MARGIN_M),
        ("finger7/flat", FeatureSurface, QS_MARGIN_M),
        ("roughness8/ra-50", ProfileSurface, QS_MARGIN_MUJOCO_M),
    ],
)
def test_each_kind_has_its_surface_and_margin(name, kind, margin):
    s = surface_of(get_plate(name))
    assert type(s) is kind and s.margin_m == margin
    assert (s.arrays is None) == (kind is FeatureSurface)
    assert isinstance(s.arrays, ProfileArrays) == (kind is ProfileSurface)
    assert (s.profile is not None) == (s.ra_m is not None) == (kind is ProfileSurface)


def _map_plate() -> Plate:
    """A height-map grating: 1 mm ridges every 2 mm, NaN holes in one corner."""
    pixel = 0.1e-3
    xs = (np.arange(361) - 180) * pixel
    z = np.where((np.floor(xs / 1e-3) % 2) == 0, 0.4e-3, 0.0)[None, :] * np.ones((361, 1))
    z[:5, :5] = np.nan
    from sim_tactile.plates import HeightMap

    return Plate(texture=HeightMap(z, pixel), area_length_m=0.036, area_width_m=0.036)


def test_a_height_map_has_its_samples_arrays_and_scales():
    plate = _map_plate()
    s = surface_of(plate)
    assert type(s) is MapSurface and isinstance(s.arrays, MapArrays)
    assert s.margin_m == QS_MARGIN_M and s.features == () and not s.has_walls
    assert s.feature_scale_m == pytest.approx(1e-3) and s.period_m == pytest.approx(2e-3)
    ((sha, z),) = s.map_samples().items()
    assert sha == plate.texture.sha256 and z is plate.texture.z
    assert samples_apart(plate.params()) and not samples_apart(get_plate("finger7/flat").params())


@pytest.mark.parametrize("name", ["finger7/bumps-4x4", "multilayer3/hemispheres-6x6", "map"])
def test_the_height_near_the_pad_is_the_whole_height(name):
    """A plate of features looks at the features within reach of the pad only: the same
    numbers as over all of them, where the points lie within the reach."""
    plate = _map_plate() if name == "map" else get_plate(name)
    s = surface_of(plate)
    rng = np.random.default_rng(5)
    for x_c in rng.uniform(-0.06, 0.06, 20):
        x = x_c + rng.uniform(-8e-3, 8e-3, 400)
        y = rng.uniform(-0.02, 0.02, 400)
        whole = s.height(x, y)
        near = s.height(x, y, near=(x_c, 8e-3))
        assert near.tobytes() == whole.tobytes()
        assert whole.tobytes() == surface_of(plate).height(x, y).tobytes()


def test_the_period_has_one_formula():
    """The planner's texture period, the anchored lattice's and the speed-error benchmark's
    are the surface's: the features' smallest column spacing."""
    ridges = get_plate("finger7/ridges-4")
    xs = sorted({round(f.x, 9) for f in surface_of(ridges).features})
    assert surface_of(ridges).period_m == pytest.approx(min(np.diff(xs))) == period_of(ridges)
    one = Plate(texture=Grating(period_m=30e-3, height_m=0.5e-3), area_length_m=0.036)
    assert surface_of(one).period_m is None and period_of(one) == SOLO_PERIOD_M
    assert surface_of(get_plate("roughness8/ra-50")).period_m is None


def test_the_features_are_computed_once_a_plate():
    """A plate's feature list is kept with its surface: asked again (by the planner, the
    lattices, the colliders) it is not expanded again, and every caller gets the one tuple."""
    plate = get_plate("finger7/bumps-6x6")
    calls = []
    texture = plate.texture
    original = type(texture).features

    class Counting(type(texture)):
        def features(self, *a):
            calls.append(1)
            return original(self, *a)

    from dataclasses import fields

    counted = Counting(**{f.name: getattr(texture, f.name) for f in fields(texture) if f.init})
    p = Plate(texture=counted, area_length_m=plate.area_length_m, area_width_m=plate.area_width_m)
    n = len(calls)  # the plate's own validation expands them once
    a, b = surface_of(p).features, surface_of(p).features
    surface_of(p).walls, surface_of(p).feature_scale_m, surface_of(p).period_m  # noqa: B018
    assert len(calls) == n + 1 and a is b and isinstance(a, tuple) and len(a) == 36


def test_the_old_facade_warns_and_answers_as_the_surface():
    """``features``, ``height_at`` and ``roughness_profile`` (deprecated for one release) say
    what replaces them and give the surface's own answers."""
    facade = importlib.import_module("sim_tactile.plates.features")  # the package's `features`
    # attribute is the function, as before

    ridges, rough = get_plate("finger7/ridges-4"), get_plate("roughness8/ra-50")
    x = np.linspace(-0.02, 0.02, 101)
    with pytest.warns(DeprecationWarning, match=r"surface_of\(plate\)\.height\(x, y\)"):
        z = facade.height_at(ridges, x, 0.0)
    assert z.tobytes() == surface_of(ridges).height(x, 0.0).tobytes()
    with pytest.warns(DeprecationWarning, match=r"surface_of\(plate\)\.features"):
        assert facade.features(ridges) == list(surface_of(ridges).features)
    with pytest.warns(DeprecationWarning, match=r"surface_of\(plate\)\.profile"):
        assert facade.roughness_profile(rough) is surface_of(rough).profile


@pytest.mark.parametrize(
    ("plate", "caps"),
    [
        ("textures20/hemispheres-6.0mm", True),
        ("multilayer3/hemispheres-6x6", True),
        ("textures20/cylinders-4.5mm", False),
        ("textures20/boxes-4.5mm", False),
        ("textures20/grating-4.0mm", False),
        ("textures20/flat", False),
        ("textures20/rough-ra25", False),
    ],
)
def test_a_plate_of_hemispheres_says_its_relief_is_caps_alone(plate, caps):
    """``all_caps``: every feature a spherical cap, no vertical wall (what ``auto`` reads to
    solve a flat pad's dear problem at every 2nd step)."""
    assert surface_of(get_plate(plate)).all_caps is caps
