"""A channel at rest: where it rests and how much it wanders there, measured from the data.

A real sensor rests wherever its tare (or its electronics) left it, and a recorded channel
is quantised and often clipped at a floor (the BioTac's baseline-subtracted electrodes and
its pdc sit at 0 counts at rest more often than not). Both bend the plain statistics: the
mean of a clipped channel is above its rest level and the spread of its first differences
below its noise; whole counts make a median move in whole counts. This module fits the
model those readings come from instead:

    reading = max(floor, step * round((mu + sigma * n) / step)),   n ~ N(0, 1)

per channel (:func:`fit_rest`), from statistics that slow excursions (a drift, a light
touch the quiet band lets through) barely move: the variance of the readings from their
first differences (half theirs, spikes left out: :func:`diff_variance`), and the readings'
mean where the channel is not clipped, or where it is, the share of readings at the floor
and the histogram of the first differences. The model's statistics are exact sums over its
levels (:func:`reading_probs`, :func:`reading_moments`; :func:`phase_var` with each quiet
stretch at its own place on the ADC grid), so the fitted ``mu`` and ``sigma`` carry neither
the clipping's nor the quantisation's bias (Sheppard's ``sigma^2 + step^2 / 12`` is the
unclipped variance on average over the grid).

:func:`rest_mode` finds a channel's rest level before anything is known: the commonest
reading among its lower half (at rest a channel stays within its noise of one level; in
contact the force spreads it over the force's range); :func:`still_level`, the force's: the
lowest level it stays still at (a press held still would be its commonest reading).
:func:`quiet_segments` are the stretches where it stays there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: First differences beyond this many of their (trimmed) standard deviations are spikes.
SPIKE_SIGMAS = 8.0
#: Share of the largest first differences left out of the first, rough scale.
ROUGH_TRIM = 0.005
#: The variance of :func:`diff_variance`'s estimate of a white Gaussian's variance v from n
#: first differences is this many v^2 / n (half their mean square: each difference's
#: square has variance 8 v^2, neighbours' squares a covariance of 2 v^2; 2 v^2 / n for
#: the readings themselves).
DIFF_VAR_VAR = 3.0
#: A quantised channel with this share of its quiet readings at the floor is fitted from
#: its first differences' histogram (:func:`_diff_fit`), not from its readings' mean.
CLIPPED_REST = 0.02
#: A channel whose quiet readings rise above the floor less often than this cannot show
#: its noise (nearly all of it is below the floor): its rest is taken as the floor and its
#: noise as what its differences show beyond the ADC step.
MIN_ABOVE_FLOOR = 0.01


@dataclass(frozen=True)
class Rest:
    """A channel's rest: ``level`` (mu) and ``noise`` (sigma, before quantisation and
    clipping) of the model in the module docstring, in the channel's units;
    ``recorded_var``: the variance of its readings' white part as recorded (quantised and
    clipped), what a drift fit subtracts from the slopes; ``at_floor``: the share of the
    quiet readings at the floor; ``n``: how many readings; ``noise_var_var``: the variance
    of ``noise ** 2`` as an estimate, where the rest is seen whole (not clipped; NaN
    elsewhere)."""

    level: float
    noise: float
    recorded_var: float
    at_floor: float
    n: int
    noise_var_var: float = float("nan")


def rest_mode(values: np.ndarray, width: float) -> float:
    """The commonest reading of ``values`` (any shape) at or below their median, in bins of
    ``width`` (the ADC step, or a fraction of the quiet band for continuous data): the
    centre of the fullest bin."""
    x = np.ravel(values)
    x = x[np.isfinite(x)]
    low = x[x <= np.median(x)]
    start = np.floor(low.min() / width - 0.5) * width + 0.5 * width
    idx = np.floor((low - start) / width).astype(np.int64)
    return float(start + (np.bincount(idx).argmax() + 0.5) * width)


#: A window is still when its spread is within this many times the still windows' typical
#: spread (the :data:`STILL_QUANTILE` of all windows' spreads, at least the bin width).
STILL_SPREAD = 2.0
#: The share of windows whose spread sets the still windows' typical spread: a recording at
#: rest for a tenth of its windows or more shows its noise there.
STILL_QUANTILE = 0.1
#: The rest is the lowest cluster of at least this share of the still windows (and 3): a
#: lone still window below it is no rest level.
REST_CLUSTER = 0.05


def still_level(series: list[np.ndarray], width: float, n: int) -> tuple[float, float]:
    """The level at which readings ``series`` (each (T,)) rest: the lowest level at which
    they stay still, and the still windows' typical standard deviation. Each series is cut
    into windows of ``n`` samples; a window is still when its standard deviation is within
    :data:`STILL_SPREAD` times the typical one; the rest is the lowest cluster of still
    windows' means (one holding :data:`REST_CLUSTER` of them, within :data:`STILL_SPREAD`
    typical deviations of its lowest), and its level the commonest reading there
    (:func:`rest_mode`, bins of ``width``). A force at rest is the lowest it reads, and
    stays there a while; in contact it is higher, however long and however still it is
    held (the commonest reading overall is a press's where it holds still longer than the
    rest)."""
    wins = [np.asarray(x, float)[k : k + n] for x in series for k in range(0, len(x) - n + 1, n)]
    wins = [w for w in wins if np.isfinite(w).all()]
    if not wins:
        return rest_mode(np.concatenate([np.ravel(x) for x in series]), width), 0.0
    sd = np.array([w.std() for w in wins])
    mean = np.array([w.mean() for w in wins])
    typical = max(float(np.quantile(sd, STILL_QUANTILE)), width)
    still = np.flatnonzero(sd <= STILL_SPREAD * typical)
    order = still[np.argsort(mean[still])]
    need = max(3, int(np.ceil(REST_CLUSTER * len(order))))
    m = mean[order]
    near = np.searchsorted(m, m + STILL_SPREAD * typical, side="right") - np.arange(len(m))
    first = int(np.argmax(near >= need)) if (near >= need).any() else 0
    cluster = order[(m >= m[first]) & (m <= m[first] + STILL_SPREAD * typical)]
    spread = float(np.median(sd[cluster]))
    return rest_mode(np.concatenate([wins[i] for i in cluster]), width), spread


def quiet_segments(x: np.ndarray, level: float, band: float, n_min: int) -> list[slice]:
    """The stretches of ``x`` (T,) that stay within ``band`` of ``level`` for at least
    ``n_min`` samples."""
    q = np.concatenate([[False], np.abs(x - level) <= band, [False]])
    edges = np.flatnonzero(np.diff(q.astype(np.int8)))
    return [slice(a, b) for a, b in zip(edges[::2], edges[1::2], strict=True) if b - a >= n_min]


def diff_variance(d: np.ndarray) -> float:
    """The variance of a white sequence from its first differences ``d``: half their mean
    square, without spikes (beyond :data:`SPIKE_SIGMAS` times a rough scale from the
    differences without their largest :data:`ROUGH_TRIM` share, itself refined once). A
    cut that far out leaves a Gaussian whole, discrete or not."""
    d = np.asarray(d, dtype=float).ravel()
    if d.size == 0:
        return 0.0
    a = np.abs(d)
    scale = float(np.sqrt(np.mean(d[a <= np.quantile(a, 1.0 - ROUGH_TRIM)] ** 2)))
    for _ in range(2):
        keep = a <= SPIKE_SIGMAS * max(scale, 1e-12)
        scale = float(np.sqrt(np.mean(d[keep] ** 2)))
    return 0.5 * scale * scale


def reading_probs(mu: float, sigma: float, floor: float | None, step: float):
    """The levels (L,) of ``max(floor, step * round((mu + sigma n) / step))``, n ~ N(0, 1),
    on a grid of ``step`` > 0 through 0 (the floor on it; None: not clipped), and their
    probabilities (L,): each level takes the readings that round to it, the lowest also all
    below it (the floor's clipped share, else a tail 12 deviations out), the highest all
    above."""
    from scipy.special import ndtr

    sigma = max(float(sigma), 1e-12)
    clipped = floor is not None and floor >= mu - 12 * sigma
    k0 = np.round(floor / step) if clipped else np.floor((mu - 12 * sigma) / step)
    k = np.arange(k0, max(np.ceil((mu + 12 * sigma) / step), k0) + 2)
    levels = k * step
    upper = ndtr((levels + step / 2 - mu) / sigma)
    p = np.diff(np.concatenate([[0.0], upper]))
    p[-1] += 1.0 - upper[-1]
    return levels, p


def reading_moments(mu: float, sigma: float, floor: float | None, step: float):
    """(mean, variance) of the readings of :func:`reading_probs` (``step`` 0: not
    quantised, the censored Gaussian's closed form): exact."""
    from scipy.special import ndtr

    sigma = max(float(sigma), 1e-12)
    if step > 0:
        levels, p = reading_probs(mu, sigma, floor, step)
        mean = float(p @ levels)
        return mean, float(max(p @ (levels - mean) ** 2, 0.0))
    if floor is None:
        return float(mu), sigma * sigma
    a = (floor - mu) / sigma
    pa, phi = float(ndtr(a)), float(np.exp(-0.5 * a * a) / np.sqrt(2 * np.pi))
    above = 1.0 - pa
    mean = floor * pa + mu * above + sigma * phi
    m2 = floor * floor * pa + mu * mu * above + 2 * mu * sigma * phi
    m2 += sigma * sigma * (a * phi + above)
    return float(mean), float(max(m2 - mean * mean, 0.0))


def _diff_fit(d: np.ndarray, v: float, at_floor: float, floor: float, step: float):
    """(mu, sigma) of a clipped, quantised rest from its first differences ``d`` and the
    share ``at_floor`` of its readings at the floor: ``mu`` follows from ``sigma`` by that
    share (``Phi((floor + step / 2 - mu) / sigma) = at_floor``), and ``sigma`` makes the
    differences' histogram (without spikes) most likely against the autocorrelation of
    :func:`reading_probs` (a composite likelihood: each difference counted once, the pairs
    they share ignored). Both statistics barely move with slow excursions above the rest
    (a drift, a light touch), which the readings' mean takes in whole."""
    from scipy.optimize import minimize_scalar
    from scipy.special import ndtri

    k = np.round(d / step).astype(np.int64)
    k = k[np.abs(k) * step <= SPIKE_SIGMAS * np.sqrt(2 * v)]
    counts = np.bincount(k - k.min())
    offs = np.arange(k.min(), k.max() + 1)
    z = float(ndtri(at_floor))

    def nll(log_sigma: float) -> float:
        sigma = np.exp(log_sigma)
        _, pr = reading_probs(floor + step / 2 - sigma * z, sigma, floor, step)
        auto = np.correlate(pr, pr, "full")  # P(difference = j steps), j = -(L-1) .. L-1
        j = offs + len(pr) - 1
        inside = (j >= 0) & (j < len(auto))
        pd = np.where(inside, auto[np.clip(j, 0, len(auto) - 1)], 0.0)
        return -float(counts @ np.log(np.maximum(pd, 1e-300)))

    lo, hi = np.log(0.05 * step), np.log(4 * np.sqrt(v) + step)
    best = minimize_scalar(nll, bounds=(lo, hi), method="bounded", options={"xatol": 1e-7})
    sigma = float(np.exp(best.x))
    return floor + step / 2 - sigma * z, sigma


def phase_var(mu: np.ndarray, weights: np.ndarray, sigma: float, step: float) -> float:
    """The variance of unclipped readings ``step * round((mu + sigma n) / step)``, averaged
    over levels ``mu`` (S,) with ``weights`` (S,): where a level sits on the ADC grid moves
    the variance of its readings (a level on a grid point rounds a noise of 0.4 steps to
    0.23 steps^2, one halfway between to 0.42), so each quiet stretch counts at its own."""
    from scipy.special import ndtr

    sigma = max(float(sigma), 1e-12)
    phase = (np.asarray(mu, float) / step) % 1.0  # (S,), in steps
    s = sigma / step
    k = np.arange(np.floor(-12 * s) - 1, np.ceil(12 * s) + 3)  # (L,) levels, in steps
    upper = ndtr((k[None, :] + 0.5 - phase[:, None]) / s)
    p = np.diff(np.concatenate([np.zeros((len(phase), 1)), upper], axis=1), axis=1)
    p[:, -1] += 1.0 - upper[:, -1]
    mean = p @ k
    var = p @ (k * k) - mean * mean
    return float(np.average(var, weights=weights) * step * step)


def fit_rest(
    quiet: list[np.ndarray], *, floor: float | None, step: float, drift_var: float = 0.0
) -> Rest:
    """The :class:`Rest` of one channel from its quiet stretches ``quiet`` (each (n,)),
    ``drift_var`` (a drift's share of half a first difference's variance) left out:

    - not clipped (fewer than :data:`CLIPPED_REST` of the readings at the floor): ``mu`` is
      the readings' mean, and ``sigma`` the noise whose readings, each stretch at its own
      place on the ADC grid (:func:`phase_var`), have the variance :func:`diff_variance`
      finds in the first differences (Sheppard's ``sigma^2 + step^2 / 12`` on average);
    - clipped and quantised: from the share of readings at the floor and the histogram of
      the first differences (:func:`_diff_fit`; the readings' mean would take in every slow
      excursion above the floor);
    - clipped and continuous: the censored Gaussian with the readings' mean and that
      variance (:func:`reading_moments`)."""
    from scipy.optimize import brentq, least_squares

    x = np.concatenate([np.ravel(s) for s in quiet])
    d = np.concatenate([np.diff(np.ravel(s)) for s in quiet])
    m, v = float(np.mean(x)), max(diff_variance(d) - drift_var, 0.0)
    at_floor = float(np.mean(x <= floor + 1e-9 * max(step, 1.0))) if floor is not None else 0.0
    if v <= 0 or (floor is not None and at_floor > 1.0 - MIN_ABOVE_FLOOR):
        level = float(floor) if floor is not None and at_floor > 0 else m
        return Rest(level, float(np.sqrt(max(v - step * step / 12, 0.0))), v, at_floor, x.size)
    if floor is None or at_floor < CLIPPED_REST:
        vv = DIFF_VAR_VAR * v * v / max(d.size, 1)  # the variance of v as an estimate
        if step <= 0:
            return Rest(m, float(np.sqrt(v)), v, at_floor, x.size, vv)
        mus = np.array([np.mean(s) for s in quiet])
        w = np.array([max(np.size(s) - 1, 0) for s in quiet], dtype=float)
        lo, hi = 1e-3 * step, np.sqrt(v) + step
        if phase_var(mus, w, lo, step) >= v:  # less spread than any noise gives: none seen
            return Rest(m, 0.0, v, at_floor, x.size)
        sigma = brentq(lambda sg: phase_var(mus, w, sg, step) - v, lo, hi, xtol=1e-9 * step)
        # through the grid, v moves with sigma^2 at its own rate (1 where Sheppard holds)
        a, b = 0.99 * sigma, 1.01 * sigma
        rate = (phase_var(mus, w, b, step) - phase_var(mus, w, a, step)) / (b * b - a * a)
        return Rest(m, float(sigma), v, at_floor, x.size, vv / max(rate, 1e-3) ** 2)
    if step > 0:
        mu, sigma = _diff_fit(d, v, at_floor, floor, step)
        return Rest(mu, sigma, v, at_floor, x.size)

    def resid(p):
        mean, var = reading_moments(p[0], np.exp(p[1]), floor, step)
        return [(mean - m) / np.sqrt(v), (var - v) / v]

    fit = least_squares(resid, [m, 0.5 * np.log(v)], xtol=1e-12, ftol=1e-12, gtol=1e-12)
    return Rest(float(fit.x[0]), float(np.exp(fit.x[1])), v, at_floor, x.size)
