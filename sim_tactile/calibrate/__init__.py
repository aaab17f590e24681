"""Calibrate a sensor model against real recordings of that sensor.

:func:`calibrate` reads a sensor's real recordings, fits per channel what they share with
the simulation (:mod:`~sim_tactile.calibrate.fit`), presses the simulated sensor on a flat
plate with the recordings' typical force to learn each taxel's share of the load, and
returns a :class:`~sim_tactile.sensors.calibration.Calibration`, which
``sim-tactile calibrate`` writes as TOML and ``--sensor-config`` applies.

Sensors with real data here:

- ``biotac19``: the public BioTac slides (seed 000). The static pressure channel ``pdc`` is
  linear in the normal force, 100 counts per newton (seed 000, section IV-D: a *change* of
  pdc), so every sample carries its own force, measured from pdc's rest level (its tare,
  found in the data, :mod:`.forced`), and the 19 electrodes are fitted against it.
- ``icub60``: the public iCub forearm slides (seed 000; compiled 1.5 s clips, the rest level
  subtracted and clipped at 0). No force was recorded and none was controlled (seed 000,
  section III-C), so what is fitted is what needs none: each taxel's noise floor on the
  clips where it stays quiet, its drift, and its steady level in contact. The steady level
  over an *assumed* force (:data:`ICUB_ASSUMED_FORCE_N`, the simulated task's nominal force,
  a free parameter the notes name) is the taxel's counts per newton. The gain the simulation
  takes is that over the taxel's simulated share at the same force, so a simulated press of
  that force reproduces the real steady level whatever force is assumed; only the reported
  counts per newton scale with it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..datasets.real import (
    BIOTAC_ELECTRODES,
    BIOTAC_RATE_HZ,
    N_MATERIALS,
    N_SLIDES,
    load_icub,
    read_biotac_csv,
)
from ..errors import ConfigError
from ..sensors import Sensor, get_sensor
from ..sensors.calibration import MIN_SHARE, Calibration
from .contact import AGREE_SIGMAS
from .fit import (
    ACTIVE_SIGMAS,
    QUIET_SIGMAS,
    ChannelFit,
    Readout,
    fit_readout,
    fit_unforced,
)
from .forced import fit_channels

#: BioTac static pressure (pdc) counts per newton of normal force (seed 000, section IV-D).
BIOTAC_PDC_COUNTS_PER_N = 100.0
#: The sensors :func:`calibrate` has a reader for.
CALIBRATABLE = ("biotac19", "icub60")
#: The plate the simulated sensor presses to learn each taxel's share of the force.
SHARE_PLATE = {"biotac19": "textures20/flat", "icub60": "textures20/flat"}
#: The normal force assumed for the iCub's recordings [N] (none was recorded): the nominal
#: force of the simulated task ``textures20-icub60-v1``, so that its slides meet the real
#: steady levels at their own force. A free parameter; the calibration's notes say so.
ICUB_ASSUMED_FORCE_N = 1.0


def read_biotac_forces(
    path: object, *, materials: int = N_MATERIALS, slides: int = N_SLIDES
) -> tuple[list[np.ndarray], list[np.ndarray], str]:
    """Every BioTac recording of the data set at ``path``, whole: the electrodes (T, 19)
    and the normal force [N] from pdc (T,), and the data set's root."""
    root = Path(str(path))
    raw = root / "raw_data"
    if not raw.is_dir():
        raise ConfigError(f"--data {str(path)!r}: no raw_data/ folder (the BioTac CSV files)")
    levels, forces = [], []
    for m in range(1, materials + 1):
        for s in range(1, slides + 1):
            f = raw / f"mat{m}" / f"mat{m}_{s}_bio.csv"
            if not f.is_file():
                continue
            with open(f, encoding="ascii") as fh:
                n = sum(1 for _ in fh) - 1
            x = read_biotac_csv(f, start=0, n_samples=n, channels=("pdc", *BIOTAC_ELECTRODES))
            forces.append(x[:, 0] / BIOTAC_PDC_COUNTS_PER_N)
            levels.append(x[:, 1:])
    if not levels:
        raise ConfigError(
            f"--data {str(path)!r}: no BioTac recordings (raw_data/matX/matX_N_bio.csv)"
        )
    return levels, forces, str(root)


def force_share(sensor: Sensor, plate: str, force_n: float) -> np.ndarray:
    """Each taxel's load per newton of normal force when the simulated sensor rests on
    ``plate`` pressed with ``force_n`` (the ideal loads, before the transducer)."""
    from ..plates import get_plate
    from ..sim.plan.protocol import Protocol
    from ..sim.plan.slide import Slide
    from ..sim.slide import prepare

    proto = Protocol(force_n=force_n, force_jitter=0.0, offset_jitter_m=0.0, speed_jitter=0.0)
    pressed = prepare(Slide(get_plate(plate), sensor, proto))
    out = np.zeros(sensor.layout.n)
    for _ in range(5):
        pressed.runner.step(force_cmd=force_n, slide_v=0.0, taxel_out=out)
    return out / force_n


def from_fit(
    sensor: Sensor,
    fit: ChannelFit,
    share: np.ndarray,
    n: int,
    source: str,
    notes: tuple[str, ...] | None = None,
    readout: Readout | None = None,
) -> Calibration:
    """The calibration of ``sensor`` from a channel fit and the simulated load shares;
    ``notes``: what the fit assumed (default: the BioTac's, fitted against its force);
    ``readout``: a multiplexed readout found in the data (:func:`fit_readout`)."""
    notes = list(notes) if notes is not None else forced_notes(fit, sensor.layout.names)
    cpn = np.nan_to_num(fit.counts_per_n, nan=0.0)
    fitted = (share >= MIN_SHARE) & (cpn > 0)
    gain = np.zeros(sensor.layout.n)
    gain[fitted] = cpn[fitted] / share[fitted]
    if not fitted.any():
        raise ConfigError(
            f"no channel of {sensor.name!r} both responds to the force in the data and carries "
            "load in the simulated press: nothing to calibrate"
        )
    borrowed = np.flatnonzero(~fitted)
    if borrowed.size:
        gain[borrowed] = float(np.median(gain[fitted]))
        names = [sensor.layout.names[k] for k in borrowed]
        notes.append(
            f"gain borrowed (median of the fitted channels) for {names}: no load in the simulated "
            f"press (share < {MIN_SHARE}) or no positive response to the force in the data"
        )
    return Calibration(
        sensor=sensor.name,
        channels=tuple(sensor.layout.names),
        n_recordings=n,
        force_n=round(float(fit.force_n), 6),
        counts_per_n=tuple(float(x) for x in cpn),
        offset=tuple(float(x) for x in np.nan_to_num(fit.offset)),
        noise_std=tuple(float(x) for x in fit.noise_std),
        drift_per_s=tuple(float(x) for x in fit.drift_per_s),
        r2=tuple(float(x) for x in np.nan_to_num(fit.r2)),
        force_share=tuple(float(x) for x in share),
        gain=tuple(float(x) for x in gain),
        quant_step=fit.quant_step,
        stretch_s=fit.stretch_s,
        crosstalk=None,
        source=source,
        notes=tuple(notes),
        readout_period=readout.period if readout else 1,
        readout_phase=readout.phase if readout and readout.period > 1 else (),
        readout_leak=round(readout.leak, 6) if readout and readout.period > 1 else 0.0,
    )


#: A channel's line misses its rest level by more than this share of its rise in contact
#: (at the typical force): its response is not linear from rest, and the notes say so.
NONLINEAR_SHARE = 0.25


def forced_notes(fit: ChannelFit, names) -> list[str]:
    """What a fit against a recorded force (:func:`~.forced.fit_channels`) assumed and
    found, for the calibration's notes (``names``: the channels')."""
    from .forced import MAX_CLIPPED

    rest, step = fit.force_rest, fit.quant_step
    notes = [
        "crosstalk: not identifiable from these data (every electrode responds to the same "
        "normal force); left to the sensor model",
        f"quiet stretches: {fit.n_quiet} (the force at its rest level for >= 0.3 s, glitches "
        f"left out), median {fit.stretch_s:.2f} s",
    ]
    if rest is not None:
        notes.append(
            f"force rest level (tare), found in the data: {rest.level:.4g} N (the lowest level "
            "the force reading stays still at, then fitted on the quiet stretches), noise "
            f"{rest.noise:.3g} N; "
            "forces are measured from it, and the gains corrected for that noise"
        )
    if fit.at_floor is not None:
        low = int(np.count_nonzero(fit.at_floor > 0.5))
        notes.append(
            "offset and noise: each channel's rest level and Gaussian noise on the quiet "
            f"stretches, fitted under the ADC step ({step:g}) and the clipping at the floor"
            + (
                f"; {low} channels read the floor in more than half their quiet samples "
                "(their noise is fitted to the histogram of their first differences)"
                if low
                else ""
            )
        )
    if fit.in_contact is not None:
        both = [names[k] for k in np.flatnonzero(fit.in_contact)]
        notes.append(
            "noise in contact: the residual of the one-factor fit (every channel and the "
            f"force a line in one force) over {fit.n_contact} first differences in contact, "
            "weighted with the rest's estimate by their standard errors, for "
            + (f"{both}" if both else "no channel")
            + f"; elsewhere (a rest at the floor, a contact at it, or the two estimates "
            f"{AGREE_SIGMAS:g} standard errors apart: no line in the force) the rest's alone"
        )
    if fit.intercept is not None:
        rise = fit.intercept + fit.counts_per_n * fit.force_n - fit.offset
        miss = np.abs(fit.intercept - fit.offset)
        bad = np.flatnonzero(
            np.isfinite(rise) & (miss > NONLINEAR_SHARE * np.maximum(np.abs(rise), fit.noise_std))
        )
        if bad.size:
            notes.append(
                f"not linear from rest: {[names[k] for k in bad]}: the line through their "
                f"levels in contact (force bins with at most {MAX_CLIPPED:.0%} of readings at "
                f"the floor) meets zero force at {[round(float(fit.intercept[k]), 2) for k in bad]}, "
                "not at their rest level; the linear model (offset = rest level, gain = that "
                f"line's slope) is off at {fit.force_n:.2f} N by the difference"
            )
    return notes


def calibrate(
    sensor: str, data: object, *, materials: int = N_MATERIALS, slides: int = N_SLIDES
) -> Calibration:
    """Fit ``sensor``'s model to the real recordings at ``data`` (see the module)."""
    if sensor not in CALIBRATABLE:
        raise ConfigError(
            f"sensor = {sensor!r} has no real-data reader; valid: {list(CALIBRATABLE)}"
        )
    sen = get_sensor(sensor)
    if sensor == "icub60":
        return _calibrate_icub(sen, data)
    levels, forces, root = read_biotac_forces(data, materials=materials, slides=slides)
    fit = fit_channels(levels, forces, BIOTAC_RATE_HZ, floor=0.0, force_floor=0.0)
    share = force_share(sen, SHARE_PLATE[sensor], fit.force_n)
    source = f"{Path(root).name}: pdc / {BIOTAC_PDC_COUNTS_PER_N:g} counts per N of normal force"
    return from_fit(sen, fit, share, len(levels), source)


def _calibrate_icub(sen: Sensor, data: object) -> Calibration:
    ds = load_icub(data)
    levels = list(ds.data.astype(np.float64))
    fit = fit_unforced(levels, ds.rate_hz, ICUB_ASSUMED_FORCE_N, floor=0.0)
    readout = fit_readout(levels, fit.noise_std, floor=0.0)
    share = force_share(sen, SHARE_PLATE["icub60"], ICUB_ASSUMED_FORCE_N)
    notes = (
        f"free parameter: the normal force, assumed {ICUB_ASSUMED_FORCE_N:g} N (none was "
        "recorded or controlled, seed 000 section III-C): the task's nominal force. "
        "counts_per_n scales with 1 / it; the gains, and so the simulated levels at that "
        "force, do not",
        f"noise: a Gaussian about the rest level clipped at 0, fitted to the first differences "
        f"of the clips where the taxel stays within {QUIET_SIGMAS:g} noise deviations of 0 "
        f"(median {fit.n_quiet} clips a taxel, {fit.stretch_s:g} s each)",
        f"steady level: the median over the clips in which the taxel rises {ACTIVE_SIGMAS:g} "
        "noise deviations above 0 of its median level there",
        "offset 0 and no ADC step: the compiled data have the rest level subtracted and are "
        "not on a grid of levels",
        "crosstalk: not identifiable without a known load; left to the sensor model",
        _readout_note(readout),
    )
    source = f"{Path(ds.meta['path']).name}: compiled iCub clips, no force (assumed)"
    return from_fit(sen, fit, share, len(levels), source, notes, readout)


def _readout_note(r: Readout) -> str:
    if r.period == 1:
        return f"readout: every sample (no cycle found in {r.n_series} loaded clip-taxels)"
    groups = sorted(set(r.phase))
    return (
        f"readout: a loaded taxel carries its level on one sample in {r.period} (its loaded "
        f"phase holds {r.contrast:.2f}x its mean level, median of {r.n_series} loaded "
        f"clip-taxels) and {r.leak:.2g} of it between; the taxels fall in {len(groups)} phase "
        f"groups {groups} (relative to the most often loaded taxel); where a clip starts in "
        "the cycle varies from clip to clip, so each simulated slide draws it"
    )


__all__ = ["CALIBRATABLE", "Calibration", "calibrate"]
