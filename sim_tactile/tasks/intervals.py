"""The 95% interval of a mean over a protocol's repeats: the percentile bootstrap.

A row's repeats (its accuracy on each split) vary with the split. Its interval is the 2.5th
and 97.5th percentiles of the means of :data:`RESAMPLES` resamples of the repeats, drawn with
replacement (Efron's percentile bootstrap; ``scipy.stats.bootstrap(method="percentile")``
gives the same numbers from the same generator, which the tests check). The resamples come
from a generator seeded with :data:`SEED`, so the interval is a function of the repeats
alone, and ``sim-tactile check`` recomputes it from them. Fewer than :data:`MIN_REPEATS`
repeats give no interval.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

#: The fewest repeats an interval is given for [repeats]: paper 000's protocol, the smallest
#: of the tasks' (5 splits); MLPerf asks for 3 to 10 runs of a result. Below it a bootstrap
#: interval mostly restates the spread of a handful of numbers.
MIN_REPEATS = 5
#: The bootstrap's resamples: the ends' Monte Carlo error is then about 6% of the standard
#: error of the mean (sqrt(0.025 * 0.975 / 2000) / phi(1.96)); Efron and Tibshirani (1993)
#: suggest 1000-2000 for percentile intervals.
RESAMPLES = 2000
#: The interval's level.
LEVEL = 0.95
#: The seed of the resampling generator (``numpy.random.default_rng``).
SEED = 0
#: How closely a recomputed interval must agree with a stored one [standard errors of the
#: mean]: about four times the ends' Monte Carlo error, so a numpy whose generator draws
#: another stream still agrees, while an edited interval does not.
AGREE_SE = 0.25
#: The most elements resampled at once (a bound on memory: 32 MB of indices).
_CHUNK = 4_000_000
#: Largest difference [relative] between a stored mean or SD and the one recomputed (JSON
#: keeps a float exactly; this allows for another summation order).
REL_TOL = 1e-9


def _values(repeats: Sequence[float]) -> np.ndarray:
    return np.asarray(repeats, dtype=np.float64).reshape(-1)


def bootstrap_means(repeats: Sequence[float]) -> np.ndarray:
    """The :data:`RESAMPLES` resampled means of ``repeats`` (the interval's distribution)."""
    x = _values(repeats)
    rng = np.random.default_rng(SEED)
    rows = max(1, _CHUNK // x.size)
    out = []
    for start in range(0, RESAMPLES, rows):
        idx = rng.integers(0, x.size, size=(min(rows, RESAMPLES - start), x.size))
        out.append(x[idx].mean(axis=1))
    return np.concatenate(out)


def interval(repeats: Sequence[float]) -> tuple[float, float] | None:
    """The 95% percentile-bootstrap interval of the mean of ``repeats``, or None for fewer
    than :data:`MIN_REPEATS`."""
    x = _values(repeats)
    if x.size < MIN_REPEATS or not np.isfinite(x).all():
        return None
    tail = 100.0 * (1.0 - LEVEL) / 2.0
    lo, hi = np.percentile(bootstrap_means(x), [tail, 100.0 - tail])
    return float(lo), float(hi)


def interval_list(repeats: Sequence[float]) -> list[float] | None:
    """:func:`interval` as a list (JSON's), or None."""
    ci = interval(repeats)
    return None if ci is None else [ci[0], ci[1]]


def summary(repeats: Sequence[float]) -> dict:
    """``{mean, sd, ci95, repeats}`` of one metric: the mean, the SD over the repeats (ddof =
    0, as the reports give it), the 95% interval (None below :data:`MIN_REPEATS`) and the
    repeats as floats."""
    x = _values(repeats)
    ci = interval(x)
    return {
        "mean": float(np.mean(x)),
        "sd": float(np.std(x)),
        "ci95": None if ci is None else [ci[0], ci[1]],
        "repeats": [float(v) for v in x],
    }


def close(stored: float, recomputed: float) -> bool:
    """A stored mean or SD agrees with the one recomputed from its repeats."""
    return math.isclose(stored, recomputed, rel_tol=REL_TOL, abs_tol=REL_TOL)


def interval_agrees(stored: Sequence[float], repeats: Sequence[float]) -> bool:
    """A stored interval agrees with the one recomputed from ``repeats`` (within
    :data:`AGREE_SE` standard errors of the mean, and :data:`REL_TOL`)."""
    now = interval(repeats)
    if now is None:
        return False
    x = _values(repeats)
    tol = AGREE_SE * float(np.std(x)) / math.sqrt(x.size) + REL_TOL
    return all(abs(float(a) - b) <= tol for a, b in zip(stored, now, strict=True))


def interval_text(ci: Sequence[float] | None, digits: int = 3) -> str:
    """``[lo, hi]`` to ``digits`` decimals, or ``-`` where there is none."""
    if ci is None:
        return "-"
    return f"[{ci[0]:.{digits}f}, {ci[1]:.{digits}f}]"
