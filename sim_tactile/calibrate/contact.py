"""A channel's noise where the force is known: the residual of the one-factor fit in contact.

At rest a channel shows its noise on its quiet samples only (:mod:`.rest`): a dozen slides
with half a second of rest at either end give about a thousand, an SD from them a standard
error near 2.5%. In contact it shows it again, on every sample, once the force's part is
taken out. Every channel and the force reading read the same force (the model of
:mod:`.forced`: ``x_c = offset_c + gain_c * F + noise_c``), so together they are a one-factor
model, and each channel's *unique* variance is its noise:

- the samples: first differences within contact (the force above its quiet band at both
  samples; a difference takes out each slide's level and a slow drift, and keeps the
  texture's fast part, which all channels share), of the channels whose readings stay off
  their floor there (a clipped reading is no line in the force) and of the force reading;
- the fit: the maximum-likelihood one-factor model of their covariance (:func:`one_factor`);
  half a channel's unique variance is its noise's variance as recorded (the ADC's step
  included: in contact the level moves over the grid, so its rounding adds ``step^2 / 12``
  on average), less the drift's share;
- its standard error (:func:`contact_noise`) counts the force's own error where the other
  channels estimate it;
- :func:`combine`: the rest's and the contact's estimates, each weighted by the inverse of
  its variance, where they agree within :data:`AGREE_SIGMAS` standard errors. Where they do
  not, the channel's response in contact is not one line in the force (a real sensor's
  often is not), and the rest's estimate stands alone; the calibration's notes name those
  channels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .rest import SPIKE_SIGMAS

#: The rest's and the contact's noise estimates are combined where they differ by less than
#: this many standard errors of their difference (beyond it, a real channel's response is
#: not one line in the force, and the rest's estimate stands alone).
AGREE_SIGMAS = 4.0
#: A channel enters the contact fit when at most this share of its contact readings sit at
#: its floor (clipped readings carry no line in the force).
MAX_FLOOR_SHARE = 0.001
#: The one-factor model needs at least this many variables to be identified.
MIN_FACTOR_VARS = 3
#: ... and at least this many differences.
MIN_DIFFERENCES = 200
#: The fixed point of :func:`one_factor` stops when no unique variance moves by more than
#: this share of itself.
FACTOR_RTOL = 1e-12
#: ... or after this many steps.
FACTOR_MAX_STEPS = 20_000


def one_factor(cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The maximum-likelihood one-factor model of a covariance ``cov`` (p, p): loadings
    (p,) and unique variances (p,) with ``cov ~ loadings loadings^T + diag(unique)``. The
    fixed point of Joreskog's (as scikit-learn's ``FactorAnalysis`` iterates it on the data,
    here on their correlations, for variables of any scale): the leading eigenpair of the
    correlations scaled by the unique deviations gives the loadings, 1 less their squares
    the unique variances."""
    scale = np.sqrt(np.diag(cov))
    corr = cov / np.outer(scale, scale)
    psi = np.full(len(scale), 0.5)
    load = np.zeros_like(psi)
    for _ in range(FACTOR_MAX_STEPS):
        s = np.sqrt(psi)
        w, v = np.linalg.eigh(corr / np.outer(s, s))
        load = np.sqrt(max(w[-1] - 1.0, 0.0)) * v[:, -1] * s
        new = np.maximum(1.0 - load * load, 1e-12)
        done = np.all(np.abs(new - psi) <= FACTOR_RTOL * new)
        psi = new
        if done:
            break
    return load * scale, psi * scale * scale


@dataclass(frozen=True)
class ContactNoise:
    """Per channel (C,): the noise variance as recorded in contact (NaN where not fitted)
    and its variance as an estimate; ``n``: how many differences the fit saw."""

    var: np.ndarray
    var_var: np.ndarray
    n: int


def _floor_share(levels, forces, band_n: float, floor: float | None) -> np.ndarray:
    """Each channel's share (C,) of its readings in contact (the force above ``band_n``)
    that sit at its ``floor`` (0 where not clipped)."""
    at, n = np.zeros(levels[0].shape[1]), 0
    for x, f in zip(levels, forces, strict=True):
        on = f > band_n
        n += int(on.sum())
        if floor is not None:
            at += np.count_nonzero(x[on] <= floor + 1e-9, axis=0)
    return at / max(n, 1)


def _differences(levels, forces, band_n: float, channels: np.ndarray) -> np.ndarray:
    """The first differences (N, len(channels) + 1) of the ``channels`` and of the force,
    where the force is above ``band_n`` at both samples (N may be 0)."""
    rows = [np.empty((0, len(channels) + 1))]
    for x, f in zip(levels, forces, strict=True):
        on = f > band_n
        both = on[1:] & on[:-1]
        if both.any():
            rows.append(np.diff(np.column_stack([x[:, channels], f]), axis=0)[both])
    return np.concatenate(rows)


def contact_noise(
    levels: list[np.ndarray],
    forces: list[np.ndarray],
    band_n: float,
    floor: float | None,
    drift_var: np.ndarray,
) -> ContactNoise:
    """Each channel's noise variance as recorded (C,), from the residual of the one-factor
    fit of recordings ``levels`` (each (T, C)) and ``forces`` (each (T,), N from the tare)
    in contact (the force above ``band_n``), the drift's share ``drift_var`` (C,) of half a
    first difference's variance taken out (see the module)."""
    nan = np.full(levels[0].shape[1], np.nan)
    use = np.flatnonzero(_floor_share(levels, forces, band_n, floor) <= MAX_FLOOR_SHARE)
    if use.size + 1 < MIN_FACTOR_VARS:
        return ContactNoise(nan, nan, 0)
    d = _differences(levels, forces, band_n, use)
    moving = d.std(axis=0) > 0 if len(d) else np.zeros(d.shape[1], bool)
    use, d = use[moving[:-1]], d[:, np.append(moving[:-1], True)]  # a dead channel: no fit
    if len(d) < MIN_DIFFERENCES or not moving[-1] or use.size + 1 < MIN_FACTOR_VARS:
        return ContactNoise(nan, nan, len(d))
    for _ in range(2):  # a glitch is no noise: rows with a residual past SPIKE_SIGMAS go
        load, psi = one_factor(np.cov(d, rowvar=False))
        prec = load / psi
        factor = (d - d.mean(axis=0)) @ prec / (1.0 + load @ prec)
        resid = (d - d.mean(axis=0)) - np.outer(factor, load)
        keep = (np.abs(resid) <= SPIKE_SIGMAS * np.sqrt(psi)).all(axis=1)
        if keep.all():
            break
        d = d[keep]
    # the force's error where the others estimate it, in channel c's units
    others = 1.0 + load @ prec - load * prec
    force_err = load * load / others
    n = len(d)
    var, var_var = nan.copy(), nan.copy()
    var[use] = 0.5 * psi[:-1] - drift_var[use]
    var_var[use] = 3.0 * (0.5 * (psi[:-1] + force_err[:-1])) ** 2 / n
    return ContactNoise(var, var_var, n)


def combine(
    rest_var: np.ndarray, rest_var_var: np.ndarray, contact: ContactNoise
) -> tuple[np.ndarray, np.ndarray]:
    """The noise variances (C,) from the rest's estimates ``rest_var`` (with their variances
    ``rest_var_var``) and the contact's, each weighted by the inverse of its variance where
    the two agree within :data:`AGREE_SIGMAS`; and where they were combined (C,) bool."""
    both = np.isfinite(contact.var) & np.isfinite(rest_var_var) & (rest_var_var > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        gap = np.abs(contact.var - rest_var) / np.sqrt(contact.var_var + rest_var_var)
    both &= np.nan_to_num(gap, nan=np.inf) <= AGREE_SIGMAS
    out = np.array(rest_var, dtype=float)
    wr = 1.0 / rest_var_var[both]
    wc = 1.0 / contact.var_var[both]
    out[both] = (wr * rest_var[both] + wc * contact.var[both]) / (wr + wc)
    return out, both
