"""Plate definitions: presets, validation messages, hashing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim_tactile.errors import ConfigError, UnknownNameError
from sim_tactile.plates import (
    Bumps,
    Flat,
    Grating,
    Plate,
    Ridges,
    Roughness,
    build,
    get_plate,
    preset_names,
    surface_of,
)
from sim_tactile.plates.define.spec import MAX_FEATURE_HEIGHT_M

MM = 1e-3


def test_contract_names_exist():
    names = set(preset_names())
    required = {
        "finger7/flat",
        "finger7/ridges-2",
        "finger7/ridges-4",
        "finger7/ridges-8",
        "finger7/bumps-3x3",
        "finger7/bumps-4x4",
        "finger7/bumps-6x6",
        "multilayer3/flat",
        "multilayer3/grating-9",
        "multilayer3/hemispheres-6x6",
    } | {f"roughness8/ra-{r}" for r in ("50", "25", "12.5", "6.3", "3.2", "1.6", "0.8", "0.4")}
    assert required <= names
    assert len([n for n in names if n.startswith("textures20/")]) == 20


def test_finger7_dimensions_match_the_paper():
    p = get_plate("finger7/ridges-4")
    assert (p.length_m, p.width_m, p.area_length_m, p.area_width_m) == (0.108, 0.036, 0.036, 0.036)
    xs = [f.x for f in surface_of(p).features]
    # 4 ridges evenly spread over 36 mm: pitch 9 mm (docs/physics.md: pulses 150 ms apart at 60 mm/s)
    assert np.allclose(np.diff(xs), 9 * MM)
    assert math.isclose(surface_of(p).height(xs[0], 0.0), 2.5 * MM)


def test_multilayer_grating_geometry():
    p = get_plate("multilayer3/grating-9")
    fs = surface_of(p).features
    assert len(fs) == 9
    assert np.allclose(np.diff([f.x for f in fs]), 4 * MM)  # 2 mm ridges, 2 mm apart
    f = fs[0]
    # 30 degree draft from vertical: top half-width = 1 mm - 1 mm * tan(30)
    assert math.isclose(f.top_hx, 1 * MM - 1 * MM * math.tan(math.radians(30)))


def test_hash_is_canonical_and_name_free():
    a = Plate(texture=Ridges(count=4, width_m=2.5e-3, height_m=2.5e-3), name="a")
    b = Plate(texture=Ridges(count=4, width_m=0.0025, height_m=0.0025), name="b")
    c = Plate(texture=Ridges(count=4, width_m=0.0025, height_m=0.0026))
    assert a.hash == b.hash == get_plate("finger7/ridges-4").hash
    assert a.hash != c.hash
    assert Plate.from_params(a.params()).hash == a.hash


def test_roughness_profile_hits_ra_and_is_seeded():
    for name in ("roughness8/ra-50", "roughness8/ra-0.4"):
        p = get_plate(name)
        ra = p.texture.ra_m
        xs = np.linspace(-0.0179, 0.0179, 20001)
        z = surface_of(p).height(xs, 0.0)
        assert abs(np.mean(np.abs(z - z.mean())) / ra - 1) < 0.05
    r1 = Plate(texture=Roughness(ra_m=1e-5, corr_length_m=1e-4, seed=1))
    r2 = Plate(texture=Roughness(ra_m=1e-5, corr_length_m=1e-4, seed=2))
    assert not np.array_equal(surface_of(r1).height(xs, 0), surface_of(r2).height(xs, 0))


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (
            lambda: Ridges(count=4, width_m=-1e-3, height_m=1e-3),
            ["ridges.width_m", "-0.001", "valid"],
        ),
        (lambda: Ridges(count=0, width_m=1e-3, height_m=1e-3), ["ridges.count", "0", "[1,"]),
        (lambda: Ridges(count=4, width_m=1e-3, height_m=0.0), ["ridges.height_m", "0", "valid"]),
        (
            lambda: Ridges(count=4, width_m=1e-3, height_m=0.02),
            ["ridges.height_m", "0.02", f"{MAX_FEATURE_HEIGHT_M:g}"],
        ),
        (
            lambda: Ridges(count=4, width_m=1e-3, height_m=1e-3, draft_deg=40),
            ["ridges.draft_deg", "40", "valid"],
        ),
        (
            lambda: Bumps(rows=2, cols=2, shape="hemisphere", size_m=2e-3, height_m=1.5e-3),
            ["bumps.height_m", "0.0015", "0.001"],
        ),
        (
            lambda: Bumps(rows=2, cols=2, shape="star", size_m=2e-3, height_m=1e-3),
            ["bumps.shape", "'star'", "hemisphere"],
        ),
        (
            lambda: Bumps(rows=2, cols=2, shape="box", size_m=2e-3, height_m=1e-3, spacing_m=1e-3),
            ["spacing_m", "overlap"],
        ),
        (
            lambda: Grating(period_m=2e-3, height_m=1e-3, duty=1.2),
            ["grating.duty", "1.2", "(0, 1)"],
        ),
        (lambda: Roughness(ra_m=-1e-6, corr_length_m=1e-4), ["roughness.ra_m", "-1e-06", "valid"]),
        (lambda: Plate(texture=Flat(), length_m=0.0), ["plate.length_m", "0", "valid"]),
        (
            lambda: Plate(texture=Ridges(count=20, width_m=2.5e-3, height_m=1e-3)),
            ["overlap", "20 ridges"],
        ),
        (
            lambda: Plate(
                texture=Bumps(
                    rows=6, cols=6, shape="box", size_m=3e-3, height_m=1e-3, spacing_m=7e-3
                )
            ),
            ["leaves the textured area"],
        ),
        (
            lambda: Plate(texture=Ridges(count=2, width_m=1e-3, height_m=1e-3, length_m=0.05)),
            ["ridges.length_m", "leaves"],
        ),
        (lambda: Plate(texture=Flat(), area_length_m=0.2), ["plate.area_length_m", "0.2", "0.108"]),
    ],
)
def test_bad_input_names_parameter_value_and_range(make, words):
    with pytest.raises(ConfigError) as exc:
        make()
    msg = str(exc.value)
    for w in words:
        assert w in msg, f"{w!r} not in {msg!r}"


def test_unknown_preset_is_a_clear_error():
    with pytest.raises(UnknownNameError, match="'finger7/ridges-5' is not a preset"):
        get_plate("finger7/ridges-5")


def test_bad_input_leaves_the_cache_untouched(cache_dir, tmp_path):
    from sim_tactile.cache import ArtefactCache

    c = ArtefactCache(tmp_path / "c")
    build("finger7/ridges-2", kinds=("mjcf",), cache=c)
    before = sorted((p.name, p.stat().st_size) for p in c.root.rglob("*"))
    with pytest.raises(ConfigError):
        build(
            Plate.from_params(
                {"texture": {"kind": "ridges", "count": 3, "width_m": -1, "height_m": 1e-3}}
            ),
            cache=c,
        )
    with pytest.raises(UnknownNameError):
        build("finger7/nope", cache=c)
    with pytest.raises(ConfigError):
        build("finger7/ridges-2", kinds=("obj",), cache=c)
    assert sorted((p.name, p.stat().st_size) for p in c.root.rglob("*")) == before


def test_from_params_rejects_unknown_fields():
    with pytest.raises(ConfigError, match="texture.kind"):
        Plate.from_params({"texture": {"kind": "waves"}})
    with pytest.raises(ConfigError, match="unexpected keyword"):
        Plate.from_params({"texture": {"kind": "flat", "wobble": 1}})


def test_the_old_module_names_still_import_with_a_warning():
    """For one release every module's name from before the four folders imports (its names
    are the new module's, read with a DeprecationWarning naming the new path), without
    loading what the old module did not (MuJoCo for ``mjcf``) until used, and without
    shadowing the package's functions of the same name (``build``)."""
    import importlib
    import subprocess
    import sys

    import sim_tactile.plates as plates
    from sim_tactile.plates import _moved
    from sim_tactile.plates.define import spec
    from sim_tactile.plates.make import build as build_module

    assert len(_moved.MOVED) == 19
    for old, folder in _moved.MOVED.items():
        new = importlib.import_module(f"sim_tactile.plates.{folder}.{old}")
        stand_in = importlib.import_module(f"sim_tactile.plates.{old}")
        name = next(n for n in vars(new) if not n.startswith("_"))
        with pytest.warns(DeprecationWarning, match=rf"plates\.{folder}\.{old}\b"):
            assert getattr(stand_in, name) is getattr(new, name)
    with pytest.warns(DeprecationWarning, match="plates.define.spec"):
        from sim_tactile.plates.spec import Plate as OldPlate
    assert OldPlate is spec.Plate is Plate
    with pytest.warns(DeprecationWarning):
        from sim_tactile.plates.build import artefact_key
    assert artefact_key is build_module.artefact_key and plates.build is build
    with pytest.raises(AttributeError, match="no_such_module"):
        plates.no_such_module  # noqa: B018
    code = "import sys, sim_tactile.plates.mjcf as m; print('mujoco' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
