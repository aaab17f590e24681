"""Sensors as files: the presets read from assets/sensors, a user's sensor file (a preset
changed, a grid generator, taxels one by one), and every bad file refused with its key."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.hashing import content_hash
from sim_tactile.sensors import (
    Piezoelectric,
    get_layout,
    get_sensor,
    preset_file,
    resolve_sensor,
    sensor_names,
)
from sim_tactile.sensors.file_data import sensor_from_record, sensor_to_data, write_sensor_file
from sim_tactile.sensors.files import load_sensor_file, sensor_from_data

HERE = Path(__file__).parent
ROOT = HERE.parent
#: Every preset sensor and plate as the code defined them before they became files of
#: assets/ (their to_json and params, written at 50ac7dc): the files must give the same.
IN_CODE = json.loads((HERE / "data" / "presets_in_code.json").read_text())


def _same(a, b) -> bool:
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


@pytest.mark.parametrize("name", sensor_names())
def test_each_preset_sensor_from_assets_is_the_one_the_code_defined(name):
    s = get_sensor(name)
    assert _same(s.to_json(), IN_CODE["sensors"][name])
    assert content_hash(s.to_json()) == content_hash(IN_CODE["sensors"][name])  # -0.0 too
    # the layout functions (which say where each taxel comes from) give the file's layout
    assert _same(get_layout(name).to_json(), s.layout.to_json())


def test_the_presets_are_the_files_of_the_assets_folder():
    folder = ROOT / "assets" / "sensors"
    assert sorted(p.stem for p in folder.glob("*.toml")) == sorted(sensor_names())
    assert preset_file("grid3x3").resolve() == (folder / "grid3x3.toml").resolve()


@pytest.mark.parametrize("name", sensor_names())
def test_a_sensor_written_and_read_back_is_the_same(name, tmp_path):
    for s in (get_sensor(name), get_sensor(name).with_paper_stack()):
        path = write_sensor_file(s, tmp_path / f"{name}.toml")
        back = load_sensor_file(path)
        assert content_hash(back.to_json()) == content_hash(s.to_json())
        # and as a data set records it (to_json), without the file
        rec = sensor_from_record(json.loads(json.dumps(s.to_json())))
        assert content_hash(rec.to_json()) == content_hash(s.to_json())


def _write(tmp_path, text: str, name="s.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


GRID4 = """
base = "grid3x3"
name = "my4x4"
rate_hz = 200.0
[layout.grid]
rows = 4
cols = 4
pitch_m = 2.5e-3
size_m = 2.0e-3
"""


def test_a_4x4_grid_from_a_preset(tmp_path):
    s = load_sensor_file(_write(tmp_path, GRID4))
    base = get_sensor("grid3x3")
    assert s.name == "my4x4" and s.layout.n == 16 and s.layout.grid_shape == (4, 4)
    assert s.rate_hz == 200.0
    np.testing.assert_allclose(
        np.unique(s.layout.positions[:, 0]), [-3.75e-3, -1.25e-3, 1.25e-3, 3.75e-3]
    )
    assert s.finger == base.finger and s.transducer == base.transducer
    assert s.imperfections == base.imperfections


def test_a_file_changes_the_fields_it_names_and_keeps_the_rest(tmp_path):
    text = """
base = "biotac19"
[pad]
young_pa = 0.5e6
[transducer]
gain_counts_per_n = 100.0
[imperfections]
noise_std = 2.0
"""
    s = load_sensor_file(_write(tmp_path, text, "soft.toml"))
    b = get_sensor("biotac19")
    assert s.name == "soft" and s.finger.young_pa == 0.5e6 and s.finger.radii_m == b.finger.radii_m
    assert s.transducer.gain_counts_per_n == 100.0
    assert s.transducer.full_scale == b.transducer.full_scale
    assert s.imperfections.noise_std == 2.0
    assert s.imperfections.quant_step == b.imperfections.quant_step
    assert _same(s.layout.to_json() | {"name": "biotac19"}, b.layout.to_json())


def test_taxels_one_by_one_with_a_stack_and_a_transducer_per_layer(tmp_path):
    text = """
rate_hz = 500.0
[layout]
x_m = [-2e-3, 2e-3, 0.0]
y_m = [0.0, 0.0, 1e-3]
depth_m = [0.5e-3, 0.5e-3, 1.5e-3]
size_m = [1e-3, [1e-3, 2e-3], 1.5e-3]
layer = [0, 0, 1]
[pad]
shape = "sphere"
radius_m = 0.01
size_m = [0.014, 0.014]
[pad.stack]
backing = "rigid"
[[pad.stack.layers]]
thickness_m = 1e-3
young_pa = 1e6
poisson = 0.45
[[pad.stack.layers]]
thickness_m = 2e-3
young_pa = 0.2e6
[[transducer]]
kind = "piezoelectric"
[[transducer]]
kind = "ideal"
"""
    s = load_sensor_file(_write(tmp_path, text))
    assert s.layout.n == 3 and s.layout.sizes[1].tolist() == [1e-3, 2e-3]
    assert s.layout.depth_m.tolist() == [0.5e-3, 0.5e-3, 1.5e-3]
    assert s.finger.thickness_m == pytest.approx(3e-3) and s.finger.young_pa == 1e6
    assert isinstance(s.transducer[0], Piezoelectric) and s.transducer[1] is None
    assert s.imperfections is None


BAD = [
    # (what, file text, words the error names)
    ("unknown top key", 'base = "grid3x3"\ncolour = "red"\n', ["colour", "valid"]),
    ("unknown pad key", 'base = "grid3x3"\n[pad]\nyoung = 1e6\n', ["pad.young", "pad.young_pa"]),
    ("unknown grid key", GRID4.replace("rows = 4", "rows = 4\nrow = 4"), ["layout.grid.row"]),
    (
        "a taxel outside the pad",
        'base = "grid3x3"\n[layout]\nx_m = [0.0, 0.02]\ny_m = [0.0, 0.0]\nsize_m = 1e-3\n',
        ["taxel 1 ('t1')", "beyond the pad", "x_m = 0.02 m", "valid: |x_m| + size/2 <= 0.008 m"],
    ),
    (
        "a taxel across the pad's edge",
        'base = "grid3x3"\n[layout]\nx_m = [0.0, 0.0]\ny_m = [0.0, -0.0075]\nsize_m = 2e-3\n',
        ["taxel 1 ('t1')", "y_m = -0.0075 m", "reaching 0.0085 m", "<= 0.008 m"],
    ),
    (
        "a taxel 1 m deep in a 4 mm pad",
        'base = "grid3x3"\n[layout]\nx_m = [0.0, 1e-3]\ny_m = [0.0, 0.0]\ndepth_m = [1e-3, 1.0]\n'
        "size_m = 1e-3\n",
        ["taxel 1 ('t1')", "below the skin", "depth_m = 1 m", "valid: 0 <= depth_m <= 0.004 m"],
    ),
    (
        "a taxel under a thinned skin",
        'base = "biotac19"\n[pad]\nthickness_m = 2e-3\n',
        ["taxel 0 ('ele1')", "depth_m = 0.0025 m", "<= 0.002 m", "19 taxel(s) below it"],
    ),
    (
        "a pad out of range",
        'base = "grid3x3"\n[pad]\nsize_m = [0.5, 0.012]\n',
        ["pad.size_m[0]", "0.5", "[0.001, 0.1]"],
    ),
    ("a negative rate", 'base = "grid3x3"\nrate_hz = -5\n', ["rate_hz", "-5", "valid"]),
    ("no layout", 'rate_hz = 100\n[pad]\n[transducer]\nkind = "ideal"\n', ["layout is missing"]),
    ("an unknown base", 'base = "grid9x9"\n', ["base", "grid9x9", "grid3x3"]),
    (
        "a transducer kind",
        'base = "grid3x3"\n[transducer]\nkind = "optical"\n',
        ["transducer.kind", "optical", "capacitive"],
    ),
    (
        "a transducer field",
        'base = "grid3x3"\n[transducer]\nvcc_v = -1.0\n',
        ["transducer.vcc_v", "-1"],
    ),
    (
        "a noise",
        'base = "grid3x3"\n[imperfections]\nnoise_std = -1.0\n',
        ["imperfections.noise_std", "-1"],
    ),
    (
        "columns of other lengths",
        'base = "grid3x3"\n[layout]\nx_m = [0.0, 1e-3]\ny_m = [0.0]\nsize_m = 1e-3\n',
        ["layout.y_m", "one per taxel (2)"],
    ),
    (
        "a grid and columns",
        GRID4.replace("[layout.grid]", "[layout]\nx_m = [0.0]\n[layout.grid]"),
        ["layout.grid", "layout.x_m"],
    ),
    (
        "the stack and the modulus",
        'base = "grid3x3"\n[pad]\nyoung_pa = 1e6\n[[pad.stack.layers]]\nthickness_m = 1e-3\nyoung_pa = 1e6\n',
        ["pad.young_pa", "pad.stack"],
    ),
    (
        "two transducers for one layer",
        'base = "grid3x3"\n[[transducer]]\nkind = "ideal"\n[[transducer]]\nkind = "ideal"\n',
        ["2 [[transducer]]", "1 layers"],
    ),
    ("another format", 'format = 2\nbase = "grid3x3"\n', ["format", "valid: 1"]),
    (
        "3 mm taxels at 2 mm pitch",
        GRID4.replace("pitch_m = 2.5e-3", "pitch_m = 2e-3").replace("2.0e-3", "3e-3"),
        ["taxels 0 (r0c0", "1 (r0c1", "of layer 0 overlap by 1 x 3 mm", "overlap = true"],
    ),
    (
        "two taxels 0.5 mm apart",
        'base = "grid3x3"\n[layout]\nx_m = [0.0, 5e-4]\ny_m = [0.0, 0.0]\nsize_m = 1e-3\n',
        ["taxels 0 (t0, 1 x 1 mm at x = 0, y = 0 mm)", "x = 0.5", "overlap by 0.5 x 1 mm"],
    ),
    (
        "overlap not true or false",
        'base = "grid3x3"\n[layout]\noverlap = "yes"\nx_m = [0.0]\ny_m = [0.0]\nsize_m = 1e-3\n',
        ["layout.overlap", "'yes'", "true or false"],
    ),
    ("not TOML", "base = \n", ["not valid TOML"]),
]


def test_overlapping_taxels_are_taken_where_the_file_says_so(tmp_path):
    """``overlap = true`` lets taxels of one layer share the skin, beside a grid or columns;
    such a sensor writes itself with the key, and reads back (from its file and from a data
    set's record); taxels that only touch need no key."""
    grid = GRID4.replace("pitch_m = 2.5e-3", "pitch_m = 2e-3").replace("2.0e-3", "3e-3")
    s = load_sensor_file(
        _write(tmp_path, grid.replace("[layout.grid]", "[layout]\noverlap = true\n[layout.grid]"))
    )
    assert s.layout.n == 16 and s.layout.sizes[0, 0] == 3e-3
    cols = 'base = "grid3x3"\n[layout]\noverlap = true\nx_m = [0.0, 5e-4]\ny_m = [0.0, 0.0]\nsize_m = 1e-3\n'
    for sensor in (s, load_sensor_file(_write(tmp_path, cols, "c.toml"))):
        path = write_sensor_file(sensor, tmp_path / "back.toml")
        assert "overlap = true" in path.read_text()
        assert content_hash(load_sensor_file(path).to_json()) == content_hash(sensor.to_json())
        rec = sensor_from_record(json.loads(json.dumps(sensor.to_json())))
        assert content_hash(rec.to_json()) == content_hash(sensor.to_json())
    touching = GRID4.replace("2.0e-3", "2.5e-3")  # size = pitch: edges meet
    assert load_sensor_file(_write(tmp_path, touching, "t.toml")).layout.n == 16
    assert (
        "overlap" not in write_sensor_file(get_sensor("grid3x3"), tmp_path / "g.toml").read_text()
    )


@pytest.mark.parametrize("what, text, words", BAD, ids=[b[0] for b in BAD])
def test_a_bad_sensor_file_is_refused_naming_the_key(what, text, words, tmp_path):
    path = _write(tmp_path, text)
    with pytest.raises(ConfigError) as exc:
        load_sensor_file(path)
    msg = str(exc.value)
    assert str(path) in msg
    for w in words:
        assert w in msg, (what, msg)


def test_resolve_sensor_takes_a_file_and_refuses_a_missing_one(tmp_path):
    s = resolve_sensor(str(_write(tmp_path, GRID4)))
    assert s.layout.n == 16
    with pytest.raises(ConfigError, match="does not exist"):
        resolve_sensor(str(tmp_path / "nope.toml"))


def test_the_data_form_of_a_sensor_is_what_the_file_holds():
    d = sensor_to_data(get_sensor("grid3x3"))
    assert d["layout"] == {
        "grid": {"rows": 3, "cols": 3, "pitch_m": 2.5e-3, "size_m": 2e-3, "depth_m": 0.0}
    }
    again = sensor_from_data(d)
    assert content_hash(again.to_json()) == content_hash(get_sensor("grid3x3").to_json())


@pytest.mark.slow
def test_a_4x4_sensor_file_through_simulate_and_generate(cli, tmp_path, cache_dir, monkeypatch):
    """16 channels from simulate (the console script) and from generate (a configuration
    naming the file beside it); the store records the sensor whole, and it re-creates the
    sensor with the file gone. A bad file stops simulate before anything is written."""
    from sim_tactile import datasets
    from sim_tactile.generate import generate

    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))
    sensor = _write(tmp_path, GRID4, "my4x4.toml")
    out = tmp_path / "r.npz"
    args = ["simulate", "--plate", "finger7/ridges-2", "--sensor", sensor, "--duration", "0.2"]
    doc = json.loads(cli([*args, "--ideal", "--out", out, "--json"]).stdout)
    assert doc["n_taxels"] == 16 and doc["rate_hz"] == 200.0 and out.is_file()
    bad = _write(tmp_path, GRID4.replace("rows = 4", "rows = 40"), "bad.toml")
    p = cli(
        ["simulate", "--plate", "finger7/flat", "--sensor", bad, "--out", tmp_path / "b.npz"],
        check=False,
    )
    assert p.returncode == 2 and "beyond the pad" in p.stderr and not (tmp_path / "b.npz").exists()

    cfg = tmp_path / "set.toml"
    cfg.write_text(
        'plates = ["finger7/flat", "finger7/ridges-2"]\nsensor = "my4x4.toml"\n'
        "slides_per_plate = 2\n[protocol]\nduration_s = 0.2\n"
    )
    res = generate(str(cfg), tmp_path / "s.zarr", progress=False, log=lambda m: None, workers=1)
    assert res["written"] == 4
    st = datasets.open(tmp_path / "s.zarr")
    assert st[0].shape[1] == 16 and st.config["sensor"] == "my4x4"
    want = content_hash(load_sensor_file(sensor).to_json())
    sensor.unlink()
    again = sensor_from_record(st.config["sensor_definition"])
    assert content_hash(again.to_json()) == want


def test_every_preset_sensor_file_still_loads_and_carries_its_taxels():
    """The pad check (taxels within the patch and the skin) passes every preset, as its
    file and with its paper's skin stack, and a taxel on the bone (depth = thickness)."""
    from sim_tactile.sensors import check_pad, get_sensor
    from sim_tactile.sensors.presets import PRESETS, preset_file

    for name in PRESETS:
        s = load_sensor_file(preset_file(name))
        check_pad(s.layout, s.finger)
        stacked = get_sensor(name).with_paper_stack()
        check_pad(stacked.layout, stacked.finger)
    bone = get_sensor("biotac19")
    check_pad(bone.layout, replace(bone.finger, thickness_m=2.5e-3))


def test_a_bare_layout_deeper_than_the_skin_is_not_simulated():
    """The simulation checks the same: taxels 1 m deep in a 4 mm pad are refused before
    anything runs, naming the taxel."""
    from sim_tactile.sensors import Layout
    from sim_tactile.sim.slide import simulate

    deep = Layout(
        "deep",
        np.array([[0.0, 0.0, -1e-3], [1e-3, 0.0, -1.0]]),
        np.full((2, 2), 1e-3),
        np.zeros(2, int),
    )
    with pytest.raises(
        ConfigError, match=r"taxel 1 \('t1'\) of the deep layout lies below the skin: depth_m = 1 m"
    ):
        simulate("finger7/flat", deep)
