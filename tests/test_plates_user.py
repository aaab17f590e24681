"""Plates from a user's files (sim_tactile.plates.parts.user): a STEP and an STL written by CadQuery
here, a CadQuery script, a .npy and a 16-bit PNG height map; each checked against the CAD it
came from, placed, cached by content; and the bad inputs the issue names refused, with
nothing written."""

from __future__ import annotations

import io
import os
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from sim_tactile.cache import ArtefactCache
from sim_tactile.errors import ConfigError
from sim_tactile.plates import build, get_plate, surface_of
from sim_tactile.plates.parts.user import RUN_IN_M, load_user_plate, parse_ref

cq = pytest.importorskip("cadquery")

#: the test grating [mm]: 6 ridges 1 mm wide, 0.5 mm high, 16 mm long, at a 3 mm pitch, on a
#: 40 x 20 x 3 mm base
PITCH, WIDTH, HEIGHT, N = 3.0, 1.0, 0.5, 6


def grating_solid(pitch=PITCH, width=WIDTH, height=HEIGHT, n=N):
    w = cq.Workplane("XY").box(40, 20, 3, centered=(True, True, False)).translate((0, 0, -3))
    for i in range(n):
        x = -n * pitch / 2 + (i + 0.5) * pitch
        ridge = cq.Workplane("XY").box(width, 16, height, centered=(True, True, False))
        w = w.union(ridge.translate((x, 0, 0)))
    return w


def grating_height_m(x_m, y_m, pitch=PITCH, width=WIDTH, height=HEIGHT, n=N):
    """The test grating's top surface [m], in the plate frame (its texture centred)."""
    x, y = np.asarray(x_m) * 1e3, np.asarray(y_m) * 1e3
    centres = -n * pitch / 2 + (np.arange(n) + 0.5) * pitch
    on = (np.abs(x[..., None] - centres) <= width / 2).any(-1) & (np.abs(y) <= 8)
    return np.where(on, height * 1e-3, 0.0)


SCRIPT = textwrap.dedent(
    """
    import cadquery as cq

    def plate():
        w = cq.Workplane("XY").box(40, 20, 3, centered=(True, True, False)).translate((0, 0, -3))
        for i in range(6):
            x = -9.0 + (i + 0.5) * 3.0
            ridge = cq.Workplane("XY").box(1.0, 16, 0.5, centered=(True, True, False))
            w = w.union(ridge.translate((x, 0, 0)))
        return w

    def raises():
        raise RuntimeError("the knurl pitch 0 is not valid")

    def hangs():
        while True:
            pass

    def mushroom():
        b = cq.Workplane("XY").box(20, 20, 2, centered=(True, True, False)).translate((0, 0, -2))
        stem = cq.Workplane("XY").circle(1).extrude(2)
        cap = cq.Workplane("XY").circle(4).extrude(1).translate((0, 0, 2))
        return b.union(stem).union(cap)

    def two_metres():
        return cq.Workplane("XY").box(2000, 20, 3, centered=(True, True, False)).translate((0, 0, -3))

    def hairline():
        b = cq.Workplane("XY").box(20, 20, 2, centered=(True, True, False)).translate((0, 0, -2))
        return b.union(cq.Workplane("XY").box(0.06, 10, 0.2, centered=(True, True, False)))
    """
)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("user_plates")
    solid = grating_solid()
    cq.exporters.export(solid, str(d / "grating.step"), exportType="STEP")
    cq.exporters.export(solid, str(d / "grating.stl"), exportType="STL", tolerance=0.005)
    # the same part drawn y-up (its texture faces +y), as some CAD tools draw it
    cq.exporters.export(
        solid.rotate((0, 0, 0), (1, 0, 0), -90), str(d / "grating-yup.stl"), exportType="STL"
    )
    (d / "parts.py").write_text(SCRIPT)
    return d


def _walls_far(plate, X, Y, clearance_m):
    """Points farther than ``clearance_m`` along x from any ridge wall (and the ridge ends)."""
    ok = np.ones(np.shape(X), bool)
    for dx in (-clearance_m, clearance_m):
        for dy in (-clearance_m, clearance_m):
            ok &= grating_height_m(X + dx, Y + dy) == grating_height_m(X, Y)
    return ok


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["step", "stl", "script"])
def test_a_cad_grating_becomes_its_height_map_within_the_stated_tolerance(files, kind):
    ref = {"step": "grating.step", "stl": "grating.stl", "script": "parts.py"}[kind]
    plate = load_user_plate(files / ref)
    t = plate.texture
    assert t.kind == "heightmap" and t.pixel_m == 5e-5
    # the plate frame: texture centred, base at z = 0, the part's 3 mm under it, a run-in
    assert plate.area_length_m == pytest.approx(0.0161, abs=1e-9)  # 16 mm and a sample each side
    assert plate.length_m == pytest.approx(0.0161 + 2 * RUN_IN_M)
    assert plate.width_m == pytest.approx(0.020) and plate.thickness_m == pytest.approx(0.003)
    rng = np.random.default_rng(1)
    X = rng.uniform(-0.0125, 0.0125, 20000)
    Y = rng.uniform(-0.0099, 0.0099, 20000)
    z = surface_of(plate).height(X, Y)
    want = grating_height_m(X, Y)
    # the stated tolerance: exact farther than a sample from a wall, and a wall moves by less
    # than one sample (its sloped sample cell is within the CAD's two levels)
    far = _walls_far(plate, X, Y, t.pixel_m)
    assert far.mean() > 0.9
    assert np.max(np.abs(z[far] - want[far])) <= 1e-9
    assert np.all((z >= -1e-9) & (z <= HEIGHT * 1e-3 + 1e-9))
    near = ~far
    shifted = [
        grating_height_m(X[near] + s, Y[near] + u)
        for s in (-t.pixel_m, 0, t.pixel_m)
        for u in (-t.pixel_m, 0, t.pixel_m)
    ]
    lo, hi = np.min(shifted, axis=0), np.max(shifted, axis=0)
    assert np.all((z[near] >= lo - 1e-9) & (z[near] <= hi + 1e-9))


@pytest.mark.slow
def test_step_stl_and_script_give_one_plate_and_its_artefacts(files, tmp_path):
    step = load_user_plate(files / "grating.step")
    script = load_user_plate(f"{files / 'parts.py'}:plate")
    stl = load_user_plate(files / "grating.stl")
    assert step.hash == script.hash  # one solid, one tessellation, one map
    assert np.max(np.abs(stl.texture.z - step.texture.z)) <= 1e-9
    cache = ArtefactCache(tmp_path / "cache")
    res = build(step, tmp_path / "out", cache=cache)
    assert sorted(res.files) == ["mjcf", "png", "step", "stl"]
    assert res.geoms == {"box": 3, "hfield": 1}  # the base, two run-in margins, the map
    assert all(p.stat().st_size > 1000 for p in res.files.values())
    # the STL is a closed solid whose top is the map (its base around it)
    import trimesh

    mesh = trimesh.load(res.files["stl"])
    assert mesh.is_watertight and mesh.volume > 0
    from sim_tactile.plates.parts.zbuffer import zbuffer

    xs = np.linspace(-0.0125, 0.0125, 301) + 1.3e-6
    ys = np.linspace(-0.009, 0.009, 101) + 1.7e-6
    top = zbuffer(mesh.vertices * 1e-3, mesh.faces, xs, ys)
    X, Y = np.meshgrid(xs, ys)
    far = _walls_far(step, X, Y, 2 * step.texture.pixel_m)
    assert np.max(np.abs(top - surface_of(step).height(X, Y))[far]) <= 1e-9
    # a second build reads the cache
    assert all(build(step, cache=cache).cached.values())


@pytest.mark.slow
def test_a_part_drawn_y_up_is_placed_by_up(files):
    z_up = load_user_plate(files / "grating.stl")
    side = load_user_plate(files / "grating-yup.stl")  # read z-up: the part on its side
    assert side.texture.z.shape != z_up.texture.z.shape  # its 20 mm width stands up
    y_up = load_user_plate(f"{files / 'grating-yup.stl'}?up=+y")
    assert y_up.texture.z.shape == z_up.texture.z.shape
    assert np.max(np.abs(y_up.texture.z - z_up.texture.z)) <= 1e-9
    turned = load_user_plate(files / "grating.stl", rotate_deg=90)  # ridges along x now
    assert turned.texture.z.shape == z_up.texture.z.shape[::-1]
    half = load_user_plate(files / "grating.stl", scale=0.5)
    assert np.nanmax(half.texture.z) == pytest.approx(0.25e-3, abs=1e-9)
    metres = load_user_plate(files / "grating.stl", units="um", scale=1000)
    assert metres.hash == z_up.hash  # um x 1000 = mm


def test_height_maps_npy_and_16bit_png(tmp_path):
    from PIL import Image

    x = np.arange(401) * 2e-5
    y = np.arange(201) * 2e-5
    z = 1e-4 * (1 + np.sin(2 * np.pi * x / 2e-3))[None, :] * np.ones((len(y), 1))
    z[:, :] += 2e-6 * (y[:, None] > 2e-3)  # a step along y: rows run along +y
    np.save(tmp_path / "scan.npy", z)
    plate = load_user_plate(f"{tmp_path / 'scan.npy'}?pixel_m=2e-05")
    t = plate.texture
    assert t.z.shape == z.shape and np.allclose(t.z, z - z.min(), atol=0, rtol=0)
    assert plate.area_length_m == pytest.approx(0.008) and plate.area_width_m == pytest.approx(
        0.004
    )
    xs, ys = t.grid()
    assert np.allclose(surface_of(plate).height(xs[None, :], ys[:, None]), t.z, rtol=0, atol=1e-18)
    counts = np.round((z - z.min()) / 1e-8).astype(np.uint16)
    Image.fromarray(counts[::-1]).save(tmp_path / "scan.png")  # the picture's top row is +y
    png = load_user_plate(tmp_path / "scan.png", pixel_m=2e-5, z_scale_m=1e-8)
    assert np.array_equal(png.texture.z, counts * 1e-8)
    with pytest.raises(ConfigError, match="pixel_m"):
        load_user_plate(tmp_path / "scan.npy")
    with pytest.raises(ConfigError, match="z_scale_m"):
        load_user_plate(tmp_path / "scan.png", pixel_m=2e-5)
    np.save(tmp_path / "objects.npy", np.array([{"a": 1}], dtype=object))
    with pytest.raises(ConfigError, match="without pickles"):
        load_user_plate(tmp_path / "objects.npy", pixel_m=1e-5)


@pytest.mark.slow
def test_cached_by_content_not_by_path(files, tmp_path):
    """Editing a CAD file makes another plate, so its slides have other cache keys; the same
    bytes at another path are the same plate."""
    from sim_tactile.sensors import get_sensor
    from sim_tactile.sim.plan.protocol import Protocol
    from sim_tactile.slides.jobs import SlideJob

    sensor = get_sensor("grid3x3")
    proto = Protocol(speed_m_s=0.04, force_n=1.0, rate_hz=200.0, duration_s=0.5)

    def key(plate):
        return SlideJob(plate, sensor, proto, seed=3).key()

    mine = tmp_path / "mine.stl"
    mine.write_bytes((files / "grating.stl").read_bytes())
    first = load_user_plate(mine)
    assert key(first) == key(load_user_plate(files / "grating.stl"))  # content, not path
    cq.exporters.export(grating_solid(height=0.6), str(mine), exportType="STL", tolerance=0.005)
    edited = load_user_plate(mine)
    assert edited.hash != first.hash and key(edited) != key(first)
    assert np.nanmax(edited.texture.z) == pytest.approx(0.6e-3, abs=1e-9)


def _nothing_written(d: Path, before: set) -> None:
    assert {p.name for p in d.iterdir()} == before


@pytest.mark.slow
@pytest.mark.parametrize(
    "ref, words",
    [
        ("parts.py:raises", ["raises() failed", "RuntimeError", "knurl pitch 0"]),
        ("parts.py:mushroom", ["overhangs along z", "fill_overhangs=true"]),
        ("parts.py:two_metres", ["2 m along x", "valid: [0.001, 0.5] m", "units"]),
        ("parts.py:hairline", ["mm across, 2 samples", "valid: at least 3 samples", "pixel_m <="]),
        ("parts.py:missing", ["missing() failed", "defines no function missing()"]),
        ("grating.stl?colour=red", ["option 'colour' is not valid", "rotate_deg"]),
        ("grating.stl?up=up", ["up = 'up' is not valid", "+z, -z"]),
        ("grating.iges", ["is not a preset", ".step, .stp, .stl"]),
        ("nowhere.step", ["no such file"]),
    ],
)
def test_bad_parts_are_refused_with_what_is_wrong_and_nothing_written(files, ref, words):
    before = {p.name for p in files.iterdir()}
    with pytest.raises(ConfigError) as exc:
        get_plate(str(files / ref))
    for w in words:
        assert w in str(exc.value), (w, str(exc.value))
    _nothing_written(files, before)


@pytest.mark.slow
def test_an_open_mesh_is_refused(files, tmp_path):
    import trimesh

    mesh = trimesh.load(files / "grating.stl")
    open_mesh = trimesh.Trimesh(mesh.vertices, mesh.faces[:-3], process=False)
    (tmp_path / "open.stl").write_bytes(trimesh.exchange.stl.export_stl(open_mesh))
    with pytest.raises(ConfigError, match=r"not a closed solid: \d+ edges belong to one triangle"):
        load_user_plate(tmp_path / "open.stl")
    (tmp_path / "junk.stl").write_bytes(b"solid nothing\nendsolid nothing\n")
    with pytest.raises(ConfigError, match="STL"):
        load_user_plate(tmp_path / "junk.stl")


@pytest.mark.slow
def test_an_overhang_may_be_filled_and_is_reported(files):
    plate = load_user_plate(f"{files / 'parts.py'}:mushroom?fill_overhangs=true")
    assert any("filled under the top surface" in n for n in plate.texture.notes)
    # the cap's top, 3 mm over the base, everywhere over the cap (4 mm radius)
    assert surface_of(plate).height(0.003, 0.0) == pytest.approx(3e-3, abs=1e-9)


@pytest.mark.slow
def test_a_script_that_never_returns_is_stopped(files):
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match="did not finish within timeout_s = 3 s"):
        load_user_plate(f"{files / 'parts.py'}:hangs?timeout_s=3")
    assert time.perf_counter() - t0 < 30
    # and no worker is left behind
    import subprocess

    ps = subprocess.run(["ps", "-eo", "args"], capture_output=True, text=True).stdout
    assert "cad_worker script" not in ps or str(files) not in ps


@pytest.mark.slow
def test_a_script_is_run_in_another_process(files, tmp_path):
    """The script's side effects stay in its own process (its working directory is its
    folder); this process's modules never see cadquery imported by it."""
    d = tmp_path / "s"
    d.mkdir()
    (d / "helpers.py").write_text("SIDE = 20\n")  # a module of the user's, beside it
    (d / "side.py").write_text(
        "import os, cadquery as cq\n"
        "from helpers import SIDE\n"
        "def plate():\n"
        "    os.environ['SIM_TACTILE_TOUCHED'] = '1'\n"
        "    open('ran-here.txt', 'w').write(str(os.getpid()))\n"
        "    return cq.Workplane('XY').box(SIDE, SIDE, 2)\n"
    )
    plate = load_user_plate(d / "side.py")
    assert "SIM_TACTILE_TOUCHED" not in os.environ
    assert int((d / "ran-here.txt").read_text()) != os.getpid()
    assert np.nanmax(plate.texture.z) <= 1e-15  # flat: a plate without texture
    assert any("no texture" in n for n in plate.texture.notes)


def test_a_script_plate_is_named_by_its_file_and_function_once():
    """``pins.py:pins`` is the plate ``pins``, not ``pins-pins``; another function is named
    after the file and the function; a ``name`` option wins."""
    from sim_tactile.plates.user import plate_name

    def name(ref: str) -> str:
        src = parse_ref(ref)
        return plate_name(src, Path(src.path))

    assert name("a/pins.py:pins") == "pins"
    assert name("a/pins.py") == name("a/pins.py:plate") == "pins"
    assert name("a/parts.py:knurl") == "parts-knurl"
    assert name("a/pins.py:pins?name=studs") == "studs"
    assert name("scan.npy") == "scan"


def test_references_parse_and_print_back():
    src = parse_ref("a/b/knurl.py:make?pixel_m=2.5e-05&up=-y&fill_overhangs=true")
    assert (src.path, src.function, src.pixel_m, src.up, src.fill_overhangs) == (
        "a/b/knurl.py",
        "make",
        2.5e-5,
        "-y",
        True,
    )
    assert parse_ref(src.ref()) == src
    assert parse_ref("x.stl").ref() == "x.stl"
    with pytest.raises(ConfigError, match="pixel_m = 'abc' is not valid"):
        parse_ref("x.stl?pixel_m=abc")


def test_png_bytes_are_data_not_code(tmp_path):
    """A file that is not what its suffix says is refused as data."""
    (tmp_path / "fake.png").write_bytes(b"\x89PNG\r\n\x1a\n" + os.urandom(64))
    with pytest.raises(ConfigError, match="PNG"):
        load_user_plate(tmp_path / "fake.png", pixel_m=1e-5, z_scale_m=1e-8)
    buf = io.BytesIO()
    np.save(buf, np.zeros((3, 3)))
    (tmp_path / "tiny.npy").write_bytes(buf.getvalue())
    with pytest.raises(ConfigError, match="valid: \\[0.001, 0.5\\] m"):
        load_user_plate(tmp_path / "tiny.npy", pixel_m=1e-5)
