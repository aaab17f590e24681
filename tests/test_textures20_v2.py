"""textures20-v2: slides that start and stay on a long textured strip, the long plates, and
the forces measured from the real recordings."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from conftest import _find_dataset as find_dataset

from sim_tactile.calibrate.motion import biotac_force, clip_level_variation
from sim_tactile.errors import ConfigError
from sim_tactile.plates import get_plate, preset_names, surface_of
from sim_tactile.plates.read.presets import LONG_AREA_M, LONG_FAMILY
from sim_tactile.sim.plan.protocol import START_MARGIN_M, Protocol, SlideWindow
from sim_tactile.slides.config import _protocol
from sim_tactile.tasks import get_task
from sim_tactile.tasks.defs import textures20 as t20

#: The real data set (conftest: $SIM_TACTILE_DATASETS, ../shared, /work/shared).
DATA = find_dataset()
LONG = [n for n in preset_names() if n.startswith(LONG_FAMILY)]
#: the long plates the fast lane checks; the others run in ``make test``
FAST = (LONG_FAMILY + "grating-3.0mm", LONG_FAMILY + "boxes-3.0mm")


def test_a_texture_start_keeps_the_pad_on_the_strip():
    plate = get_plate(LONG_FAMILY + "grating-3.0mm")
    pad = 0.022
    proto = Protocol(speed_m_s=0.025, duration_s=4.0, start="texture", rate_hz=100.0)
    w = SlideWindow.of(plate, pad, proto)
    assert w.x_start_m == pytest.approx(-LONG_AREA_M / 2 + pad / 2 + START_MARGIN_M)
    assert w.x_end_m == pytest.approx(-w.x_start_m) and w.x_limit_m == w.x_end_m
    assert w.n_samples == 400
    # the default start crosses from flat ground to flat ground, as before
    flat = SlideWindow.of(plate, pad, replace(proto, start="flat"))
    assert flat.x_start_m == pytest.approx(-LONG_AREA_M / 2 - pad / 2 - START_MARGIN_M)


def test_a_texture_start_names_what_it_needs():
    with pytest.raises(ConfigError, match="start = 'texture' needs duration_s"):
        Protocol(start="texture")
    with pytest.raises(ConfigError, match="start"):
        Protocol(start="middle", duration_s=1.0)
    short = get_plate("textures20/flat")
    with pytest.raises(ConfigError, match=r"too short for a 0.04 m pad to start on it; valid"):
        SlideWindow.of(short, 0.04, Protocol(duration_s=1.0, start="texture", rate_hz=50.0))
    assert _protocol({"start": "texture", "duration_s": 2.0}, {}).start == "texture"
    with pytest.raises(ConfigError, match="protocol.start must be a string"):
        _protocol({"start": 1, "duration_s": 2.0}, {})


def test_slide_keys_made_before_the_start_field_are_unchanged():
    assert "start" not in Protocol().to_json()
    assert Protocol(duration_s=1.0, start="texture").to_json()["start"] == "texture"


@pytest.mark.parametrize(
    "name", [n if n in FAST else pytest.param(n, marks=pytest.mark.slow) for n in LONG]
)
def test_each_long_plate_is_its_short_plate_extended(name):
    """Over the short plate's textured area the heights are the same (sampled off the
    feature edges); past it the long plate is still textured."""
    long, short = get_plate(name), get_plate(name.replace(LONG_FAMILY, "textures20/"))
    x = np.linspace(-0.018, 0.018, 721) + 3.7e-7
    X, Y = np.meshgrid(x, np.linspace(-0.018, 0.018, 49) + 2.9e-7)
    if "rough" in name:  # a new draw of the same statistics
        assert long.texture == short.texture and long.area_length_m == LONG_AREA_M
        return
    # equal to round-off (a drafted flank's height is computed from the feature's centre)
    np.testing.assert_allclose(
        surface_of(long).height(X, Y), surface_of(short).height(X, Y), rtol=0, atol=1e-12
    )
    if "flat" not in name:
        FX, FY = np.meshgrid(np.linspace(0.05, 0.07, 801), np.linspace(-0.018, 0.018, 145))
        assert surface_of(long).height(FX, FY).max() > 0


def test_a_v2_slide_stays_on_the_texture_for_its_window():
    from sim_tactile.sim.slide import simulate

    ss = get_task("textures20-biotac19-v2").get_data
    r = simulate(LONG_FAMILY + "grating-4.0mm", ss.sensor, protocol=ss.protocol, seed=2)
    x = np.asarray(r.recording.meta["x_pad_m"])
    pad = r.recording.meta["finger"]["size_m"][0]
    assert r.recording.data.shape == (400, 19)
    assert x.min() - pad / 2 > -LONG_AREA_M / 2 and x.max() + pad / 2 < LONG_AREA_M / 2
    speed = r.recording.meta["protocol"]["speed_m_s"]
    assert (x[-1] - x[0]) == pytest.approx(speed * 3.99, rel=0.01)
    assert not any("stopped" in w for w in r.recording.meta["warnings"])


def test_the_force_of_synthetic_slides_is_recovered():
    rng = np.random.default_rng(0)
    true = 0.5 * (1 + 0.2 * rng.standard_normal(400))
    forces = [np.concatenate([np.full(100, 2.0), np.full(400, f), np.zeros(100)]) for f in true]
    st = biotac_force(forces, 100.0, (1.0, 5.0))
    assert st.median_n == pytest.approx(np.median(true), rel=1e-9)
    assert st.cv == pytest.approx(true.std() / true.mean(), rel=1e-9) and st.n == 400
    with pytest.raises(ConfigError, match="slide 0 has 500 samples"):
        biotac_force([f[:500] for f in forces], 100.0, (1.0, 5.5))


def test_the_clip_level_variation_of_synthetic_clips_is_recovered():
    """Clips whose level scales with a per-clip force of known spread, per material."""
    rng = np.random.default_rng(1)
    R, T, C = 600, 75, 6
    labels = np.repeat(np.arange(6), 100)
    base = rng.uniform(10, 60, (6, C))
    force = 1 + 0.15 * rng.standard_normal(R)
    clips = base[labels][:, None, :] * force[:, None, None] * np.ones((R, T, C))
    lv = clip_level_variation(clips, labels, np.ones(C))
    assert lv.cv == pytest.approx(0.15, rel=0.15) and lv.n_classes == 6
    assert lv.within_clip_cv == pytest.approx(0.0, abs=1e-12)


@pytest.mark.slow
@pytest.mark.skipif(not DATA.is_dir(), reason=f"the real data set is not at {DATA}")
def test_the_v2_forces_are_the_ones_measured_on_the_real_data():
    from sim_tactile.calibrate import read_biotac_forces
    from sim_tactile.datasets.real import load_icub
    from sim_tactile.sensors.calibration import load_calibration

    _, forces, _ = read_biotac_forces(DATA)
    st = biotac_force(forces, 100.0, (1.0, 5.0))
    assert round(st.median_n, 2) == t20.BIOTAC_FORCE_N
    assert round(st.cv, 2) == t20.BIOTAC_PDC_FORCE_CV
    ds = load_icub(DATA)
    lv = clip_level_variation(ds.data, ds.labels, load_calibration("icub60").noise_std)
    assert round(lv.cv, 2) == t20.ICUB_LEVEL_CV
    assert round(lv.within_clip_cv, 3) == t20.ICUB_WITHIN_CLIP_CV
    assert get_task("textures20-icub60-v2").get_data.protocol.force_jitter == t20.ICUB_LEVEL_CV


@pytest.mark.slow
def test_run_textures20_v2_quick(tmp_path, cli):
    p = cli(
        ["run", "textures20-v2", "--quick", "--out", str(tmp_path), "--json"]
        + ([] if _has_torch() else ["--classifiers", "svm-raw,svm-spike"]),
        check=False,
    )
    assert p.returncode == 0, p.stderr
    doc = json.loads(p.stdout)
    parts = {r["part"] for r in doc["results"]}
    assert parts == {"textures20-biotac19-v2", "textures20-icub60-v2"}
    for part, window in (("textures20-biotac19-v2", 4.0), ("textures20-icub60-v2", 1.5)):
        sub = json.loads((tmp_path / part / "report.json").read_text())
        assert sub["dataset"]["classes"] == 4 and sub["dataset"]["samples"] == 12
        assert sub["dataset"]["duration_s"] == window  # the paper's window, all on texture
    # four classes: the best row is above chance
    assert max(r["accuracy_mean"] for r in doc["results"]) > 0.25


def _has_torch() -> bool:
    try:
        import torch  # noqa: F401
    except ImportError:
        return False
    return True
