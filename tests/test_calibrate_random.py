"""``calibrate biotac19`` recovers the sensor that made a recording, on recordings the rest of
the suite did not make: this module's own generator draws a BioTac-like sensor and a
protocol at random (seeded, so each run is the same), writes the data set's CSV files, and
the whole command path (the real loader, the fit, the calibration) must find every gain,
offset and noise within 5%, draw after draw: continuous readings and whole counts, a pdc
resting at 0 (clipped there) and one resting at a tare.

The generator differs from tests/test_calibrate_rest.py's on purpose: a dozen slides of
6 s, each with half a second of rest at either end only (about 1,200 rest samples a
channel), pressed with a ramp of its own length, a force level and texture of its own,
and no drift; noise of 0.5-2 counts (at least half the ADC step of 1 where it rounds: below
that, whole counts hide most of a Gaussian; one of 0.3 counts about a whole count rounds to
it nine times in ten) and gains of 10-120 counts per newton (the press moves every channel
by several of its noise deviations).

Also here: the contact fit's parts (the one-factor fit against scikit-learn's, the gate that
keeps a bent channel's contact residual out of its noise) and the fit under another BLAS
kernel (the same within ``BLAS_RTOL``, as on another machine).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import sim_tactile.calibrate as cb
from sim_tactile.calibrate import calibrate

#: The issue's bar for every gain, offset and noise, on every draw.
RECOVERY_RTOL = 0.05
#: BioTac sample rate [Hz], slides, their length [samples] and rest at either end [samples].
RATE_HZ, N_SLIDES, N_SAMPLES, N_REST = 100.0, 12, 600, 50
N_ELECTRODES = 19
#: pdc counts per newton of normal force (the data set's, and calibrate's).
PDC_PER_N = 100.0
#: The draws: a seed each, and which of the four kinds it is (rounded to whole counts or
#: not; pdc resting at a tare or at 0, where it is clipped), each kind twice.
DRAWS = [(seed, bool(seed % 2), seed % 4 >= 2) for seed in range(8)]
COLUMNS = (
    ["timestamp", "tdc", "tac", "pdc"]
    + [f"pac{k}" for k in range(1, 23)]
    + [f"ele{k}" for k in range(1, N_ELECTRODES + 1)]
)


def _sensor(rng: np.random.Generator, tare: bool) -> dict:
    """Per electrode a gain [counts/N] (log-uniform: weak and strong alike), an offset
    (the rest level) [counts] and a white noise SD [counts]; pdc's tare and noise
    [counts]; the slides' typical force [N]."""
    return dict(
        gain=np.exp(rng.uniform(np.log(10.0), np.log(120.0), N_ELECTRODES)),
        offset=rng.uniform(15.0, 90.0, N_ELECTRODES),
        noise=rng.uniform(0.5, 2.0, N_ELECTRODES),
        tare=rng.uniform(5.0, 60.0) if tare else 0.0,
        pdc_noise=rng.uniform(0.3, 2.0),
        force_n=rng.uniform(0.3, 1.0),
    )


def _force(rng: np.random.Generator, level_n: float) -> np.ndarray:
    """One slide's true normal force [N] (N_SAMPLES,): at rest (0) for N_REST samples at
    either end; between, a ramp up and down of 0.1-0.4 s each, the level times a texture
    (a 3-25 Hz sine of 5-40%) and a slow wave (0.1-0.5 Hz, up to 30%)."""
    n = N_SAMPLES - 2 * N_REST
    i = np.arange(n)
    t = i / RATE_HZ
    up, down = rng.integers(10, 41, 2)
    ramp = np.minimum(np.minimum(i / up, (n - 1 - i) / down), 1.0)
    texture = rng.uniform(0.05, 0.4) * np.sin(
        2 * np.pi * rng.uniform(3, 25) * t + rng.uniform(0, 7)
    )
    slow = rng.uniform(0.0, 0.3) * np.sin(2 * np.pi * rng.uniform(0.1, 0.5) * t)
    press = np.maximum(level_n * (1.0 + texture + slow) * ramp, 0.0)
    return np.concatenate([np.zeros(N_REST), press, np.zeros(N_REST)])


def write_recordings(root: Path, seed: int, rounded: bool, tare: bool) -> dict:
    """The draw's sensor, and its slides written as the data set's CSV files
    (``raw_data/mat1/mat1_N_bio.csv``): electrodes = offset + gain * force + noise, pdc =
    tare + 100 * force + noise, both clipped at 0 and, where ``rounded``, in whole counts."""
    rng = np.random.default_rng(seed)
    truth = _sensor(rng, tare)
    for s in range(1, N_SLIDES + 1):
        force = _force(rng, truth["force_n"] * rng.uniform(0.8, 1.25))
        ele = truth["offset"] + np.outer(force, truth["gain"])
        ele = ele + truth["noise"] * rng.standard_normal(ele.shape)
        pdc = (
            truth["tare"] + PDC_PER_N * force + truth["pdc_noise"] * rng.standard_normal(N_SAMPLES)
        )
        if rounded:
            ele, pdc = np.round(ele), np.round(pdc)
        rows = np.zeros((N_SAMPLES, len(COLUMNS)))
        rows[:, 0] = 1.6e9 + np.arange(N_SAMPLES) / RATE_HZ
        rows[:, 3] = np.maximum(pdc, 0.0)
        rows[:, 26:] = np.maximum(ele, 0.0)
        path = root / "raw_data" / "mat1" / f"mat1_{s}_bio.csv"
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savetxt(path, rows, fmt="%.6f", delimiter=",", header=",".join(COLUMNS), comments="")
    return truth


def _relative_errors(cal, truth) -> dict[str, np.ndarray]:
    return {
        "gain": np.asarray(cal.counts_per_n) / truth["gain"] - 1.0,
        "offset": np.asarray(cal.offset) / truth["offset"] - 1.0,
        "noise": np.asarray(cal.noise_model) / truth["noise"] - 1.0,
    }


@pytest.mark.parametrize("seed, rounded, tare", DRAWS)
def test_calibrate_recovers_a_drawn_sensor_within_5_percent(
    tmp_path, monkeypatch, seed, rounded, tare
):
    """Every gain, offset and noise within 5% (measured over seeds 0-99: gains within
    2.8%, offsets 0.8%, noise 4.4%, the noise's SD 1.2%), the tare within a count, and a
    step only where the readings are whole counts. The simulated press that gives each
    taxel's load share is replaced by a fixed share: it is not what is tested."""
    truth = write_recordings(tmp_path, seed, rounded, tare)
    monkeypatch.setattr(cb, "force_share", lambda sensor, plate, force_n: np.full(19, 0.02))
    cal = calibrate("biotac19", tmp_path, materials=1)
    assert cal.quant_step == (1.0 if rounded else 0.0)
    (note,) = [n for n in cal.notes if "found in the data" in n]
    tare_n = float(note.split("found in the data: ")[1].split(" N")[0])
    assert tare_n * PDC_PER_N == pytest.approx(truth["tare"], abs=1.0)
    for name, err in _relative_errors(cal, truth).items():
        worst = int(np.argmax(np.abs(err)))
        assert abs(err[worst]) <= RECOVERY_RTOL, (name, worst, float(err[worst]))


#: What the machine comparison holds: every per-channel array of the fit, and its scalars.
FIT_FIELDS = ("counts_per_n", "offset", "noise_std", "drift_per_s", "r2", "intercept", "force_n")
_FIT_CODE = """
import json, sys
import numpy as np
from sim_tactile.calibrate import read_biotac_forces
from sim_tactile.calibrate.forced import fit_channels
levels, forces, _ = read_biotac_forces(sys.argv[1], materials=1)
fit = fit_channels(levels, forces, 100.0, floor=0.0, force_floor=0.0)
print(json.dumps({k: np.atleast_1d(getattr(fit, k)).tolist() for k in sys.argv[2:]}))
"""


@pytest.mark.slow
def test_the_fit_is_the_same_under_another_blas_kernel(tmp_path):
    """The fit of a draw in whole counts with pdc clipped at 0 (the clipped rest's bounded
    search, the contact's eigenproblems) in this process and in a fresh one under another
    OpenBLAS kernel (``OPENBLAS_CORETYPE``): equal within BLAS_RTOL, as on another machine."""
    from _blas import BLAS_RTOL, run_under_other_kernel

    from sim_tactile.calibrate import read_biotac_forces
    from sim_tactile.calibrate.forced import fit_channels

    write_recordings(tmp_path, 1, rounded=True, tare=False)
    levels, forces, _ = read_biotac_forces(tmp_path, materials=1)
    fit = fit_channels(levels, forces, RATE_HZ, floor=0.0, force_floor=0.0)
    assert fit.in_contact.all() and fit.force_rest.at_floor > 0.5  # both paths taken
    kernel, out = run_under_other_kernel(_FIT_CODE, str(tmp_path), *FIT_FIELDS)
    there = json.loads(out.strip().splitlines()[-1])
    for k in FIT_FIELDS:
        here = np.atleast_1d(getattr(fit, k))
        np.testing.assert_allclose(
            there[k], here, rtol=BLAS_RTOL, atol=BLAS_RTOL * np.abs(here).max(), err_msg=k
        )


def test_the_one_factor_fit_is_scikit_learns():
    """:func:`~sim_tactile.calibrate.contact.one_factor` iterates scikit-learn's fixed point
    on the covariance instead of the data (the real recordings hold 683,000 differences):
    the same unique variances and loadings, on variables of scales 1e-3 to 1e2."""
    from sklearn.decomposition import FactorAnalysis

    from sim_tactile.calibrate.contact import one_factor

    rng = np.random.default_rng(0)
    f = rng.standard_normal(2000)
    scale = np.array([1e-3, 0.5, 2.0, 30.0, 100.0])
    x = (np.outer(f, [1.0, 0.8, 0.5, 0.9, 0.3]) + rng.standard_normal((2000, 5)) * 0.6) * scale
    load, psi = one_factor(np.cov(x, rowvar=False, bias=True))
    ref = FactorAnalysis(1, tol=1e-10, max_iter=100_000, svd_method="lapack").fit(x)
    # scikit-learn stops where its log-likelihood moves by less than tol: 5e-7 apart here
    np.testing.assert_allclose(psi, ref.noise_variance_, rtol=1e-5)
    np.testing.assert_allclose(np.abs(load), np.abs(ref.components_[0]), rtol=1e-5)


def test_a_channel_that_is_no_line_in_the_force_keeps_the_rests_noise(tmp_path):
    """A channel whose contact level bends with the force (a real electrode's often does:
    here 150 F^3 counts on a line of 12 counts/N) has a contact residual far above its noise
    (70% more variance): the two estimates disagree, and its noise is the rest's alone
    (whose standard error is near 3%); the other channels take in the contact. (A bend of
    40 F^3 adds 5%, within the two estimates' errors: it passes, and moves the noise by
    about 2%.)"""
    from sim_tactile.calibrate.forced import fit_channels

    rng = np.random.default_rng(3)
    truth = _sensor(rng, tare=True)
    levels, forces = [], []
    for _ in range(N_SLIDES):
        force = _force(rng, truth["force_n"])
        ele = truth["offset"] + np.outer(force, truth["gain"])
        ele[:, 0] += 150.0 * force**3  # channel 0: no line in the force
        levels.append(ele + truth["noise"] * rng.standard_normal(ele.shape))
        forces.append((truth["tare"] + PDC_PER_N * force) / PDC_PER_N)
    fit = fit_channels(levels, forces, RATE_HZ, floor=0.0, force_floor=0.0)
    assert not fit.in_contact[0] and fit.in_contact[1:].all()
    assert fit.noise_std[0] == pytest.approx(truth["noise"][0], rel=0.1)
