"""Fuzzed user inputs (hypothesis): random plate files, sensor files, configurations and small
height maps are each either refused with a SimTactileError (never another exception: no
TypeError, no traceback from numpy or tomllib) or read back as a valid object. A few dozen
cases of each run in the fast lane; the slow lane runs many more."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from sim_tactile.errors import SimTactileError

FAST = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
SLOW = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# ------------------------------------------------------------------------------ strategies
# numbers near the valid ranges (metres of plates and taxels, rates, counts) and far from them
numbers = st.one_of(
    st.sampled_from([0, 1, 2, 3, 4, -1, 0.5, 1e-4, 5e-4, 1e-3, 2e-3, 0.012, 0.036, 0.108, 200.0]),
    st.integers(-(10**7), 10**7),
    st.floats(allow_nan=True, allow_infinity=True),
)
words = st.sampled_from(["box", "cylinder", "hemisphere", "flat", "sphere", "grid3x3", "x"])
scalars = st.one_of(numbers, st.booleans(), words, st.text(max_size=6))
values = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=4), inner, max_size=3)
    ),
    max_leaves=6,
)


@st.composite
def mutated(draw, base):
    """``base`` (valid data) with some keys dropped, some values fuzzed and a stray key."""
    if not isinstance(base, dict):
        return base if draw(st.integers(0, 5)) else draw(values)
    if not draw(st.integers(0, 3)):
        return base  # valid as it is
    out = {}
    for key, val in base.items():
        action = draw(st.integers(0, 19))
        if action < 18:
            out[key] = draw(mutated(val))
        elif action < 19:
            out[key] = draw(values)
    if not draw(st.integers(0, 9)):
        out[draw(st.text(max_size=5))] = draw(values)
    return out


PLATE = {"length_m": 0.108, "width_m": 0.036, "thickness_m": 0.005, "area_length_m": 0.036}
TEXTURES = [
    {"kind": "flat"},
    {"kind": "ridges", "count": 6, "width_m": 1e-3, "height_m": 5e-4, "draft_deg": 10.0},
    {"kind": "grating", "period_m": 2e-3, "height_m": 5e-4, "duty": 0.5},
    {"kind": "bumps", "rows": 3, "cols": 3, "shape": "hemisphere", "size_m": 4e-3},
    {"kind": "bumps", "rows": 4, "cols": 4, "shape": "box", "size_m": 2e-3, "height_m": 1e-3},
    {"kind": "roughness", "ra_m": 1e-6, "corr_length_m": 1e-4, "seed": 3},
    {"kind": "heightmap", "sha256": "00", "pixel_m": 1e-4, "shape": [2, 2]},
]
plate_data = st.sampled_from(TEXTURES).flatmap(
    lambda tex: mutated({"format": 1, "name": "p", **PLATE, "texture": tex})
)

PAD = {"shape": "sphere", "size_m": [0.014, 0.014], "radius_m": 0.01, "young_pa": 3e5}
SENSORS = [
    {"base": "grid3x3"},
    {"base": "grid3x3", "rate_hz": 200.0, "layout": {"grid": {"rows": 4, "cols": 4}}},
    {
        "base": "pvdf2",
        "layout": {"x_m": [0.0, 0.003, 0.0], "y_m": [0.0, 0.0, 0.002], "size_m": 2e-3},
        "imperfections": {"noise_std": 0.01, "quant_step": 0.001},
    },
    {
        "rate_hz": 100.0,
        "layout": {"x_m": [0.0, 0.003], "y_m": [0.0, 0.0], "size_m": [[1e-3, 2e-3]], "layer": 0},
        "pad": PAD,
        "transducer": {"kind": "ideal"},
    },
]
for _s in SENSORS[1:2]:
    _s["layout"]["grid"].update(pitch_m=2.5e-3, size_m=2e-3)
sensor_data = st.sampled_from(SENSORS).flatmap(mutated)

CONFIG = {
    "name": "fuzz",
    "seed": 1,
    "plates": ["finger7/flat", "finger7/ridges-2", "finger7/bumps-3x3"],
    "sensor": "grid3x3",
    "slides_per_plate": 4,
    "quick_slides_per_plate": 2,
    "fidelity": "auto",
    "protocol": {"speed_m_s": 0.04, "force_n": 1.0, "passes": 1},
    "randomise": {"speed_jitter": 0.05, "offset_jitter_m": 5e-4},
}
config_data = mutated(CONFIG)


# ------------------------------------------------------------------------------ the cases
def _read(call):
    """``call()``'s result, or None where it refused with a SimTactileError (any other
    exception fails the test, as hypothesis reports it)."""
    try:
        out = call()
    except SimTactileError as exc:
        assert str(exc), "an error without a message"
        event("refused")
        return None
    event("read")
    return out


def check_plate(data: dict) -> None:
    from sim_tactile.plates.define.spec import Plate
    from sim_tactile.plates.read.files import plate_from_data, plate_to_data

    plate = _read(lambda: plate_from_data(data, "fuzz"))
    if plate is not None:
        assert isinstance(plate, Plate)
        assert plate_from_data(plate_to_data(plate), "fuzz") == plate


def check_sensor(data: dict) -> None:
    from sim_tactile.sensors.files import sensor_from_data

    sensor = _read(lambda: sensor_from_data(data))
    if sensor is not None:
        assert sensor.layout.n >= 1 and np.isfinite(sensor.layout.positions).all()


def check_config(data: dict, base_dir: Path) -> None:
    from sim_tactile.slides.config import config_slide_set

    out = _read(lambda: config_slide_set(data, base_dir=base_dir))
    if out is not None:
        ss, seed, _ = out
        assert len(ss.plates) >= 2 and seed >= 0


DTYPES = ["<f8", "<f4", ">f8", "<i2", "<u2", "|u1", "|b1", "<c16"]


@st.composite
def map_case(draw):
    shape = (draw(st.integers(0, 7)), draw(st.integers(0, 7)))
    odd = st.sampled_from([np.nan, np.inf, -np.inf, 0.0, 1e-4])
    fill = st.floats(-1e-3, 1e-3) if draw(st.booleans()) else st.floats(-1e-2, 1e-2) | odd
    z = np.array(draw(st.lists(fill, min_size=math.prod(shape), max_size=math.prod(shape))))
    dtype = draw(st.sampled_from(DTYPES))
    with np.errstate(invalid="ignore", over="ignore"):
        z = z.reshape(shape).astype(dtype)
    opts = draw(
        st.fixed_dictionaries(
            {"pixel_m": st.sampled_from([1e-3, 2e-3, 1e-3, 1e-4, 0.0, -1.0, math.nan, "x"])},
            optional={
                "holes": st.booleans() | st.just("maybe"),
                "units": st.sampled_from(["m", "mm", "um", "in"]),
                "rotate_deg": st.sampled_from([0, 90, 45, 270]),
                "scale": st.sampled_from([1.0, 2.0, 0.0]),
            },
        )
    )
    return z, opts


def check_map(z: np.ndarray, opts: dict, raw: bytes | None) -> None:
    from sim_tactile.plates.parts.user import load_user_plate

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "map.npy"
        if raw is None:
            np.save(path, z)
        else:
            path.write_bytes(raw)
        plate = _read(lambda: load_user_plate(path, **opts))
    if plate is not None:
        t = plate.texture
        assert t.kind == "heightmap" and np.isfinite(np.nan_to_num(t.z, nan=0.0)).all()
        if not opts.get("holes"):
            assert not np.isnan(t.z).any()


def check_png(counts: np.ndarray, raw: bytes | None) -> None:
    from PIL import Image

    from sim_tactile.plates.parts.user import load_user_plate

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "map.png"
        if raw is None:
            Image.fromarray(counts).save(path)
        else:
            path.write_bytes(raw)
        plate = _read(lambda: load_user_plate(path, pixel_m=1e-3, z_scale_m=1e-8))
    if plate is not None:
        z = counts[::-1] * 1e-8  # rows run up the picture; lowest at 0
        assert np.array_equal(plate.texture.z, z - z.min())


pngs = st.tuples(st.integers(1, 6), st.integers(1, 6)).flatmap(
    lambda s: st.lists(st.integers(0, 65535), min_size=s[0] * s[1], max_size=s[0] * s[1]).map(
        lambda xs, s=s: np.array(xs, dtype=np.uint16).reshape(s)
    )
)
garbage = (
    st.none() | st.binary(max_size=200) | st.sampled_from([b"\x93NUMPY", b"\x89PNG\r\n\x1a\n"])
)


# ------------------------------------------------------------------------------ the tests
@FAST
@given(plate_data)
def test_fuzzed_plate_files(data):
    check_plate(data)


@FAST
@given(sensor_data)
def test_fuzzed_sensor_files(data):
    check_sensor(data)


@FAST
@given(config_data)
def test_fuzzed_configurations(data):
    with tempfile.TemporaryDirectory() as d:
        check_config(data, Path(d))


@FAST
@given(map_case(), garbage)
def test_fuzzed_npy_height_maps(case, raw):
    check_map(*case, raw)


@FAST
@given(pngs, garbage)
def test_fuzzed_png_height_maps(counts, raw):
    check_png(counts, raw)


@FAST
@given(st.binary(max_size=300) | st.text(max_size=200).map(str.encode))
def test_fuzzed_bytes_as_toml_files(raw):
    from sim_tactile.plates.read.files import load_plate_file
    from sim_tactile.sensors.files import load_sensor_file
    from sim_tactile.slides.config import load_config

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "f.toml"
        path.write_bytes(raw)
        for read in (load_plate_file, load_sensor_file, load_config):
            _read(lambda read=read: read(path))


@pytest.mark.slow
@SLOW
@given(plate_data, sensor_data, config_data)
def test_many_fuzzed_files(plate, sensor, config):
    check_plate(plate)
    check_sensor(sensor)
    with tempfile.TemporaryDirectory() as d:
        check_config(config, Path(d))


@pytest.mark.slow
@SLOW
@given(map_case(), garbage, pngs)
def test_many_fuzzed_height_maps(case, raw, counts):
    check_map(*case, raw)
    check_png(counts, None)
