"""Plates as parameter files: the presets read from assets/plates, a user's plate file
through simulate and generate, and bad files refused with their key."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.plates import get_plate, preset_names
from sim_tactile.plates.read.files import load_plate_file, write_plate_file
from sim_tactile.plates.read.presets import assets_dir, preset_file
from sim_tactile.records import Recording

HERE = Path(__file__).parent
ROOT = HERE.parent
IN_CODE = json.loads((HERE / "data" / "presets_in_code.json").read_text())


def test_each_preset_plate_from_assets_is_the_one_the_code_defined():
    assert sorted(preset_names()) == sorted(IN_CODE["plates"])
    for name in preset_names():
        p = get_plate(name)
        assert p.name == name
        assert p.params() == IN_CODE["plates"][name]["params"], name
        assert p.hash == IN_CODE["plates"][name]["hash"], name


def test_the_presets_are_the_files_of_the_assets_folder():
    assert assets_dir().resolve() == (ROOT / "assets" / "plates").resolve()
    files = sorted(str(p.relative_to(assets_dir()))[:-5] for p in assets_dir().rglob("*.toml"))
    assert files == sorted([*preset_names(), "index"])
    assert preset_file("finger7/ridges-4").is_file()


def test_a_copied_and_edited_preset_is_another_plate(tmp_path):
    src = preset_file("textures20/grating-3.0mm").read_text()
    p = tmp_path / "grating-2.2mm.toml"
    p.write_text(
        src.replace('name = "textures20/grating-3.0mm"', 'name = "mine/grating-2.2mm"').replace(
            "period_m = 0.003", "period_m = 0.0022"
        )
    )
    plate = get_plate(str(p))
    assert plate.name == "mine/grating-2.2mm" and plate.texture.period_m == 0.0022
    assert plate.hash != get_plate("textures20/grating-3.0mm").hash
    again = load_plate_file(write_plate_file(plate, tmp_path / "again.toml"))
    assert again.hash == plate.hash and again.name == plate.name


BAD = [
    ("unknown key", 'colour = 1\n[texture]\nkind = "flat"\n', ["colour"]),
    ("no texture", "length_m = 0.1\n", ["texture"]),
    ("unknown kind", '[texture]\nkind = "knurl"\n', ["texture.kind", "knurl", "grating"]),
    (
        "a 2 m plate",
        'length_m = 2.5\n[texture]\nkind = "flat"\n',
        ["plate.length_m", "2.5", "[0.001, 2]"],
    ),
    (
        "duty and width",
        '[texture]\nkind = "grating"\nperiod_m = 0.003\nheight_m = 5e-4\nduty = 0.5\nwidth_m = 1e-3\n',
        ["duty or width_m"],
    ),
    (
        "a bad ridge key",
        '[texture]\nkind = "ridges"\ncount = 3\nwidth_m = 1e-3\nheight_m = 1e-3\nwidht_m = 1\n',
        ["widht_m"],
    ),
]


@pytest.mark.parametrize("what, text, words", BAD, ids=[b[0] for b in BAD])
def test_a_bad_plate_file_is_refused_naming_the_key(what, text, words, tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(ConfigError) as exc:
        get_plate(str(p))
    msg = str(exc.value)
    assert str(p) in msg
    for w in words:
        assert w in msg, (what, msg)


@pytest.mark.slow
def test_a_plate_file_through_simulate_and_generate(cli, tmp_path, cache_dir, monkeypatch):
    """A user's grating of 2.2 mm period: simulate obeys the grating law (period = spacing /
    speed within 2%), and a configuration naming two plate files beside it makes a store
    whose classes are the plates' names and which records their parameters."""
    from sim_tactile import datasets
    from sim_tactile.generate import generate

    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))
    text = preset_file("textures20/grating-3.0mm").read_text()
    mine = tmp_path / "g22.toml"
    mine.write_text(
        text.replace('name = "textures20/grating-3.0mm"', 'name = "mine/g22"').replace(
            "period_m = 0.003", "period_m = 0.0022"
        )
    )
    out = tmp_path / "r.npz"
    cli(
        [
            "simulate",
            "--plate",
            mine,
            "--speed",
            "0.04",
            "--force",
            "1",
            "--ideal",
            "--out",
            out,
            "--json",
        ]
    )
    rec = Recording.load(out)
    data, rate = rec.data, rec.rate_hz
    x = data[:, 4] - data[:, 4].mean()  # the middle taxel
    n = len(x)
    core = x[n // 4 : 3 * n // 4] - x[n // 4 : 3 * n // 4].mean()
    spec = np.abs(np.fft.rfft(core * np.hanning(len(core)), n=1 << 16))
    f = np.fft.rfftfreq(1 << 16, 1 / rate)
    peak = f[np.argmax(spec[f > 2]) + np.count_nonzero(f <= 2)]
    assert peak == pytest.approx(0.04 / 0.0022, rel=0.02)

    flat = tmp_path / "flat.toml"
    flat.write_text(
        preset_file("textures20/flat")
        .read_text()
        .replace('name = "textures20/flat"', 'name = "mine/flat"')
    )
    cfg = tmp_path / "set.toml"
    cfg.write_text(
        'plates = ["flat.toml", "g22.toml"]\nsensor = "grid3x3"\nslides_per_plate = 2\n'
        "[protocol]\nduration_s = 0.2\n"
    )
    res = generate(str(cfg), tmp_path / "s.zarr", progress=False, log=lambda m: None, workers=1)
    assert res["written"] == 4
    st = datasets.open(tmp_path / "s.zarr")
    assert st.to_tactile().class_names == ("flat", "g22")
    assert st.config["plate_params"][1]["texture"]["period_m"] == 0.0022
