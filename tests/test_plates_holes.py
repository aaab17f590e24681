"""A plate has material wherever its part has: an off-centre part, a part's edges and the
project's own exported STL come back without NaN inside the part's outline (beyond it, the
plate's flat base); a hole through a part, or NaN in a map, is refused saying where, unless
``holes=true`` marks it intended; the preview draws the map, its holes, and flat maps."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
import trimesh

from sim_tactile.cache import ArtefactCache
from sim_tactile.errors import ConfigError
from sim_tactile.plates import build, surface_of
from sim_tactile.plates.define.spec import HeightMap, Plate
from sim_tactile.plates.make import map_mesh
from sim_tactile.plates.make.render import HOLE_RGB, preview_png
from sim_tactile.plates.parts.user import load_user_plate, parse_ref

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "own_sensor_and_plates"
#: Heights read back from an STL whose vertices are the samples: its vertices are float32,
#: so a node 50 mm out moves by up to 3.7e-9 m (in mm or in m), and on the steepest slope
#: of the test maps (2.5: a 0.5 mm block's wall over a 0.2 mm sample) its height by 1e-8 m.
READBACK_TOL_M = 2e-8
PIXEL_M = 2e-4  # coarse enough that the exported STL keeps every sample (MAX_STL_CELLS)


def _npy(tmp_path: Path, z: np.ndarray, name="map.npy") -> Path:
    path = tmp_path / name
    np.save(path, z)
    return path


def _block_map() -> np.ndarray:
    """20 x 20 mm every 0.2 mm: a 0.5 mm block from x = 4 to 8 mm, y = -1 to 1 mm (centred
    on a sample: x = 6 mm, y = 0), in the map's +x half."""
    z = np.zeros((101, 101))
    z[45:56, 70:91] = 5e-4
    return z


def _stl_of(plate: Plate, path: Path, scale: float = 1.0) -> Path:
    """The project's own STL export of ``plate`` [mm], written ``scale`` times larger."""
    mesh = trimesh.load(io.BytesIO(map_mesh.stl_bytes(plate)), file_type="stl")
    mesh.apply_scale(scale)
    path.write_bytes(trimesh.exchange.stl.export_stl(mesh))
    return path


@pytest.mark.parametrize("units", ["mm", "m"])
def test_an_off_centre_part_exported_and_imported_again_has_material_everywhere(tmp_path, units):
    """The project's STL of a map plate whose block sits off-centre: the part reimported is
    centred on the block, its grid reaches past the part on +x (there the base, z = 0), and
    every sample of the part's footprint is the original's height."""
    plate = load_user_plate(_npy(tmp_path, _block_map()), pixel_m=PIXEL_M)
    assert (
        map_mesh.stride(
            (round(plate.width_m / PIXEL_M) + 1, round(plate.length_m / PIXEL_M) + 1),
            map_mesh.MAX_STL_CELLS,
        )
        == 1
    )
    scale = 1e-3 if units == "m" else 1.0
    stl = _stl_of(plate, tmp_path / f"part-{units}.stl", scale)
    back = load_user_plate(f"{stl}?units={units}&pixel_m={PIXEL_M}")
    t = back.texture
    assert not np.isnan(t.z).any()
    assert any("beyond the part on its +x side" in n and "z = 0" in n for n in t.notes)
    # the back plate is centred on the block (6 mm, 0 in the part's frame)
    xs, ys = t.grid()
    X, Y = np.meshgrid(xs + 6e-3, ys)
    on_part = (np.abs(X) <= plate.length_m / 2 - 1e-9) & (np.abs(Y) <= plate.width_m / 2 - 1e-9)
    want = np.where(on_part, surface_of(plate).height(X, Y), 0.0)
    assert on_part.mean() > 0.8
    assert np.max(np.abs(t.z - want)) <= READBACK_TOL_M
    # height_at reads material over the whole part, never NaN inside its footprint
    rng = np.random.default_rng(0)
    px = rng.uniform(-plate.length_m / 2, plate.length_m / 2, 20000) - 6e-3
    py = rng.uniform(-plate.width_m / 2, plate.width_m / 2, 20000)
    assert np.isfinite(surface_of(back).height(px, py)).all()


@pytest.mark.slow
def test_the_exported_stl_of_a_map_plate_comes_back_as_the_same_surface(tmp_path):
    x = np.arange(151) * PIXEL_M
    z = 2e-4 * (1 + np.sin(2 * np.pi * x / 2e-3))[None, :] * np.ones((51, 1))
    plate = load_user_plate(_npy(tmp_path, z), pixel_m=PIXEL_M)
    for units, scale in (("mm", 1.0), ("m", 1e-3)):
        stl = _stl_of(plate, tmp_path / f"plate-{units}.stl", scale)
        back = load_user_plate(f"{stl}?units={units}&pixel_m={PIXEL_M}")
        t = back.texture
        assert not np.isnan(t.z).any(), units
        xs, ys = t.grid()
        X, Y = np.meshgrid(xs, ys)
        on_part = (np.abs(X) <= plate.length_m / 2) & (np.abs(Y) <= plate.width_m / 2)
        assert np.max(np.abs(t.z - np.where(on_part, surface_of(plate).height(X, Y), 0.0))) <= (
            READBACK_TOL_M
        )


def _ring_stl(tmp_path: Path) -> Path:
    """A ring (a through-hole of 5 mm radius in a disc of 10 mm, 3 mm thick), in mm."""
    ring = trimesh.creation.annulus(5.0, 10.0, 3.0)
    path = tmp_path / "ring.stl"
    path.write_bytes(trimesh.exchange.stl.export_stl(ring))
    return path


def test_a_hole_through_a_part_is_refused_saying_where_unless_intended(tmp_path):
    stl = _ring_stl(tmp_path)
    with pytest.raises(ConfigError) as exc:
        load_user_plate(stl)
    msg = str(exc.value)
    for w in ["holes through it", "samples without material", "x = 0.000 mm, y = 0.000 mm"]:
        assert w in msg, (w, msg)
    assert "pass holes=true" in msg and str(stl.name) in msg
    plate = load_user_plate(f"{stl}?holes=true")
    z = plate.texture.z
    n_hole = int(np.isnan(z).sum())
    assert n_hole == pytest.approx(np.pi * 5e-3**2 / 5e-5**2, rel=0.02)
    assert any("kept as holes (holes=true)" in n for n in plate.texture.notes)
    assert (
        np.isnan(surface_of(plate).height(0.0, 0.0))
        and surface_of(plate).height(7.5e-3, 0.0) == 0.0
    )
    # the corners of the disc's square: beyond its outline, the base
    assert surface_of(plate).height(9.9e-3, 9.9e-3) == 0.0


def test_nan_in_a_map_is_refused_with_where_it_lies_unless_holes_are_intended(tmp_path):
    z = np.full((51, 101), 1e-4)
    z[30:40, 75:95] = np.nan  # 200 samples around x = 6.9 mm, y = 1.9 mm
    path = _npy(tmp_path, z)
    with pytest.raises(ConfigError) as exc:
        load_user_plate(path, pixel_m=PIXEL_M)
    msg = str(exc.value)
    for w in ["200 samples without material (NaN)", "x = 6.900 mm, y = 1.900 mm", "holes=true"]:
        assert w in msg, (w, msg)
    plate = load_user_plate(path, pixel_m=PIXEL_M, holes=True)
    assert int(np.isnan(plate.texture.z).sum()) == 200
    assert any("kept as holes" in n for n in plate.texture.notes)
    # the holes are the plate's identity: the same map without them is another plate
    z[np.isnan(z)] = 1e-4
    whole = load_user_plate(_npy(tmp_path, z, "whole.npy"), pixel_m=PIXEL_M, holes=True)
    assert whole.hash != plate.hash and not whole.texture.notes[:-1]
    # the option in a reference, in --plate-frame and in a configuration's plate table
    assert parse_ref(f"{path}?pixel_m=0.0001&holes=true").holes
    assert "holes=true" in parse_ref(path.name, holes="true").ref()
    from sim_tactile.cli._common import plate_of

    assert parse_ref(plate_of(str(path), "pixel_m=2e-4,holes=true")).holes
    with pytest.raises(ConfigError, match="holes = 'maybe' is not valid; valid: true or false"):
        parse_ref(f"{path}?holes=maybe")


def test_a_configuration_table_marks_a_map_s_holes(tmp_path):
    from sim_tactile.slides.config import config_slide_set

    z = np.full((51, 101), 1e-4)
    z[30:40, 75:95] = np.nan
    _npy(tmp_path, z)
    table = {"file": "map.npy", "pixel_m": PIXEL_M}
    cfg = {"plates": [table, "finger7/flat"], "sensor": "grid3x3", "slides_per_plate": 2}
    with pytest.raises(ConfigError, match="holes=true"):
        config_slide_set(cfg, base_dir=tmp_path)
    cfg["plates"][0] = {**table, "holes": True}
    ss, _, _ = config_slide_set(cfg, base_dir=tmp_path)
    assert "holes=true" in ss.plates[0]


def _png_pixels(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def _has_hole_colour(rgb: np.ndarray) -> int:
    want = np.round(np.asarray(HOLE_RGB) * 255)
    return int((np.abs(rgb.astype(float) - want).max(axis=-1) <= 2).sum())


def test_the_preview_shows_a_map_its_holes_and_flat_maps(tmp_path):
    z = _block_map()
    z[10:20, 10:20] = np.nan
    holed = load_user_plate(_npy(tmp_path, z), pixel_m=PIXEL_M, holes=True)
    rgb = _png_pixels(preview_png(holed))
    assert _has_hole_colour(rgb) > 50  # drawn in its own colour
    assert len(np.unique(rgb.reshape(-1, 3), axis=0)) > 100  # the panel is not blank
    whole = load_user_plate(_npy(tmp_path, _block_map(), "whole.npy"), pixel_m=PIXEL_M)
    assert _has_hole_colour(_png_pixels(preview_png(whole))) == 0
    for level in (0.0, 2e-4):  # flat, and constant above the base
        flat = Plate(
            HeightMap(np.full((50, 60), level), PIXEL_M), 0.02, 0.01, 0.005, 0.0059, 0.0049
        )
        assert _png_pixels(preview_png(flat)).shape[2] == 3
    # plates build makes the preview of a plate with holes
    res = build(holed, kinds=("png",), cache=ArtefactCache(tmp_path / "cache"))
    assert res.files["png"].stat().st_size > 10_000


@pytest.mark.slow
@pytest.mark.parametrize("function", ["knurl", "chevron"])
def test_the_worked_example_parts_have_material_over_their_footprint(function):
    pytest.importorskip("cadquery")
    plate = load_user_plate(f"textures.py:{function}", base_dir=EXAMPLE)
    assert not np.isnan(plate.texture.z).any()
    rng = np.random.default_rng(1)
    x = rng.uniform(-0.018, 0.018, 20000)  # the part: 36 mm square
    y = rng.uniform(-0.018, 0.018, 20000)
    assert np.isfinite(surface_of(plate).height(x, y)).all()


PINS = """
import cadquery as cq

def pins():
    # a 40 x 20 mm base, its pins in the +x half only
    w = cq.Workplane("XY").box(40, 20, 3, centered=(True, True, False)).translate((0, 0, -3))
    pts = [(x, y) for x in (6, 10, 14) for y in (-5, 0, 5)]
    return w.union(cq.Workplane("XY").pushPoints(pts).circle(1.0).extrude(0.5))

def holed():
    return pins().cut(cq.Workplane("XY").circle(1.5).extrude(10).translate((-12, 0, -5)))
"""


@pytest.mark.slow
def test_an_off_centre_cadquery_part_and_its_hole(tmp_path):
    """The user's case: pins on one half of a base. The map (centred on the pins) covers the
    whole base with material, and reaches past it on +x, where the base is the surface."""
    pytest.importorskip("cadquery")
    (tmp_path / "pins.py").write_text(PINS)
    plate = load_user_plate(tmp_path / "pins.py:pins")
    assert not np.isnan(plate.texture.z).any()
    assert any("beyond the part on its +x side" in n for n in plate.texture.notes)
    # the base (40 x 20 mm, centred 10 mm to -x of the pins' centre) reads 0, the pins 0.5 mm
    rng = np.random.default_rng(2)
    x = rng.uniform(-0.030, 0.010, 20000)
    y = rng.uniform(-0.0099, 0.0099, 20000)
    z = surface_of(plate).height(x, y)
    assert np.isfinite(z).all() and z.min() >= -1e-12 and z.max() <= 5e-4 + 1e-12
    assert surface_of(plate).height(0.0, 0.0) == pytest.approx(5e-4)  # the middle pin
    with pytest.raises(ConfigError, match=r"holes through it.*x = -22.0\d\d mm, y = 0.000 mm"):
        load_user_plate(tmp_path / "pins.py:holed")
