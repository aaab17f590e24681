"""Inputs are bounded before they are read: a .npy's header and a PNG's dimensions are checked
before their samples, every file's size before its bytes, and every count in a plate,
sensor or configuration file is capped; each refusal names the value and the valid range."""

from __future__ import annotations

import struct
import tracemalloc
import zlib
from pathlib import Path

import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.plates.define.spec import (
    MAX_FEATURES,
    MAX_HEIGHTMAP_SAMPLES,
    Bumps,
    Grating,
    Plate,
)
from sim_tactile.plates.parts import map_files
from sim_tactile.plates.parts.user import load_user_plate
from sim_tactile.plates.read.files import load_plate_file
from sim_tactile.sensors.files import MAX_TAXELS, load_sensor_file
from sim_tactile.slides.config import MAX_PLATES, config_slide_set, load_config
from sim_tactile.toml_text import MAX_TEXT_BYTES

#: Peak memory a refusal may take [bytes]: the header and the error, never the samples (the
#: crafted files claim gigabytes).
REFUSAL_PEAK_BYTES = 4 * 2**20


def _refused_lightly(call, *words) -> str:
    """The ConfigError of ``call()``, checked to name ``words`` and to have taken little
    memory (traced by tracemalloc)."""
    tracemalloc.start()
    try:
        with pytest.raises(ConfigError) as exc:
            call()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    msg = str(exc.value)
    for w in words:
        assert w in msg, (w, msg)
    assert peak < REFUSAL_PEAK_BYTES, peak
    return msg


def _npy_header_only(path: Path, shape, descr="<f8") -> None:
    """A .npy file of the header alone: it claims ``shape`` and holds no sample."""
    from numpy.lib import format as npf

    with open(path, "wb") as fh:
        npf.write_array_header_1_0(fh, {"descr": descr, "fortran_order": False, "shape": shape})


def test_a_npy_header_claiming_20_gb_is_refused_without_reading_it(tmp_path):
    path = tmp_path / "huge.npy"
    _npy_header_only(path, (50_000, 50_000))  # 2.5e9 float64: 20 GB
    assert path.stat().st_size < 1000
    _refused_lightly(
        lambda: load_user_plate(path, pixel_m=1e-5),
        "50000 x 50000 = 2500000000 samples",
        f"at most {MAX_HEIGHTMAP_SAMPLES}",
    )


@pytest.mark.parametrize(
    "shape, descr, words",
    [
        ((100, 100), "|O", ["dtype is object", "without pickles"]),
        ((100, 100), "<c16", ["dtype is complex128", "numbers"]),
        ((100, 100), "|b1", ["dtype is bool", "numbers"]),
        ((10, 10, 10), "<f8", ["shape (10, 10, 10)", "2-D"]),
        ((100, 100), "<f8", ["the file is", "its header describes 80"]),  # no samples follow
    ],
)
def test_a_npy_header_is_checked_before_its_samples(tmp_path, shape, descr, words):
    path = tmp_path / "map.npy"
    _npy_header_only(path, shape, descr)
    _refused_lightly(lambda: load_user_plate(path, pixel_m=1e-4), *words)


def test_a_npy_map_too_long_for_its_pixel_is_refused_from_its_header(tmp_path):
    path = tmp_path / "long.npy"
    _npy_header_only(path, (200, 60_000), "<f4")  # within every bound but its 0.5 m side
    _refused_lightly(lambda: load_user_plate(path, pixel_m=1e-5), "along x", "[0.001, 0.5] m")


def _png_claiming(path: Path, width: int, height: int) -> None:
    """A PNG whose header claims ``width`` x ``height`` 16-bit grey pixels, with one tiny
    compressed row: the chunks are well formed (their CRCs right), the pixels never there."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    ihdr = struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0)
    idat = zlib.compress(b"\x00" * 64)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")
    )


@pytest.mark.parametrize(
    "width, height, words",
    [
        (5000, 5000, ["5000 x 5000 = 25000000 samples", "at most"]),  # under Pillow's own limit
        (200_000, 200_000, ["decompression bomb", "at most"]),  # Pillow refuses it on open
    ],
)
def test_a_png_claiming_a_huge_size_is_refused_without_decoding(tmp_path, width, height, words):
    path = tmp_path / "huge.png"
    _png_claiming(path, width, height)
    assert path.stat().st_size < 200
    _refused_lightly(lambda: load_user_plate(path, pixel_m=1e-5, z_scale_m=1e-8), *words)


def test_a_file_too_large_is_refused_by_its_size(tmp_path):
    stl = tmp_path / "big.stl"
    with open(stl, "wb") as fh:  # sparse: its size is all it has
        fh.truncate(map_files.MAX_FILE_BYTES + 1)
    _refused_lightly(
        lambda: load_user_plate(stl), "MiB", f"at most {map_files.MAX_FILE_BYTES >> 20}"
    )
    toml = tmp_path / "big.toml"
    with open(toml, "wb") as fh:
        fh.truncate(MAX_TEXT_BYTES + 1)
    _refused_lightly(lambda: load_plate_file(toml), "MiB", "at most 8 MiB")
    _refused_lightly(lambda: load_sensor_file(toml), "MiB")
    _refused_lightly(lambda: load_config(toml), "MiB")


def test_deeply_nested_values_are_refused_as_configuration_errors(tmp_path):
    deep = tmp_path / "deep.toml"
    deep.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(ConfigError, match="nest too deeply"):
        load_plate_file(deep)
    js = tmp_path / "deep.json"
    js.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(ConfigError, match="nest too deeply"):
        load_config(js)


def _plate_toml(tmp_path: Path, texture: str) -> Path:
    path = tmp_path / "p.toml"
    path.write_text(
        "length_m = 0.3\nwidth_m = 0.3\narea_length_m = 0.2\narea_width_m = 0.2\n\n[texture]\n"
        + texture
    )
    return path


def test_the_bumps_and_ridges_a_plate_carries_are_capped():
    """rows x cols (each within [1, 1000]) is capped at MAX_FEATURES, before any bump is made."""
    Bumps(100, 100, "box", 1e-3, 5e-4)  # 10,000: the cap
    with pytest.raises(ConfigError) as exc:
        Bumps(1000, 1000, "box", 1e-4, 5e-5)
    assert "1000 x 1000 = 1000000 bumps" in str(exc.value)
    assert f"at most {MAX_FEATURES}" in str(exc.value)
    with pytest.raises(ConfigError, match=r"12500 ridges over 0.5 m; valid: at most 10000"):
        Plate(Grating(4e-5, 1e-5), length_m=0.6, width_m=0.1, area_length_m=0.5)


def test_a_plate_file_of_a_million_bumps_is_refused(tmp_path):
    path = _plate_toml(
        tmp_path,
        'kind = "bumps"\nrows = 1000\ncols = 1000\nshape = "box"\nsize_m = 1e-4\nheight_m = 5e-5\n',
    )
    msg = _refused_lightly(lambda: load_plate_file(path), "bumps.rows x bumps.cols", "1000000")
    assert str(path) in msg


def _sensor_toml(tmp_path: Path, layout: str) -> Path:
    path = tmp_path / "s.toml"
    path.write_text('base = "grid3x3"\n\n' + layout)
    return path


def test_a_sensor_file_of_a_million_taxels_is_refused(tmp_path):
    grid = _sensor_toml(
        tmp_path, "[layout.grid]\nrows = 1000\ncols = 1000\npitch_m = 1e-5\nsize_m = 1e-5\n"
    )
    _refused_lightly(lambda: load_sensor_file(grid), "1000000 taxels", f"at most {MAX_TAXELS}")
    n = MAX_TAXELS + 1
    xs = ", ".join(f"{i * 1e-5:.6g}" for i in range(n))
    listed = _sensor_toml(tmp_path, f"[layout]\nx_m = [{xs}]\ny_m = [{xs}]\nsize_m = 1e-5\n")
    with pytest.raises(ConfigError, match=f"layout.x_m: {n} taxels; valid: at most {MAX_TAXELS}"):
        load_sensor_file(listed)


def test_two_taxels_at_one_point_are_refused_naming_both(tmp_path):
    path = _sensor_toml(
        tmp_path,
        "[layout]\nx_m = [0.0, 0.002, 0.004, 0.002]\ny_m = [0.0, 0.001, 0.0, 0.001]\n"
        'size_m = 1e-3\nnames = ["a", "b", "c", "d"]\n',
    )
    with pytest.raises(ConfigError) as exc:
        load_sensor_file(path)
    msg = str(exc.value)
    for w in ["taxels 1 (b) and 3 (d)", "one point", "x = 2 mm, y = 1 mm", "one taxel a point"]:
        assert w in msg, (w, msg)
    # at one point in two layers (stacked transducers) is a sensor
    path.write_text(
        path.read_text().replace("size_m = 1e-3", "size_m = 1e-3\nlayer = [0, 0, 0, 1]")
    )
    assert load_sensor_file(path).layout.n == 4


def test_a_configuration_of_too_many_plates_or_slides_is_refused():
    from sim_tactile.plates import preset_names

    names = preset_names()
    cfg = {"plates": ["x"] * (MAX_PLATES + 1), "sensor": "grid3x3", "slides_per_plate": 2}
    with pytest.raises(ConfigError, match=f"1001 plates; valid: at most {MAX_PLATES}"):
        config_slide_set(cfg)  # refused before any plate is looked up
    cfg = {"plates": names[:11], "sensor": "grid3x3", "slides_per_plate": 100_000}
    with pytest.raises(ConfigError) as exc:
        config_slide_set(cfg)
    assert "1100000 slides; valid: at most 1000000" in str(exc.value)
    assert "slides_per_plate <= 90909" in str(exc.value)
