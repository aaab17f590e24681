"""Statistics that a sensor's real recordings and its simulation share, fitted per channel.

What every fit shares is here: :class:`ChannelFit` (the result), the ADC step
(:func:`quant_step`: the smallest non-zero difference between levels) and the drift taken
as a random walk (:func:`random_walk_rate`: its rate, the standard deviation of its change
over one second, from the least-squares slopes of quiet stretches beyond what the noise
alone gives a stretch of each length). The fits:

- against a recorded normal force (the BioTac): :func:`~.forced.fit_channels`;
- without a force (the iCub's compiled clips): :func:`fit_unforced`, and the multiplexed
  readout such clips show, :func:`fit_readout`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from .rest import Rest

#: Time cut from each end of a quiet stretch (the contact's onset and release) [s].
QUIET_EDGE_S = 0.1
#: Share of the largest first differences left out of the noise estimate (spikes, jumps).
NOISE_TRIM = 0.005
#: The standard deviation of a Gaussian without its largest NOISE_TRIM share of absolute
#: values is this share of the whole one's (truncated at 2.807 sigma).
TRIM_STD_RATIO = 0.9777


@dataclass(frozen=True)
class ChannelFit:
    """Per channel (arrays of shape (C,)): see :mod:`sim_tactile.sensors.calibration`."""

    counts_per_n: np.ndarray
    offset: np.ndarray
    r2: np.ndarray
    noise_std: np.ndarray
    drift_per_s: np.ndarray
    quant_step: float
    stretch_s: float
    n_quiet: int
    force_n: float
    #: the force reading's rest (its tare, in N; :mod:`.forced`), None where no force
    force_rest: Rest | None = None
    #: the fitted line's level at zero force (C,), None where no force
    intercept: np.ndarray | None = None
    #: the share of each channel's quiet readings at its floor (C,), None where not fitted
    at_floor: np.ndarray | None = None
    #: where the noise takes in the residual of the one-factor fit in contact (C,)
    #: (:mod:`~sim_tactile.calibrate.contact`), None where not fitted; ``n_contact``: the
    #: first differences that fit saw
    in_contact: np.ndarray | None = None
    n_contact: int = 0


#: A grid finer than this share of the readings' typical first difference (their RMS) is no
#: ADC's step but a text file's last printed digit: such readings count as continuous, and
#: no step enters the noise (a fit on a grid of 1e-6 counts would sum over 10^7 levels).
NEGLIGIBLE_STEP = 1e-3


def quant_step(levels: list[np.ndarray]) -> float:
    """The ADC step: the smallest non-zero difference between any two recorded levels (0 if
    the levels are not on a grid, or on one finer than :data:`NEGLIGIBLE_STEP` of their
    first differences: the data are not quantised)."""
    vals = np.unique(np.concatenate([np.ravel(x) for x in levels]))
    d = np.diff(vals)
    d = d[d > 0]
    if d.size == 0:
        return 0.0
    step = float(d.min())
    on_grid = np.allclose(
        np.round(vals / step) * step, vals, rtol=0.0, atol=1e-6 * max(step, 1e-12)
    )
    diffs = np.concatenate([np.diff(x, axis=0).ravel() for x in levels if len(x) > 1])
    typical = float(np.sqrt(np.mean(diffs**2))) if diffs.size else 0.0
    return step if on_grid and step > NEGLIGIBLE_STEP * typical else 0.0


def _slope_var_per_noise(n: int) -> float:
    """Variance of the least-squares slope [1/s^2, per unit noise variance] over ``n``
    samples one second apart: 12 / (n (n^2 - 1))."""
    return 12.0 / (n * (n * n - 1.0))


def trimmed_noise(d: np.ndarray) -> float:
    """The white noise's standard deviation from first differences ``d``, without their
    largest NOISE_TRIM share (trimmed: a quantised signal's MAD is 0 below the step; spikes
    would dominate a plain standard deviation)."""
    keep = np.abs(d) <= np.quantile(np.abs(d), 1.0 - NOISE_TRIM)
    return float(d[keep].std() / np.sqrt(2) / TRIM_STD_RATIO)


def random_walk_rate(
    stretches: list[np.ndarray],
    noise: np.ndarray,
    rate_hz: float,
    extra: list[np.ndarray] | None = None,
):
    """Per channel, the rate of a random-walk drift (the standard deviation of its change over
    one second) from the least-squares slopes of quiet stretches (each (n, C)) beyond what
    white noise of ``noise`` (per channel) gives them, and beyond ``extra`` (per stretch,
    (C,)): any other variance of a stretch's slope known to be there [units^2 / s^2]."""
    # a random walk of rate r: a stretch's least-squares slope S has E[S^2] =
    # noise^2 c + r^2 g, c = 12 / (n (n^2 - 1)) rate^2, g = 6 / (5 L); r^2 by weighted least
    # squares over the stretches, weights 1 / c^2 (short stretches, whose slopes the noise
    # dominates, count little)
    num = np.zeros(len(noise))
    den = 0.0
    for k, seg in enumerate(stretches):
        n = seg.shape[0]
        t = np.arange(n) / rate_hz
        tc = t - t.mean()
        slope_k = tc @ (seg - seg.mean(axis=0)) / (tc @ tc)
        c = _slope_var_per_noise(n) * rate_hz**2
        g = 6.0 / (5.0 * n / rate_hz)
        w = 1.0 / c**2
        known = noise**2 * c + (extra[k] if extra is not None else 0.0)
        num += w * g * (slope_k**2 - known)
        den += w * g * g
    return np.sqrt(np.maximum(num / den, 0.0))


#: A Gaussian noise of standard deviation s about a rest level at the clipping floor, clipped
#: there, has first differences of standard deviation sqrt(2) * RECTIFIED_DIFF * s
#: (the variance of max(n, 0) is s^2 (1/2 - 1/(2 pi)): sqrt of that is 0.5838 s).
RECTIFIED_DIFF = float(np.sqrt(0.5 - 1.0 / (2.0 * np.pi)))
#: A channel's recording is quiet when its maximum is within this many noise standard
#: deviations of the floor (the bound and the noise are found together, see fit_unforced).
QUIET_SIGMAS = 4.0
#: A channel is in contact in a recording when it rises this many noise deviations above
#: the floor; its steady level is the median of those samples.
ACTIVE_SIGMAS = 8.0


def fit_unforced(
    levels: list[np.ndarray], rate_hz: float, force_n: float, *, floor: float = 0.0
) -> ChannelFit:
    """Fit every channel of recordings ``levels`` (each (T, C)) that carry no force, clipped
    at ``floor`` at rest (the rest level subtracted, as the iCub's compiled data are), under
    an assumed normal force ``force_n`` [N] (a free parameter: the gains scale with it).

    - noise: a channel's recordings whose maximum stays within QUIET_SIGMAS noise deviations
      of the floor are quiet; the noise is the one whose clipped Gaussian gives their first
      differences' spread (:func:`trimmed_noise`), the bound and the noise found
      together by a fixed point from 1 count;
    - the steady level in contact: the median over the recordings in which the channel rises
      ACTIVE_SIGMAS deviations above the floor of its median level there; over ``force_n``
      it is the channel's counts per newton (r2 0: no force to explain);
    - offset: the floor; drift: :func:`random_walk_rate` on the quiet recordings.
    """
    if not levels:
        raise ConfigError("calibration needs recordings: got none")
    v_force = float(force_n)
    if not v_force > 0:
        raise ConfigError(f"force_n = {force_n!r}; valid: > 0 N (the assumed normal force)")
    C = levels[0].shape[1]
    for k, x in enumerate(levels):
        if x.ndim != 2 or x.shape[1] != C:
            raise ConfigError(f"recording {k}: levels {x.shape}; valid: (T, {C})")
    X = np.stack(levels)  # (R, T, C)
    top = X.max(axis=1) - floor  # (R, C)
    noise, recorded = np.empty(C), np.empty(C)
    quiet_sets = []
    for c in range(C):
        sigma = 1.0
        for _ in range(50):
            q = top[:, c] <= QUIET_SIGMAS * sigma
            if q.sum() < 2:
                raise ConfigError(
                    f"channel {c}: fewer than 2 quiet recordings (maximum within "
                    f"{QUIET_SIGMAS:g} noise deviations of the floor): no noise floor to fit"
                )
            rec = trimmed_noise(np.diff(X[q, :, c], axis=1).ravel())
            new = rec / RECTIFIED_DIFF
            if abs(new - sigma) <= 1e-6 * sigma:
                break
            sigma = new
        noise[c], recorded[c] = sigma, rec
        quiet_sets.append(np.flatnonzero(q))
    steady = np.full(C, np.nan)
    for c in range(C):
        vals = [
            float(np.median(x[x - floor >= ACTIVE_SIGMAS * noise[c]]))
            for x in X[:, :, c]
            if (x - floor >= ACTIVE_SIGMAS * noise[c]).any()
        ]
        if vals:
            steady[c] = float(np.median(vals)) - floor
    drift = np.array(
        [
            random_walk_rate(list(X[quiet_sets[c], :, c : c + 1]), recorded[c : c + 1], rate_hz)[0]
            for c in range(C)
        ]
    )
    return ChannelFit(
        steady / v_force,
        np.full(C, float(floor)),
        np.zeros(C),
        noise,
        drift,
        quant_step(levels),
        float(X.shape[1] / rate_hz),
        int(np.median([len(q) for q in quiet_sets])),
        v_force,
    )


#: Longest readout cycle :func:`fit_readout` looks for [samples].
MAX_READOUT_PERIOD = 16
#: A cycle is found when its loaded phase holds this many times a channel's mean level
#: (a channel read on every sample scores 1; one read on one sample in P scores about P).
MIN_READOUT_CONTRAST = 1.5
#: Of the cycles whose loaded phase scores within this share of the best, the shortest is
#: the readout's (a multiple of the period scores as high as the period itself).
READOUT_TIE = 0.95


@dataclass(frozen=True)
class Readout:
    """A multiplexed readout: each channel carries its signal on one sample in ``period``, at
    ``phase`` relative to the others, and ``leak`` of it on the other samples. ``contrast``
    is the loaded phase's mean over the channel's mean (median over the loaded clips), the
    statistic that found the period; ``n_series`` how many (clip, channel) pairs it saw."""

    period: int
    phase: tuple[int, ...]
    leak: float
    contrast: float
    n_series: int


def clipped_mean_level(m: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """The level mu >= 0 whose Gaussian noise of deviation ``sigma``, clipped at 0, has mean
    ``m``: mu Phi(mu / sigma) + sigma phi(mu / sigma) = m (bisection; 0 where ``m`` is at or
    below the clipped noise's own mean, sigma / sqrt(2 pi))."""
    from scipy.special import ndtr

    m, sigma = np.asarray(m, dtype=float), np.maximum(np.asarray(sigma, dtype=float), 1e-12)
    lo, hi = np.zeros_like(m), np.maximum(m, 0.0) + 1e-12
    for _ in range(60):
        mu = 0.5 * (lo + hi)
        z = mu / sigma
        mean = mu * ndtr(z) + sigma * np.exp(-0.5 * z * z) / np.sqrt(2.0 * np.pi)
        lo, hi = np.where(mean < m, mu, lo), np.where(mean < m, hi, mu)
    return 0.5 * (lo + hi)


def _phase_means(x: np.ndarray, period: int) -> np.ndarray:
    """(S, period): each series' mean at each phase of the cycle (whole cycles only)."""
    n = (x.shape[1] // period) * period
    return x[:, :n].reshape(x.shape[0], n // period, period).mean(axis=1)


def fit_readout(levels: list[np.ndarray], noise: np.ndarray, *, floor: float = 0.0) -> Readout:
    """The readout cycle of recordings ``levels`` (each (T, C), clipped at ``floor``) whose
    channels have noise ``noise`` (C,): period 1 when none is found.

    Only loaded series count (a clip and channel rising ACTIVE_SIGMAS noise deviations above
    the floor). For each candidate period P the statistic is the median, over those series,
    of the largest phase mean over the series' mean; the period is the shortest P within
    READOUT_TIE of the best (its multiples tie with it), if it reaches MIN_READOUT_CONTRAST.
    A channel's phase is the mode, over the clips where both are loaded, of its loaded phase
    less that of the channel loaded in most clips (the cycle's start in a clip is arbitrary);
    the leak is the median, over the loaded series, of the level under the other phases
    (:func:`clipped_mean_level` of their mean) over the loaded phase's mean."""
    X = np.stack(levels) - floor  # (R, T, C)
    R, T, C = X.shape
    loaded = X.max(axis=1) >= ACTIVE_SIGMAS * np.asarray(noise)[None, :]  # (R, C)
    r_idx, c_idx = np.nonzero(loaded)
    if r_idx.size == 0:
        return Readout(1, (), 0.0, 1.0, 0)
    series = X[r_idx, :, c_idx]  # (S, T)
    mean = np.maximum(series.mean(axis=1), 1e-12)
    periods = list(range(2, min(MAX_READOUT_PERIOD, T // 4) + 1))
    score = {P: float(np.median(_phase_means(series, P).max(axis=1) / mean)) for P in periods}
    if not score:
        return Readout(1, (), 0.0, 1.0, int(r_idx.size))
    best = max(score.values())
    P = min(p for p in periods if score[p] >= READOUT_TIE * best)
    if score[P] < MIN_READOUT_CONTRAST:
        return Readout(1, (), 0.0, score[P], int(r_idx.size))
    pm = _phase_means(series, P)
    on_phase = np.full((R, C), -1, dtype=np.int64)
    on_phase[r_idx, c_idx] = pm.argmax(axis=1)
    on = pm.max(axis=1)
    off = clipped_mean_level((pm.sum(axis=1) - on) / (P - 1), np.asarray(noise)[c_idx])
    leak = float(np.clip(np.median(off / on), 0.0, 1.0))
    ref = int(np.argmax(loaded.sum(axis=0)))
    phase = []
    for c in range(C):
        both = loaded[:, c] & loaded[:, ref]
        rel = (on_phase[both, c] - on_phase[both, ref]) % P
        phase.append(int(np.bincount(rel, minlength=P).argmax()) if rel.size else 0)
    return Readout(P, tuple(phase), leak, score[P], int(r_idx.size))
