"""Channels fitted against a recorded normal force (the BioTac's pdc): :func:`fit_channels`.

The model, per channel c, and for the force channel f (say pdc / 100 counts per newton):

    x_c = max(floor, Q(offset_c + gain_c * F + drift_c(t) + noise_c))
    f   = max(force_floor, Q(tare + F + force noise))

with Q a rounding to the ADC step, F the true normal force [N], the noises white and
Gaussian, the drift a random walk. What is fitted, and how:

1. **the force's rest level (its tare)**: first the lowest level at which the force reading
   stays still (:func:`~.rest.still_level`: at rest it is the lowest it reads and stays
   within its noise there; a press is higher however still it is held), then the quiet
   stretches (the force within ``quiet_n``, or four of its noise deviations if more, of
   that level for ``min_quiet_s``, less :data:`QUIET_EDGE_S` at each end that borders a
   contact: a recording's own start or end is no contact's onset), and on them the rest
   level and noise of the model above (:func:`~.rest.fit_rest`: exact under clipping and
   quantisation); twice, the second time about the fitted level. The force is measured
   from the tare. Assumed: the sensor was tared once (one rest level for all recordings).
2. **each channel's offset and noise**: the same rest fit of the channel on the same quiet
   stretches: the offset is the channel's level at rest, not a line's intercept; the noise
   is sigma, reported as the ADC records it unclipped (sqrt(sigma^2 + step^2 / 12), which
   the calibration's ``noise_model`` turns back; no step where the data are not on a grid).
   The quiet stretches are taken whole: no force is subtracted (the force reading's own
   noise, times the gain, would add to the channel's: that was 9% on a channel of 60
   counts per newton under 1.5 counts of pdc noise). Where the rest is seen whole (not
   clipped), the noise then takes in the contact too
   (:mod:`~sim_tactile.calibrate.contact`): the residual of the one-factor fit of all
   channels and the force in contact, weighted with the rest's by their standard errors
   where the two agree (on a dozen slides with half a second of rest at either end, the
   noise's standard error was near 3% from the rest alone, near 1% from both).
3. **each channel's counts per newton**: a line through the channel's level against the
   force in bins of ``bin_n`` (bins with more than :data:`MAX_CLIPPED` of their readings at
   the floor are left out; where the force channel is clipped, its readings at its floor
   too), each bin's level the median *interpolated within its ADC step*
   (:func:`level_median`: the plain median of whole counts moves in whole counts, and a
   line through such a staircase missed a gain of 10 counts per newton by 7%; a median
   still, so texture and clipping below half a bin do not move it). The slope is then
   corrected for the force reading's noise (errors in the regressor flatten a least-
   squares line by var(F) / (var(F) + var(noise)); the variance of the force reading's
   noise is its rest noise's, measured in step 1).
4. **the drift**: a random walk's rate from the slopes of the same quiet stretches
   (:func:`~.fit.random_walk_rate`), without the response to what force is left in them
   (averaged over :data:`SMOOTH_S`) and without what that response's own noise adds to
   their slopes (the force reading's noise times the gain, :func:`_held_noise`), and
   without the stretches where a channel jumps (a glitch); the noise's variance then
   without the drift's share of the first differences (rate^2 / sample rate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError
from .contact import combine, contact_noise
from .fit import QUIET_EDGE_S, ChannelFit, quant_step, random_walk_rate
from .rest import SPIKE_SIGMAS, Rest, diff_variance, fit_rest, quiet_segments, still_level

#: A channel's force bin needs this many samples for its median.
MIN_BIN_SAMPLES = 50
#: Bins with more than this share of samples at the channel's floor (clipped) are left out.
MAX_CLIPPED = 0.4
#: The quiet band about the force's rest level is at least this many of its noise deviations.
QUIET_FORCE_SIGMAS = 4.0
#: The force left in a quiet stretch is averaged over this long before its response is
#: taken out of the stretch for the drift fit [s].
SMOOTH_S = 0.2


def level_median(y: np.ndarray, step: float) -> float:
    """The median of readings ``y`` on a grid of ``step`` (0: continuous, the plain median),
    interpolated within the level that holds it as if that level's readings spread evenly
    over its width (the median of grouped data): ``L - step/2 + step (n/2 - below) / at``."""
    m = float(np.median(y))
    if step <= 0:
        return m
    level = round(m / step) * step
    below = np.count_nonzero(y < level - step / 2)
    at = np.count_nonzero(np.abs(y - level) <= step / 2)
    return level - step / 2 + step * (len(y) / 2 - below) / max(at, 1)


def linear_response(
    level: np.ndarray,
    force: np.ndarray,
    floor: float | None,
    bin_n: float,
    *,
    step: float = 0.0,
    force_noise_var: float = 0.0,
):
    """(slope, intercept, r2) of one channel's ``level`` (T,) against the ``force`` (T,)
    [N, from its tare]: a line through the :func:`level_median` of each force bin of
    ``bin_n`` newtons, its slope corrected for a force reading noise of variance
    ``force_noise_var`` [N^2] (module docstring, step 3)."""
    lo, top = float(force.min()), float(np.quantile(force, 0.99))
    edges = lo + np.arange(0.0, top - lo + bin_n, bin_n)
    xs, ys, ws = [], [], []
    idx = np.digitize(force, edges) - 1
    for b in range(len(edges) - 1):
        m = idx == b
        k = int(m.sum())
        if k < MIN_BIN_SAMPLES:
            continue
        y = level[m]
        if floor is not None and np.mean(y <= floor) > MAX_CLIPPED:
            continue
        xs.append(float(np.mean(force[m])))
        ys.append(level_median(y, step))
        ws.append(k)
    if len(xs) < 2:
        return np.nan, np.nan, np.nan
    slope, intercept = np.polyfit(xs, ys, 1, w=np.sqrt(ws))
    used = (idx >= 0) & (idx < len(edges) - 1)
    var_f = float(np.var(force[used]))
    if force_noise_var > 0 and var_f > force_noise_var:
        centre = float(np.average(xs, weights=ws))
        corrected = slope * var_f / (var_f - force_noise_var)
        intercept += (slope - corrected) * centre
        slope = corrected
    pred = intercept + slope * force
    var = np.var(level)
    r2 = 1.0 - np.var(level - pred) / var if var > 0 else 0.0
    return float(slope), float(intercept), float(r2)


@dataclass(frozen=True)
class _Quiet:
    """The force channel's rest (:class:`~.rest.Rest`, in N), the quiet band about it [N]
    and the quiet stretches: (recording, slice) pairs, their edges already cut."""

    rest: Rest
    band_n: float
    stretches: list[tuple[int, slice]]


def _force_rest(forces, quiet_n, n_min, edge, force_floor, fstep) -> _Quiet:
    """Step 1 of the module docstring."""
    tare, spread = still_level(forces, fstep if fstep > 0 else quiet_n / 4, n_min)
    # the band takes in a noisy rest's noise (4 SD), where that noise is within the band
    # itself: a lowest still level that wanders further is a held contact, not a rest
    band = max(quiet_n, QUIET_FORCE_SIGMAS * spread) if spread <= quiet_n else quiet_n
    rest, cut = None, []
    for _ in range(2):
        cut = [
            (k, s)
            for k, f in enumerate(forces)
            for s in _inner(quiet_segments(f, tare, band, n_min), edge, len(f))
            if s.stop - s.start >= n_min
        ]
        if not cut:
            raise ConfigError(
                f"no quiet stretch (force within {band:.3g} N of its rest level {tare:.4g} N "
                f"for {n_min} samples, less {edge} at a contact) in the recordings: the rest "
                "levels, the noise floor and the drift cannot be fitted"
            )
        rest = fit_rest([forces[k][s] for k, s in cut], floor=force_floor, step=fstep)
        tare = rest.level
        band = max(quiet_n, QUIET_FORCE_SIGMAS * max(rest.noise, np.sqrt(rest.recorded_var)))
    return _Quiet(rest, band, cut)


def _inner(segments: list[slice], edge: int, n: int) -> list[slice]:
    """The quiet ``segments`` of a recording of ``n`` samples less ``edge`` samples at each
    end that borders the contact (its onset or release); an end at the recording's own start
    or end borders none, and keeps its samples."""
    return [
        slice(s.start + (edge if s.start > 0 else 0), s.stop - (edge if s.stop < n else 0))
        for s in segments
    ]


def _mean_below(rest: Rest, cut: float) -> float:
    """The mean of the rest's readings (before clipping) below ``cut``: a truncated
    Gaussian's, ``mu - sigma phi(a) / Phi(a)`` with ``a = (cut - mu) / sigma``."""
    from scipy.special import ndtr

    if rest.noise <= 0:
        return min(rest.level, cut)
    a = (cut - rest.level) / rest.noise
    return rest.level - rest.noise * float(np.exp(-0.5 * a * a) / np.sqrt(2 * np.pi)) / max(
        float(ndtr(a)), 1e-300
    )


def _spike_free(stretches: list[np.ndarray]) -> list[int]:
    """The indices of the quiet stretches (each (n, C)) in which no channel jumps more than
    :data:`~.rest.SPIKE_SIGMAS` of its noise between two samples (a glitch: one of 3000
    counts on four BioTac electrodes at once passed for a drift of 0.75 counts per sqrt(s));
    all of them if every one has a jump."""
    d = np.concatenate([np.diff(x, axis=0) for x in stretches])
    cut = SPIKE_SIGMAS * np.sqrt(2 * np.array([diff_variance(d[:, c]) for c in range(d.shape[1])]))
    keep = [i for i, x in enumerate(stretches) if not (np.abs(np.diff(x, axis=0)) > cut).any()]
    return keep or list(range(len(stretches)))


def _held(pairs, slope: np.ndarray, width: int) -> list[np.ndarray]:
    """The quiet stretches' levels (each (n, C)) without the response (``slope``, (C,)) to
    what force is left in them (each (n,), from the tare), that force averaged over
    ``width`` samples: a light touch's slow change is no drift, and the force reading's
    own noise, so averaged, stays out."""
    from scipy.ndimage import uniform_filter1d

    return [
        x - np.outer(uniform_filter1d(f, max(width, 1), mode="nearest"), slope) for x, f in pairs
    ]


def _held_noise(pairs, slope: np.ndarray, width: int, force_var: float, rate_hz: float):
    """What :func:`_held` adds to each stretch's least-squares slope (per stretch, (C,))
    [units^2 / s^2]: the force reading's noise (variance ``force_var``), averaged over
    ``width`` samples and times ``slope``, still moves a slope; a drift fit that took it for
    a random walk found one of 2 counts per sqrt(s) where there was none."""
    from scipy.ndimage import uniform_filter1d

    out, memo = [], {}
    for x, _ in pairs:
        n = len(x)
        if n not in memo:
            tc = np.arange(n) - 0.5 * (n - 1)
            k = uniform_filter1d(np.eye(n), max(width, 1), axis=0, mode="nearest")
            memo[n] = float(np.sum((k.T @ tc) ** 2) / (tc @ tc) ** 2) * rate_hz**2
        out.append(slope * slope * force_var * memo[n])
    return out


def _check(levels, forces) -> int:
    if not levels or len(levels) != len(forces):
        raise ConfigError(
            f"calibration needs recordings with their forces: got {len(levels)} recordings "
            f"and {len(forces)} force traces"
        )
    C = levels[0].shape[1]
    for k, (x, f) in enumerate(zip(levels, forces, strict=True)):
        if x.ndim != 2 or x.shape[1] != C or f.shape != (x.shape[0],):
            raise ConfigError(
                f"recording {k}: levels {x.shape} and force {f.shape}; valid: (T, {C}) and (T,)"
            )
    return C


def fit_channels(
    levels: list[np.ndarray],
    forces: list[np.ndarray],
    rate_hz: float,
    *,
    quiet_n: float = 0.03,
    min_quiet_s: float = 0.3,
    bin_n: float = 0.05,
    floor: float | None = 0.0,
    force_floor: float | None = None,
) -> ChannelFit:
    """Fit every channel of recordings ``levels`` (each (T, C)) against their normal-force
    readings ``forces`` (each (T,), newtons, *not* tared: the rest level is found here)
    sampled at ``rate_hz`` (the estimator: the module docstring). ``floor``: the level at
    which the channels are clipped; ``force_floor``: the force reading's (None: not
    clipped)."""
    C = _check(levels, forces)
    step = quant_step(levels)
    n_min = max(3, round(min_quiet_s * rate_hz))
    fstep = quant_step(forces)
    q = _force_rest(forces, quiet_n, n_min, round(QUIET_EDGE_S * rate_hz), force_floor, fstep)
    pairs = [(levels[k][s], forces[k][s] - q.rest.level) for k, s in q.stretches]
    pairs = [pairs[i] for i in _spike_free([x for x, _ in pairs])]
    stretches = [x for x, _ in pairs]
    X = np.concatenate(levels)
    F = np.concatenate(forces)
    if force_floor is not None:  # a clipped force reading stands for the rest's below it
        clipped = F <= force_floor + 1e-9
        F[clipped] = _mean_below(q.rest, force_floor + fstep / 2)
    F -= q.rest.level
    fits = [
        linear_response(X[:, c], F, floor, bin_n, step=step, force_noise_var=q.rest.recorded_var)
        for c in range(C)
    ]
    slope, intercept, r2 = (np.array(v) for v in zip(*fits, strict=True))
    rests = [fit_rest([x[:, c] for x in stretches], floor=floor, step=step) for c in range(C)]
    width = round(SMOOTH_S * rate_hz)
    drift = random_walk_rate(
        _held(pairs, np.nan_to_num(slope), width),
        np.sqrt([r.recorded_var for r in rests]),
        rate_hz,
        _held_noise(pairs, np.nan_to_num(slope), width, q.rest.recorded_var, rate_hz),
    )
    drift_var = 0.5 * drift**2 / rate_hz  # the walk's share of half a first difference's
    rests = [
        fit_rest([x[:, c] for x in stretches], floor=floor, step=step, drift_var=drift_var[c])
        for c in range(C)
    ]
    lengths = np.array([s.shape[0] / rate_hz for s in stretches])
    contact = F > q.band_n
    inside = contact_noise(levels, [f - q.rest.level for f in forces], q.band_n, floor, drift_var)
    noise_var, combined = combine(
        np.array([r.noise for r in rests]) ** 2 + step * step / 12,
        np.array([r.noise_var_var for r in rests]),
        inside,
    )
    return ChannelFit(
        slope,
        np.array([r.level for r in rests]),
        r2,
        np.sqrt(noise_var),
        drift,
        step,
        float(np.median(lengths)),
        len(stretches),
        float(np.median(F[contact])) if contact.any() else float("nan"),
        force_rest=q.rest,
        intercept=intercept,
        at_floor=np.array([r.at_floor for r in rests]),
        in_contact=combined,
        n_contact=inside.n,
    )
