"""A user's parts through the commands: `simulate` over an STL grating drawn y-up (placed by
--plate-frame) obeys the grating law; `plates build` makes its artefacts; a configuration
naming a CadQuery script, a table and a height map makes a store that re-creates its plates
after the files are gone; a bad part in a configuration writes nothing."""

from __future__ import annotations

import json
import textwrap

import numpy as np
import pytest

from sim_tactile.bench.closed_forms import pulse_period
from sim_tactile.records import Recording
from sim_tactile.sensors import Finger

cq = pytest.importorskip("cadquery")
pytestmark = pytest.mark.slow

PERIOD_MM = 2.2


def _grating(period=PERIOD_MM, n=16, height=0.5):
    w = cq.Workplane("XY").box(40, 36, 3, centered=(True, True, False)).translate((0, 0, -3))
    for i in range(n):
        x = -n * period / 2 + (i + 0.5) * period
        ridge = cq.Workplane("XY").box(period / 2, 36, height, centered=(True, True, False))
        w = w.union(ridge.translate((x, 0, 0)))
    return w


def test_an_stl_grating_drawn_y_up_through_simulate_and_plates_build(cli, tmp_path):
    stl = tmp_path / "grating-yup.stl"
    solid = _grating().rotate((0, 0, 0), (1, 0, 0), -90)  # its texture faces +y
    cq.exporters.export(solid, str(stl), exportType="STL", tolerance=0.005)
    out = tmp_path / "r.npz"
    res = cli(
        ["simulate", "--plate", stl, "--plate-frame", "up=+y", "--speed", "0.04"]
        + ["--force", "1", "--ideal", "--out", out, "--json"]
    )
    rec = Recording.load(out)
    assert rec.meta["plate_params"]["texture"]["kind"] == "heightmap"
    area, pad = rec.meta["plate_params"]["area_length_m"], Finger().patch_m[0]
    m = pulse_period(rec, 4, area, PERIOD_MM * 1e-3, 0.04, pad)  # the middle taxel
    assert m["period_s"] == pytest.approx(PERIOD_MM * 1e-3 / 0.04, rel=0.02)  # the grating law
    assert json.loads(res.stdout)["n_taxels"] == 9
    built = cli(
        ["plates", "build", stl, "--plate-frame", "up=+y", "--out", tmp_path / "b", "--json"]
    )
    files = json.loads(built.stdout)["files"]
    assert sorted(files) == ["mjcf", "png", "step", "stl"]
    assert "flat base extends the part" in built.stderr  # what loading it reported
    bad = cli(
        ["simulate", "--plate", "finger7/flat", "--plate-frame", "up=+y", "--out", out], check=False
    )
    assert bad.returncode == 2 and "--plate-frame applies to a part" in bad.stderr


SCRIPT = textwrap.dedent(
    """
    import cadquery as cq

    def bumps(pitch=4.0):
        w = cq.Workplane("XY").box(36, 36, 2, centered=(True, True, False)).translate((0, 0, -2))
        pts = [(x, y) for x in (-12, -8, -4, 0, 4, 8, 12) for y in (-12, -8, -4, 0, 4, 8, 12)]
        return w.union(cq.Workplane("XY").pushPoints(pts).circle(1.0).extrude(0.5))

    def mushroom():
        b = cq.Workplane("XY").box(20, 20, 2, centered=(True, True, False)).translate((0, 0, -2))
        stem = cq.Workplane("XY").circle(1).extrude(2)
        cap = cq.Workplane("XY").circle(4).extrude(1).translate((0, 0, 2))
        return b.union(stem).union(cap)
    """
)


def test_a_configuration_of_parts_makes_a_store_that_holds_them(tmp_path, cache_dir, monkeypatch):
    from sim_tactile import datasets
    from sim_tactile.errors import ConfigError
    from sim_tactile.generate import generate
    from sim_tactile.plates import get_plate

    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))
    d = tmp_path / "mine"
    d.mkdir()
    (d / "parts.py").write_text(SCRIPT)
    x = np.arange(721) * 5e-5
    np.save(d / "waves.npy", 2e-4 * (1 + np.sin(2 * np.pi * x / 3e-3))[None, :] * np.ones((721, 1)))
    cfg = d / "set.toml"
    cfg.write_text(
        'plates = ["parts.py:bumps", {file = "waves.npy", pixel_m = 5e-5, name = "waves"}]\n'
        'sensor = "grid3x3"\nslides_per_plate = 2\n[protocol]\nduration_s = 0.2\n'
    )
    text = cfg.read_text()
    res = generate(str(cfg), tmp_path / "s.zarr", progress=False, log=lambda m: None, workers=1)
    assert res["written"] == 4
    loaded = [
        get_plate(f"{d / 'parts.py'}:bumps"),
        get_plate(f"{d / 'waves.npy'}?pixel_m=5e-05&name=waves"),
    ]
    st = datasets.open(tmp_path / "s.zarr")
    assert st.to_tactile().class_names == ("parts-bumps", "waves")
    for f in d.iterdir():
        f.unlink()  # the store alone re-creates the plates
    again = st.plates()
    assert [p.hash for p in again] == [p.hash for p in loaded]
    assert np.array_equal(again[1].texture.z, loaded[1].texture.z)
    assert [p.name for p in again] == ["parts-bumps", "waves"]

    # a bad part refuses the configuration before anything is written
    (d / "parts.py").write_text(SCRIPT)
    bad = d / "bad.toml"
    bad.write_text(text.replace('"parts.py:bumps"', '"parts.py:mushroom"'))
    with pytest.raises(ConfigError, match="overhangs along z"):
        generate(str(bad), tmp_path / "bad.zarr", progress=False, log=lambda m: None, workers=1)
    assert not (tmp_path / "bad.zarr").exists()
    assert not list(tmp_path.glob(".bad.zarr*"))


def test_editing_a_part_never_reuses_its_old_slides(tmp_path):
    """Through the slide cache itself: the second run of an unchanged file reads its slide,
    an edited file (a taller grating) is simulated again and records another stream."""
    from sim_tactile.cache import ArtefactCache
    from sim_tactile.plates import get_plate
    from sim_tactile.sensors import get_sensor
    from sim_tactile.sim.plan.protocol import Protocol
    from sim_tactile.slides.jobs import SlideJob
    from sim_tactile.slides.run import run_slides

    cache = ArtefactCache(tmp_path / "cache")
    stl = tmp_path / "mine.stl"
    sensor = get_sensor("grid3x3")
    proto = Protocol(speed_m_s=0.04, force_n=1.0, rate_hz=100.0, duration_s=0.3)

    def slide():
        job = SlideJob(get_plate(str(stl)), sensor, proto, seed=5, ideal=True)
        (rec,), stats = run_slides([job], cache=cache, workers=1)
        return rec, stats

    cq.exporters.export(_grating(), str(stl), exportType="STL", tolerance=0.005)
    first, s1 = slide()
    again, s2 = slide()
    assert (s1["slides_simulated"], s2["slides_simulated"], s2["slides_cached"]) == (1, 0, 1)
    assert np.array_equal(first.data, again.data)
    # edited in place: ridges 0.8 mm high
    cq.exporters.export(_grating(height=0.8), str(stl), exportType="STL", tolerance=0.005)
    edited, s3 = slide()
    assert s3["slides_simulated"] == 1 and s3["slides_cached"] == 0
    assert not np.array_equal(edited.data, first.data)
