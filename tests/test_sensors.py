"""Sensors: every layout on every plate family, transducer behaviour, the grating's spectral
peak, micro-roughness, seeded imperfections, real-data statistics, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sim_tactile.errors import ConfigError, UnknownNameError
from sim_tactile.sensors import Finger, Imperfections, get_sensor, sensor_names
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.slide import simulate

FAMILIES = [
    "finger7/flat",
    "finger7/ridges-4",
    "multilayer3/grating-9",
    "finger7/bumps-3x3",
    "roughness8/ra-25",
]
#: The papers' taxel counts and sampling rates [Hz] of their sensors.
EXPECTED_N = {"grid3x3": 9, "multilayer3x3x2": 18, "biotac19": 19, "icub60": 60, "pvdf2": 2}
EXPECTED_RATE = {
    "grid3x3": 100.0,
    "multilayer3x3x2": 100.0,
    "biotac19": 100.0,
    "icub60": 50.0,
    "pvdf2": 1000.0,
}
#: The issue's tolerance on the grating's spectral peak.
PEAK_RTOL = 0.03
GRATING_PERIOD_M = 4e-3


@pytest.mark.parametrize("plate", FAMILIES)
@pytest.mark.parametrize("sensor", sensor_names())
def test_every_layout_on_every_family(sensor, plate, cache):
    """Each sensor on each plate family, the protocol giving no rate: the recording has the
    paper's taxel count and is sampled at the paper's rate (the sensor's own)."""
    rec = simulate(plate, sensor, protocol=Protocol(duration_s=0.1), cache=cache).recording
    assert rec.data.shape == (round(0.1 * EXPECTED_RATE[sensor]), EXPECTED_N[sensor])
    assert rec.meta["rate_hz"] == EXPECTED_RATE[sensor]
    assert np.isfinite(rec.data).all()
    assert rec.units == get_sensor(sensor).units


def _steady(sensor: str, cache):
    proto = Protocol(speed_m_s=0.06, duration_s=1.0, rate_hz=EXPECTED_RATE[sensor])
    res = simulate("finger7/flat", sensor, protocol=proto, seed=5, cache=cache)
    return res.recording.data[10:].astype(float)  # after the 20 ms speed ramp


def test_piezoelectric_output_averages_to_zero_on_a_flat_slide(cache):
    y = _steady("pvdf2", cache)
    noise = get_sensor("pvdf2").imperfections.noise_std
    # a steady load reads zero: the mean is within 4 standard errors of the noise
    assert np.abs(y.mean(axis=0)).max() < 4 * noise / np.sqrt(len(y)) + 1e-4


@pytest.mark.parametrize("n", [1, 2, 250, 20_001])
def test_the_piezoelectric_high_pass_is_scipys_lfilter_bit_for_bit(n, monkeypatch):
    """The high-pass runs its own loop on a slide's samples (no scipy.signal to load) and
    lfilter on long recordings: both equal scipy.signal.lfilter, the reference, bit for bit,
    on loads of every scale; and a loop that skipped the state (a plain scale) would not be."""
    from scipy.signal import lfilter

    from sim_tactile.sensors import transducers

    rng = np.random.default_rng(n)
    # a few channels (each in Python's floats), many (numpy's rows), one (a 1-D recording)
    for shape in ((n, 3), (n, 40), (n,)):
        x = rng.lognormal(0.0, 2.0, shape) * rng.choice([-1.0, 1.0], shape)
        for a in (0.9937, 0.5, 1.0 / 3.0):
            ref = lfilter([a, -a], [1.0, -a], x, axis=0)
            got = transducers.high_pass(x, a)
            assert got.shape == ref.shape and got.dtype == ref.dtype, (shape, a)
            assert np.array_equal(got, ref), (shape, a)
            if n > 2:
                assert not np.allclose(got, a * np.diff(x, axis=0, prepend=0.0))
    if n == 250:  # the loop itself serves the long branch's lengths too
        monkeypatch.setattr(transducers, "HIGH_PASS_LOOP_MAX", 10**9)
        y = rng.normal(size=(3000, 2))
        assert np.array_equal(
            transducers.high_pass(y, 0.99), lfilter([0.99, -0.99], [1, -0.99], y, axis=0)
        )


@pytest.mark.parametrize("sensor", ["grid3x3", "icub60"])
def test_resistive_and_capacitive_hold_a_steady_level_plus_noise(sensor, cache):
    y = _steady(sensor, cache)
    imp = get_sensor(sensor).imperfections
    ideal = simulate(
        "finger7/flat",
        sensor,
        protocol=Protocol(speed_m_s=0.06, duration_s=1.0, rate_hz=EXPECTED_RATE[sensor]),
        ideal=True,
        seed=5,
        cache=cache,
    ).recording.data[10:]
    loaded = ideal.mean(axis=0) > 1e-4  # taxels in contact
    assert loaded.any()
    level = get_sensor(sensor).transducer.apply(ideal.mean(axis=0), EXPECTED_RATE[sensor])
    # level: within 5 noise std plus crosstalk and the drift over the second
    slack = 5 * imp.noise_std + 3 * imp.drift_std_per_sqrt_s + 0.05 * np.abs(level)
    assert np.all(np.abs(y.mean(axis=0) - level)[loaded] < slack[loaded])
    # fluctuation: the noise (quantisation and drift add a little), not a signal
    spread = y[:, loaded].std(axis=0)
    assert np.all(spread < 2.0 * imp.noise_std + imp.quant_step + 2 * imp.drift_std_per_sqrt_s)
    assert np.all(spread > 0.5 * imp.noise_std)


def _peak_frequency(y: np.ndarray, rate: float, band: tuple[float, float]) -> float:
    """The strongest spectral line of ``y`` within ``band`` [Hz]."""
    t = np.arange(len(y))
    y = y - np.polyval(np.polyfit(t, y, 1), t)  # the slow trend of entering the grating
    n = 16 * len(y)  # zero padding refines the peak's position
    spec = np.abs(np.fft.rfft(y * np.hanning(len(y)), n))
    f = np.fft.rfftfreq(n, 1 / rate)
    spec[(f < band[0]) | (f > band[1])] = 0
    return float(f[np.argmax(spec)])


@pytest.mark.parametrize("speed", [0.04, 0.065, 0.1])
def test_pvdf_film_across_the_slide_peaks_at_speed_over_period(speed, cache):
    rec = simulate(
        "multilayer3/grating-9",
        "pvdf2",
        protocol=Protocol(speed_m_s=speed, rate_hz=1000.0),
        cache=cache,
    ).recording
    # the film over the grating, away from its ends (where the pad tilts onto it)
    over = np.abs(np.asarray(rec.meta["x_pad_m"])) < 12e-3
    # the rate sensor sees each ridge's two edges: the strongest line between half the
    # grating's frequency and 2.5 times it is the grating's frequency or its second harmonic
    # (which wins at 40 mm/s under the held force). The band leaves out the slow trend and the
    # tone of the skin's nodes crossing the ridge edges (speed / node pitch, 7-8 times the
    # grating's frequency here), a discretisation artefact that the derivative amplifies.
    f0 = speed / GRATING_PERIOD_M
    f = _peak_frequency(rec.data[over, 0].astype(float), 1000.0, (0.5 * f0, 2.5 * f0))
    harmonic = round(f / f0)
    assert harmonic in (1, 2)
    assert f == pytest.approx(harmonic * f0, rel=PEAK_RTOL)


@pytest.mark.slow
def test_pvdf_rms_rises_monotonically_with_ra(cache):
    rms = []
    for ra in ("0.4", "0.8", "1.6", "3.2", "6.3", "12.5", "25", "50"):
        rec = simulate(
            f"roughness8/ra-{ra}",
            "pvdf2",
            protocol=Protocol(speed_m_s=0.24, rate_hz=1000.0),
            seed=3,
            cache=cache,
        ).recording
        over = np.abs(np.asarray(rec.meta["x_pad_m"])) < 12e-3
        rms.append(float(np.sqrt(np.mean(rec.data[over, 0].astype(float) ** 2))))
    assert all(b > a for a, b in zip(rms, rms[1:], strict=False)), rms


def test_a_seed_reproduces_every_imperfection(cache):
    proto = Protocol(duration_s=0.3)
    a = simulate(
        "finger7/ridges-2", "biotac19", protocol=proto, seed=11, cache=cache
    ).recording.data
    b = simulate(
        "finger7/ridges-2", "biotac19", protocol=proto, seed=11, cache=cache
    ).recording.data
    c = simulate(
        "finger7/ridges-2", "biotac19", protocol=proto, seed=12, cache=cache
    ).recording.data
    assert a.tobytes() == b.tobytes()
    assert not np.array_equal(a, c)
    imp = Imperfections(
        noise_std=0.1, quant_step=0.05, drift_std_per_sqrt_s=0.1, dead_fraction=0.3, crosstalk=0.1
    )
    x = np.ones((50, 9))
    pos = np.c_[np.arange(9) * 1e-3, np.zeros(9), np.zeros(9)]
    r1 = imp.apply(x, pos, 100.0, np.random.default_rng(1))
    r2 = imp.apply(x, pos, 100.0, np.random.default_rng(1))
    r3 = imp.apply(x, pos, 100.0, np.random.default_rng(2))
    assert np.array_equal(r1, r2) and not np.array_equal(r1, r3)
    assert (r1 == 0).all(axis=0).any()  # dead taxels read their constant


def _real_biotac(dataset_dir, n: int = 20) -> np.ndarray:
    files = sorted((dataset_dir / "raw_data").glob("mat*/mat*_bio.csv"))[:: max(1, 1000 // n)][:n]
    return np.array([np.genfromtxt(f, delimiter=",", skip_header=1)[100:500, 26:45] for f in files])


@pytest.mark.slow
def test_simulated_biotac_and_icub_look_like_the_real_data(cache, dataset_dir):
    """Same order of magnitude, noise level and rate as the real recordings."""
    real_b = _real_biotac(dataset_dir)
    real_i = (
        np.load(dataset_dir / "compiled_data" / "icub_test.npy")
        .reshape(200, 60, 75)
        .transpose(0, 2, 1)
    )
    for sensor, real, rate in (("biotac19", real_b, 100.0), ("icub60", real_i, 50.0)):
        sim = simulate("textures20/grating-3.0mm", sensor, cache=cache).recording
        assert sim.meta["rate_hz"] == rate
        s = sim.data.astype(float)
        mean_ratio = s.mean() / real.mean()
        assert 0.1 < mean_ratio < 10, (sensor, mean_ratio)
        assert 0 <= s.min() and s.max() <= 2 * real.max()
        noise_sim = np.median(np.diff(s, axis=0).std(axis=0))
        noise_real = np.median(np.diff(real, axis=1).std(axis=1))
        assert 0.5 < noise_sim / noise_real < 2.0, (sensor, noise_sim, noise_real)


def test_bad_input_is_refused(cache):
    with pytest.raises(UnknownNameError, match="not known"):
        simulate("finger7/flat", "biotac20")
    with pytest.raises(ConfigError, match="beyond the pad"):
        simulate("finger7/flat", "icub60", finger=Finger(), cache=cache)
    with pytest.raises(ConfigError, match="noise_std"):
        Imperfections(noise_std=-1.0)


def test_baselines_and_dead_taxels_belong_to_the_unit_not_the_slide():
    """Two slides of one sensor unit share its per-taxel baselines and dead taxels; noise is
    new in every slide; another unit has other baselines."""
    from sim_tactile.sensors.transducers import Imperfections

    pos = np.zeros((40, 3))
    y = np.ones((50, 40))
    imp = Imperfections(noise_std=0.1, offset_max=4.0, dead_fraction=0.2)
    a = imp.apply(y, pos, 100.0, np.random.default_rng(1))
    b = imp.apply(y, pos, 100.0, np.random.default_rng(2))
    dead_a, dead_b = np.all(a == 0.0, axis=0), np.all(b == 0.0, axis=0)
    assert dead_a.any() and np.array_equal(dead_a, dead_b)
    live = ~dead_a
    # per-taxel means agree to the noise's standard error; the slides' noise differs
    np.testing.assert_allclose(a[:, live].mean(0), b[:, live].mean(0), atol=0.1)
    assert not np.array_equal(a, b)
    other = Imperfections(noise_std=0.1, offset_max=4.0, dead_fraction=0.2, unit_seed=7)
    c = other.apply(y, pos, 100.0, np.random.default_rng(1))
    assert np.abs(c.mean(0) - a.mean(0)).max() > 0.5


def test_the_biotac_channels_have_one_name_in_data_calibration_and_simulation(tmp_path):
    """``ele1`` .. ``ele19`` everywhere: the real data's columns, the shipped calibration,
    the sensor (a simulated slide's ``channel_names``) and the traces figure's legend, which
    named them ``t0`` .. ``t18``; a recording that names no channels keeps ``t0``, ``t1``."""
    import sim_tactile.sensors as sensors_pkg
    from sim_tactile.datasets.real import BIOTAC_ELECTRODES
    from sim_tactile.records import Recording
    from sim_tactile.sensors.calibration import load_calibration
    from sim_tactile.sim.plots import channel_names, plot_traces

    names = list(BIOTAC_ELECTRODES)
    cal = load_calibration(Path(sensors_pkg.__file__).parent / "calibrations" / "biotac19.toml")
    assert list(cal.channels) == names == list(get_sensor("biotac19").layout.names)
    taxels = get_sensor("biotac19").layout.positions
    rec = Recording(np.zeros((4, 19), np.float32), np.arange(4) / 100.0, taxels, meta={})
    assert channel_names(rec)[:2] == ["t0", "t1"]
    named = Recording(rec.data, rec.times, taxels, meta={"channel_names": names})
    assert channel_names(named) == names
    assert plot_traces(named, tmp_path / "traces.png").is_file()
