"""Sensor calibration against recordings: the fit recovers known parameters, the file is
data, and a calibrated sensor simulates with the fitted gains."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from _blas import BLAS_RTOL, run_under_other_kernel
from conftest import _find_dataset as find_dataset

from sim_tactile.calibrate import calibrate, from_fit
from sim_tactile.calibrate.fit import RECTIFIED_DIFF, fit_readout, fit_unforced
from sim_tactile.calibrate.forced import fit_channels
from sim_tactile.cli import main
from sim_tactile.errors import ConfigError
from sim_tactile.sensors import get_sensor
from sim_tactile.sensors.calibration import Calibration, calibrated, load_calibration
from sim_tactile.sensors.transducers import Imperfections

#: The real data set (conftest: $SIM_TACTILE_DATASETS, ../shared, /work/shared).
DATA = find_dataset()
#: The issue's bar for recovering known parameters from synthetic recordings.
RECOVERY_RTOL = 0.05
RATE = 100.0


def _synthetic(seed=0, n_rec=120, C=4):
    """Recordings of a sensor with known parameters: the force rises from rest, wanders
    for a few seconds and returns to rest; each channel is offset + gain * force + a random
    walk + white noise, quantised to 1 count and clipped at 0."""
    rng = np.random.default_rng(seed)
    gain = np.array([60.0, 12.0, 25.0, 5.0])[:C]
    offset = np.array([6.0, 4.0, 5.0, 8.0])[:C]
    noise = np.array([0.9, 1.5, 0.7, 1.2])[:C]
    drift = np.array([0.3, 0.0, 0.6, 0.2])[:C]
    levels, forces = [], []
    for _ in range(n_rec):
        T = int(rng.integers(500, 800))
        t = np.arange(T) / RATE
        on, off = rng.uniform(0.8, 1.5), rng.uniform(4.0, 5.5)
        shape = np.clip((t - on) / 0.2, 0, 1) * np.clip((off - t) / 0.2, 0, 1)
        f = shape * (
            0.5 + 0.3 * np.sin(2 * np.pi * t / rng.uniform(1, 3)) + 0.05 * rng.standard_normal(T)
        )
        f = np.maximum(f, 0.0)
        walk = np.cumsum(rng.standard_normal((T, C)), axis=0) * drift / np.sqrt(RATE)
        x = offset + np.outer(f, gain) + walk + noise * rng.standard_normal((T, C))
        levels.append(np.maximum(np.round(x), 0.0))
        forces.append(np.round(100 * f) / 100)  # pdc: 100 counts per newton, whole counts
    return levels, forces, dict(gain=gain, offset=offset, noise=noise, drift=drift)


def _of_fit(fit, n: int) -> Calibration:
    """A calibration of four channels from a fit (its shares and gains placeholders)."""
    lists = ("counts_per_n", "offset", "noise_std", "drift_per_s", "r2")
    return Calibration(
        "s",
        ("a", "b", "c", "d"),
        n,
        0.5,
        *(tuple(getattr(fit, k)) for k in lists),
        (0.1,) * 4,
        (1.0,) * 4,
        quant_step=fit.quant_step,
        stretch_s=fit.stretch_s,
    )


def test_the_fit_recovers_known_gains_offsets_noise_and_step():
    levels, forces, truth = _synthetic()
    fit = fit_channels(levels, forces, RATE, floor=0.0)
    np.testing.assert_allclose(fit.counts_per_n, truth["gain"], rtol=RECOVERY_RTOL)
    # the fit reports the noise as recorded (quantised): sqrt(sigma^2 + 1/12)
    recorded = np.sqrt(truth["noise"] ** 2 + 1 / 12)
    np.testing.assert_allclose(fit.noise_std, recorded, rtol=RECOVERY_RTOL)
    np.testing.assert_allclose(fit.offset, truth["offset"], atol=0.5)
    assert fit.quant_step == 1.0
    # and the model noise undoes the quantisation
    cal = _of_fit(fit, len(levels))
    np.testing.assert_allclose(cal.noise_model, truth["noise"], rtol=RECOVERY_RTOL)


def test_the_drift_of_a_random_walk_is_recovered_as_its_rate():
    """The quiet stretches' slopes, beyond what the noise gives them, are a random walk's
    of rate r (a slope over L seconds has variance 6 r^2 / (5 L)): the fitted rate is the
    walk's (from about 470 quiet stretches: within 10-20% here)."""
    levels, forces, truth = _synthetic(seed=1, n_rec=250)
    fit = fit_channels(levels, forces, RATE, floor=0.0)
    cal = _of_fit(fit, len(levels))
    got = np.array(cal.drift_model)
    for k in (0, 2, 3):
        assert got[k] == pytest.approx(truth["drift"][k], rel=0.25), (k, got)
    assert got[1] < 0.08  # no drift: what remains is the estimate's noise


def test_the_fit_needs_quiet_stretches_and_matching_shapes():
    """A force that rests at 1 N is a tare, found; one that never rests leaves nothing to
    fit the rest levels on."""
    levels, forces, truth = _synthetic(n_rec=40)
    fit = fit_channels(levels, [f + 1.0 for f in forces], RATE, floor=0.0)
    assert fit.force_rest.level == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(fit.counts_per_n, truth["gain"], rtol=RECOVERY_RTOL)
    with pytest.raises(ConfigError, match="no quiet stretch"):
        fit_channels([x[200:380] for x in levels], [f[200:380] for f in forces], RATE)
    with pytest.raises(ConfigError, match="levels .* and force"):
        fit_channels(levels, [f[:-1] for f in forces], RATE)


def _cal(**kw) -> Calibration:
    n = 19
    base = dict(
        sensor="biotac19",
        channels=tuple(f"ele{k}" for k in range(1, n + 1)),
        n_recordings=10,
        force_n=0.4,
        counts_per_n=(10.0,) * n,
        offset=(1.0,) * n,
        noise_std=(0.6,) * n,
        drift_per_s=(0.3,) * n,
        r2=(0.5,) * n,
        force_share=(0.02,) * n,
        gain=(500.0,) * n,
        quant_step=1.0,
        stretch_s=1.5,
        source="test",
    )
    return Calibration(**(base | kw))


def test_the_file_round_trips_and_bad_files_name_what_is_wrong(tmp_path):
    cal = _cal(notes=("a note",))
    path = cal.write(tmp_path / "c.toml")
    assert load_calibration(path) == cal
    text = path.read_text()
    for bad, msg in [
        (text.replace("noise_std = [0.6,", "noise_std = [-0.6,"), r"calibration.noise_std\[0\]"),
        (text.replace("format = 1", "format = 7"), "format = 7"),
        (text + "pickle = 1\n", "unknown key"),
        (text.replace("gain = [500.0, ", "gain = ["), "gain has 18 values"),
        ("sensor = [", "not valid TOML"),
    ]:
        p = tmp_path / "bad.toml"
        p.write_text(bad)
        with pytest.raises(ConfigError, match=msg):
            load_calibration(p)
    # a multiplexed readout round-trips; without one the file has no readout keys
    assert "readout" not in text
    mux = _cal(readout_period=6, readout_phase=(0, 3) * 9 + (0,), readout_leak=0.001)
    again = load_calibration(mux.write(tmp_path / "m.toml"))
    assert again == mux
    assert calibrated(get_sensor("biotac19"), again).imperfections.readout_phase[1] == 3
    mtext = (tmp_path / "m.toml").read_text()
    for bad, msg in [
        (
            mtext.replace("readout_phase = [0, 3,", "readout_phase = [0, 7,"),
            r"calibration.readout_phase\[1\] = 7 is out of range; valid: \[0, 5\]",
        ),
        (
            mtext.replace("readout_phase = [0, 3,", "readout_phase = ["),
            "readout_phase has 17 values; valid: none, or one per channel",
        ),
        (mtext.replace("readout_period = 6", "readout_period = 0"), "readout_period = 0"),
    ]:
        p = tmp_path / "bad.toml"
        p.write_text(bad)
        with pytest.raises(ConfigError, match=msg):
            load_calibration(p)
    with pytest.raises(ConfigError, match="ending in .toml"):
        cal.write(tmp_path / "c.txt")
    with pytest.raises(ConfigError, match="does not exist"):
        load_calibration(tmp_path / "none.toml")


def test_a_calibrated_sensor_carries_the_fitted_gains_and_noise():
    sen = calibrated(get_sensor("biotac19"), _cal(gain=tuple(float(g) for g in range(100, 119))))
    assert sen.transducer.gain_counts_per_n[3] == 103.0
    assert sen.imperfections.quant_step == 1.0
    assert sen.imperfections.noise_std[0] == pytest.approx(np.sqrt(0.36 - 1 / 12))
    loads = np.full((50, 19), 0.01)
    out = sen.transduce(loads, 100.0, np.random.default_rng(0))
    # gain * load + offset, give or take the noise
    np.testing.assert_allclose(out.mean(axis=0), np.arange(100, 119) * 0.01 + 1.0, atol=0.5)
    with pytest.raises(ConfigError, match="cannot calibrate 'icub60'"):
        calibrated(get_sensor("icub60"), _cal())
    with pytest.raises(ConfigError, match="PiezoResistive transducer"):
        calibrated(
            get_sensor("grid3x3"),
            _cal(
                sensor="grid3x3",
                channels=tuple("abcdefghi"),
                **{
                    k: (1.0,) * 9
                    for k in (
                        "counts_per_n",
                        "offset",
                        "noise_std",
                        "drift_per_s",
                        "r2",
                        "force_share",
                        "gain",
                    )
                },
            ),
        )
    with pytest.raises(ConfigError, match="imperfections.noise_std has 2 values"):
        Imperfections(noise_std=(1.0, 2.0)).apply(
            np.zeros((5, 3)), np.zeros((3, 3)), 100.0, np.random.default_rng(0)
        )


def test_the_shipped_biotac_calibration_loads_by_name():
    from sim_tactile.sensors.calibration import calibration_names

    assert "biotac19" in calibration_names()
    cal = load_calibration("biotac19")
    assert cal.n_recordings == 1000 and "pdc" in cal.source
    sen = calibrated(get_sensor("biotac19"), cal)
    assert len(sen.transducer.gain_counts_per_n) == 19
    with pytest.raises(ConfigError, match="shipped calibration"):
        load_calibration("pvdf2")


def _unforced(seed=0, n_rec=600, T=75, readout=None):
    """Clips of a sensor with no force recorded: each channel rests at 0 with Gaussian noise
    of a known deviation, clipped at 0; in a third of the clips it is in contact at a known
    steady level (with the same noise). ``readout = (period, phase, leak)``: the level comes
    through a multiplexed readout, on one sample in ``period`` at ``(shift + phase[c]) %
    period`` (the shift drawn per clip) and ``leak`` of it between; noise on every sample."""
    rng = np.random.default_rng(seed)
    sigma = np.array([0.6, 1.0, 1.5, 2.2])
    level = np.array([20.0, 45.0, 30.0, 60.0])
    out = []
    for _ in range(n_rec):
        contact = rng.random(4) < 1 / 3
        signal = np.broadcast_to(np.where(contact, level, 0.0), (T, 4))
        if readout is not None:
            period, phase, leak = readout
            shift = rng.integers(period)
            on = (np.arange(T)[:, None] - shift - np.asarray(phase)[None, :]) % period == 0
            signal = signal * np.where(on, 1.0, leak)
        out.append(np.maximum(signal + sigma * rng.standard_normal((T, 4)), 0.0))
    return out, sigma, level


def test_the_unforced_fit_recovers_noise_and_steady_levels_under_the_assumed_force():
    levels, sigma, level = _unforced()
    fit = fit_unforced(levels, 50.0, 2.0)
    np.testing.assert_allclose(fit.noise_std, sigma, rtol=RECOVERY_RTOL)
    np.testing.assert_allclose(fit.counts_per_n, level / 2.0, rtol=RECOVERY_RTOL)
    assert (fit.offset == 0).all() and fit.quant_step == 0.0 and (fit.r2 == 0).all()
    np.testing.assert_array_less(fit.drift_per_s, 0.2)  # none was put in
    # the clipping matters: the plain spread of the quiet differences is 0.58 of the noise
    quiet = [x[:, 0] for x in levels if x[:, 0].max() < 4 * sigma[0]]
    plain = np.diff(np.concatenate(quiet)).std() / np.sqrt(2)
    assert plain == pytest.approx(RECTIFIED_DIFF * sigma[0], rel=0.1)
    with pytest.raises(ConfigError, match="force_n = 0.*valid: > 0 N"):
        fit_unforced(levels, 50.0, 0.0)
    with pytest.raises(ConfigError, match="fewer than 2 quiet"):
        fit_unforced([x + 100.0 for x in levels[:10]], 50.0, 1.0)


@pytest.mark.parametrize("period, phase", [(6, (0, 3, 0, 3)), (4, (1, 0, 2, 1)), (5, (0, 0, 4, 2))])
def test_the_readout_cycle_of_multiplexed_clips_is_recovered(period, phase):
    """Period, each channel's phase relative to the most often loaded one, and the leak."""
    levels, sigma, level = _unforced(seed=1, n_rec=400, readout=(period, phase, 0.02))
    fit = fit_unforced(levels, 50.0, 1.0)
    r = fit_readout(levels, fit.noise_std)
    assert r.period == period
    ref = int(
        np.argmax(
            [sum(x[:, c].max() >= 8 * s for x in levels) for c, s in enumerate(fit.noise_std)]
        )
    )
    assert r.phase == tuple((p - phase[ref]) % period for p in phase)
    assert r.leak == pytest.approx(0.02, abs=0.005)
    assert r.contrast > 0.8 * period
    # the steady level is the loaded phase's
    np.testing.assert_allclose(fit.counts_per_n, level, rtol=RECOVERY_RTOL)


def test_clips_read_on_every_sample_have_no_readout_cycle():
    levels, _, _ = _unforced()
    r = fit_readout(levels, fit_unforced(levels, 50.0, 1.0).noise_std)
    assert r.period == 1 and r.phase == () and r.leak == 0.0


def test_the_readout_gate_keeps_one_sample_in_the_period_and_draws_only_when_multiplexed():

    y = np.full((24, 4), 10.0)
    pos = np.zeros((4, 3))
    plain = Imperfections(noise_std=0.5)
    a = plain.apply(y, pos, 50.0, np.random.default_rng(3))
    b = plain.apply(y, pos, 50.0, np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)
    assert "readout_period" not in plain.to_json()  # keys made before the readout stay
    mux = Imperfections(readout_period=6, readout_phase=(0, 3, 0, 3), readout_leak=0.1)
    out = mux.apply(y, pos, 50.0, np.random.default_rng(3))
    on = out == 10.0
    assert (on.sum(axis=0) == 4).all() and np.allclose(out[~on], 1.0)
    t0 = np.flatnonzero(on[:, 0])
    np.testing.assert_array_equal(np.diff(t0), 6)
    np.testing.assert_array_equal(np.flatnonzero(on[:, 1]), (t0 + 3) % 6 + np.arange(4) * 6)
    np.testing.assert_array_equal(on[:, 0], on[:, 2])
    with pytest.raises(
        ConfigError, match=r"readout_phase\[1\] = 6 is out of range; valid: \[0, 5\]"
    ):
        Imperfections(readout_period=6, readout_phase=(0, 6))
    with pytest.raises(ConfigError, match="readout_phase has 2 values; valid: one per channel"):
        Imperfections(readout_period=6, readout_phase=(0, 3)).apply(
            y, pos, 50.0, np.random.default_rng(0)
        )


def test_from_fit_borrows_the_gain_of_channels_the_press_does_not_load():
    levels, forces, _ = _synthetic(n_rec=40)
    fit = fit_channels(levels, forces, RATE, floor=0.0)
    sen = replace(get_sensor("biotac19"))
    # four fitted channels stand in for the first four electrodes; the rest are unloaded
    fit = replace(
        fit,
        **{
            k: np.concatenate([getattr(fit, k), np.zeros(15)])
            for k in (
                *("counts_per_n", "offset", "r2", "noise_std", "drift_per_s"),
                *("intercept", "at_floor"),
            )
        },
    )
    share = np.concatenate([[0.1, 0.2, 0.0, 0.05], np.zeros(15)])
    cal = from_fit(sen, fit, share, 40, "synthetic")
    assert cal.gain[0] == pytest.approx(fit.counts_per_n[0] / 0.1)
    assert cal.gain[2] == pytest.approx(np.median([cal.gain[0], cal.gain[1], cal.gain[3]]))
    assert "ele3" in cal.notes[-1]


def _same_fit(a: Calibration, b: Calibration) -> None:
    """Two fits of the same recordings agree within what a BLAS kernel moves (BLAS_RTOL)."""
    for k in ("counts_per_n", "gain", "noise_std", "offset", "drift_per_s", "force_share"):
        x, y = np.asarray(getattr(a, k)), np.asarray(getattr(b, k))
        np.testing.assert_allclose(
            x, y, rtol=BLAS_RTOL, atol=BLAS_RTOL * np.abs(y).max(), err_msg=k
        )
    assert a.readout_phase == b.readout_phase and a.readout_period == b.readout_period


@pytest.mark.slow
@pytest.mark.skipif(not DATA.is_dir(), reason=f"the real data set is not at {DATA}")
def test_calibrate_biotac_on_the_real_recordings(tmp_path):
    """On the public BioTac slides (pdc: 100 counts per newton): the electrodes 1 and 11 that
    the force moves most, a one-count ADC, a noise floor under two counts; the CLI writes the
    file and prints the fit's keys, and simulate takes the file."""
    out = tmp_path / "biotac19.toml"
    assert main(["calibrate", "biotac19", "--data", str(DATA), "--out", str(out), "--json"]) == 0
    cal = load_calibration(out)
    order = np.argsort(cal.counts_per_n)[::-1]
    assert {cal.channels[order[0]], cal.channels[order[1]]} == {"ele1", "ele11"}
    assert min(cal.counts_per_n[0], cal.counts_per_n[10]) > 40
    assert cal.quant_step == 1.0 and all(0.2 < s < 2.0 for s in cal.noise_std)
    assert cal.n_recordings == 1000
    # the electrodes rest at the floor (offsets are rest levels, no longer line intercepts),
    # pdc's tare is within a count of 0, and the glitch on ele7-10 is no drift
    assert all(-0.5 < o < 2.0 for o in cal.offset)
    (tare,) = [n for n in cal.notes if "tare" in n]
    assert abs(float(tare.split("found in the data: ")[1].split(" N")[0])) < 0.01
    assert max(cal.drift_per_s[6:10]) < 0.3
    (bent,) = [n for n in cal.notes if n.startswith("not linear from rest")]
    assert all(f"'ele{k}'" in bent for k in (8, 9, 10, 17))
    # the calibration that ships is this fit (regenerate it with the same command if not),
    # and so is the fit under another BLAS kernel, as on another machine: within BLAS_RTOL
    shipped = load_calibration("biotac19")
    _same_fit(shipped, cal)
    code = "import sys\nfrom sim_tactile.cli import main\nassert main(sys.argv[1:]) == 0"
    there = tmp_path / "there.toml"
    run_under_other_kernel(code, "calibrate", "biotac19", "--data", str(DATA), "--out", str(there))
    _same_fit(load_calibration(there), cal)
    rec = tmp_path / "r.npz"
    args = [
        "simulate",
        "--plate",
        "textures20/grating-3.0mm",
        "--sensor-config",
        str(out),
        "--speed",
        "0.025",
        "--force",
        "0.5",
        "--duration",
        "1.0",
        "--out",
        str(rec),
    ]
    assert main(args) == 0
    data = np.load(rec, allow_pickle=False)["data"]
    assert data.max() > 10  # counts of the calibrated gains, not of the default


@pytest.mark.slow
@pytest.mark.skipif(not DATA.is_dir(), reason=f"the real data set is not at {DATA}")
def test_calibrate_icub_on_the_real_clips(tmp_path):
    """On the public iCub clips (no force): noise floors of about a count, steady levels of
    tens of counts; the shipped calibration is this fit, and it names its free parameter."""
    out = tmp_path / "icub60.toml"
    assert main(["calibrate", "icub60", "--data", str(DATA), "--out", str(out)]) == 0
    cal = load_calibration(out)
    assert cal.n_recordings == 1000 and cal.quant_step == 0.0
    assert all(0.3 < s < 4.0 for s in cal.noise_std)
    assert all(5.0 < c < 100.0 for c in cal.counts_per_n)
    assert "free parameter" in cal.notes[0] and "assumed 1 N" in cal.notes[0]
    # the clips' readout: a loaded taxel reads on one sample in six, the patches alternate
    assert cal.readout_period == 6 and cal.readout_leak < 0.01
    assert set(cal.readout_phase) == {0, 3}
    assert all(cal.readout_phase[10 * m] == 3 * (m % 2) for m in range(6))
    _same_fit(load_calibration("icub60"), cal)


def test_calibrate_json_has_the_contract_keys(tmp_path, capsys, monkeypatch):
    import sim_tactile.calibrate as cb

    monkeypatch.setattr(cb, "calibrate", lambda sensor, data: _cal())
    out = tmp_path / "c.toml"
    assert (
        main(["calibrate", "biotac19", "--data", str(tmp_path), "--out", str(out), "--json"]) == 0
    )
    doc = json.loads(capsys.readouterr().out)
    for k in (
        "sensor",
        "channels",
        "n_recordings",
        "counts_per_n",
        "noise_std",
        "offset",
        "drift_per_s",
        "out",
    ):
        assert k in doc
    assert len(doc["counts_per_n"]) == len(doc["channels"]) == 19 and doc["out"] == str(out)
    with pytest.raises(ConfigError, match="no real-data reader"):
        calibrate("grid3x3", tmp_path)


def test_a_task_runs_with_a_sensor_config_and_its_slides_are_keyed_by_it(tmp_path):
    from sim_tactile.tasks import get_task
    from sim_tactile.tasks.registry import with_calibration

    spec = get_task("textures20-biotac19-v1")
    cal = _cal()
    cspec = with_calibration(spec, cal)
    assert cspec.get_data.sensor_def().transducer.gain_counts_per_n == cal.gain
    assert cspec.get_data.describe() != spec.get_data.describe()
    assert "calibrated" in cspec.remarks[-1]
    with pytest.raises(
        ConfigError, match="calibrates 'biotac19'; task finger7-v1 simulates 'grid3x3'"
    ):
        with_calibration(get_task("finger7-v1"), cal)
    with pytest.raises(ConfigError, match="suite"):
        with_calibration(get_task("textures20-v1"), cal)


def test_the_level_under_clipped_noise_inverts_the_clipped_mean():
    """Against the mean of max(mu + sigma n, 0) integrated by scipy."""
    from scipy import integrate, stats

    from sim_tactile.calibrate.fit import clipped_mean_level

    mus, sigmas = np.array([0.0, 0.3, 2.0, 15.0]), np.array([1.0, 0.6, 1.5, 2.0])
    means = [
        integrate.quad(lambda x, mu=mu, s=s: max(x, 0.0) * stats.norm.pdf(x, mu, s), -50, 80)[0]
        for mu, s in zip(mus, sigmas, strict=True)
    ]
    np.testing.assert_allclose(clipped_mean_level(np.array(means), sigmas), mus, atol=1e-6)
    assert clipped_mean_level(np.array([0.1]), np.array([1.0]))[0] == pytest.approx(0.0, abs=1e-9)
