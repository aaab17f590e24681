"""Spike-train distances: Victor-Purpura, van Rossum, ISI, SPIKE and event synchronization.

All spike trains are sorted 1-D arrays of spike times in seconds. Each function computes the
exact value of its definition (no time grid); the matrices run a numba kernel tested against
a plain reference (:mod:`._reference`) and against Elephant and PySpike (see ``docs/spikes.md``).

Conventions (seed paper 001, eqs. 4-14):

- ``victor_purpura(a, b, q)``: minimum cost of turning ``a`` into ``b`` with deletions and
  insertions (cost 1) and shifts (cost ``q * |dt|``), ``q`` in 1/s. ``q = 0`` gives the count
  difference, ``q = inf`` the number of spikes without an exact partner (Elephant returns
  ``len(a) + len(b)`` there, which is wrong for coincident spikes).
- ``van_rossum(a, b, tau)``: ``sqrt((1/tau) * integral (f_a - f_b)^2 dt)`` over all time with
  the causal kernel ``f(t) = sum H(t - t_i) exp(-(t - t_i)/tau)``; one spike against none gives
  ``1/sqrt(2)``. This is Elephant's value divided by ``sqrt(2)``.
- ``isi_distance`` and ``spike_distance``: time averages of the ISI and SPIKE profiles over
  ``[t_start, t_end]`` with PySpike's (0.9) edge corrections; an empty train is read as spikes at
  ``t_start`` and ``t_end`` and repeated spike times within one train count once, as in PySpike.
- ``event_sync_distance``: ``1 - Q`` of Quian Quiroga et al. (2002), see its docstring.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .._validate import non_negative, positive
from ..errors import ConfigError
from ..records import as_spike_times, check_window
from . import _kernels as K

METRICS = (
    "victor_purpura",
    "van_rossum",
    "isi_distance",
    "spike_distance",
    "event_sync_distance",
)
_ALIASES = {
    "vp": "victor_purpura",
    "vr": "van_rossum",
    "isi": "isi_distance",
    "spike": "spike_distance",
    "event_sync": "event_sync_distance",
    "es": "event_sync_distance",
}
_CODES = {
    "victor_purpura": K.VP,
    "van_rossum": K.VR,
    "isi_distance": K.ISI,
    "spike_distance": K.SPIKE,
    "event_sync_distance": K.ES,
}
_PARAMS = {
    "victor_purpura": ("q",),
    "van_rossum": ("tau",),
    "isi_distance": ("t_start", "t_end"),
    "spike_distance": ("t_start", "t_end"),
    "event_sync_distance": ("tau", "tau_max"),
}


def metric_name(metric: str) -> str:
    """Canonical metric name (accepts the short aliases vp, vr, isi, spike, es)."""
    name = _ALIASES.get(metric, metric)
    if name not in _CODES:
        valid = ", ".join(METRICS + tuple(_ALIASES))
        raise ConfigError(f"metric = {metric!r} is not valid; valid: {valid}")
    return name


def _q(q: float) -> float:
    if isinstance(q, int | float) and math.isinf(q) and q > 0:
        return math.inf
    return non_negative("q", q, unit="1/s")


def _tau(tau: float) -> float:
    return positive("tau", tau, unit="s")


def _es_params(tau: float | None, tau_max: float | None) -> tuple[float, float]:
    fixed = 0.0 if tau is None else positive("tau", tau, unit="s")
    cap = math.inf
    if tau_max is not None and not (isinstance(tau_max, float) and math.isinf(tau_max)):
        cap = positive("tau_max", tau_max, unit="s")
    return fixed, cap


def _params(name: str, params: dict) -> tuple[float, float, bool]:
    """Validate the keyword parameters of a metric; return (p0, p1, unique_spikes)."""
    allowed = _PARAMS[name]
    unknown = set(params) - set(allowed)
    if unknown:
        raise ConfigError(
            f"{name} takes the parameters {', '.join(allowed)}; got unknown "
            f"{', '.join(sorted(unknown))}"
        )
    if name == "victor_purpura":
        if "q" not in params:
            raise ConfigError("victor_purpura needs the parameter q [1/s]")
        return _q(params["q"]), 0.0, False
    if name == "van_rossum":
        if "tau" not in params:
            raise ConfigError("van_rossum needs the parameter tau [s]")
        return _tau(params["tau"]), 0.0, False
    if name in ("isi_distance", "spike_distance"):
        if "t_start" not in params or "t_end" not in params:
            raise ConfigError(f"{name} needs the parameters t_start and t_end [s]")
        t0, t1 = check_window(params["t_start"], params["t_end"])
        return t0, t1, True
    fixed, cap = _es_params(params.get("tau"), params.get("tau_max"))
    return fixed, cap, False


def _one(a: object, b: object, name: str, window: tuple[float, float] | None = None):
    t0, t1 = (None, None) if window is None else window
    x = as_spike_times(a, "a", t_start=t0, t_end=t1)
    y = as_spike_times(b, "b", t_start=t0, t_end=t1)
    return x, y


def victor_purpura(a: np.ndarray, b: np.ndarray, q: float) -> float:
    """Victor-Purpura distance (dimensionless cost) between spike trains ``a``, ``b`` [s].

    ``q`` [1/s] is the cost per second of shifting a spike; ``q >= 0``, ``inf`` allowed.
    """
    x, y = _one(a, b, "victor_purpura")
    row = np.empty(y.size + 1)
    return float(K._vp(x, y, _q(q), row))


def van_rossum(a: np.ndarray, b: np.ndarray, tau: float) -> float:
    """van Rossum distance ``sqrt((1/tau) * integral (f_a - f_b)^2 dt)`` over all time.

    Causal exponential kernel with time constant ``tau`` [s] (finite, > 0); computed in closed
    form as a sum of non-negative terms, so identical trains give exactly 0.
    """
    x, y = _one(a, b, "van_rossum")
    return float(K._vr(x, y, _tau(tau)))


def isi_distance(a: np.ndarray, b: np.ndarray, t_start: float, t_end: float) -> float:
    """ISI-distance, the time average over ``[t_start, t_end]`` [s] of
    ``|nu_a(t) - nu_b(t)| / max(nu_a(t), nu_b(t))`` (``nu`` = current inter-spike interval).

    Edges as PySpike: before the first spike ``nu = max(t_1 - t_start, t_2 - t_1)``, after the
    last ``nu = max(t_end - t_n, t_n - t_{n-1})`` (a lone spike uses its distance to the edge);
    an empty train counts as spikes at both edges. Spikes must lie in ``[t_start, t_end]``.
    """
    window = check_window(t_start, t_end)
    x, y = _one(a, b, "isi_distance", window)
    return float(K._isi(np.unique(x), np.unique(y), *window))


def spike_distance(a: np.ndarray, b: np.ndarray, t_start: float, t_end: float) -> float:
    """SPIKE-distance (Kreuz et al. 2013), time average of the profile over ``[t_start, t_end]``.

    PySpike's edge rules: auxiliary spikes at ``min(t_start, 2 t_1 - t_2)`` and
    ``max(t_end, 2 t_n - t_{n-1})`` take the nearest-neighbour distance of the first and last
    spike; an empty train counts as spikes at both edges.
    """
    window = check_window(t_start, t_end)
    x, y = _one(a, b, "spike_distance", window)
    return float(K._spike(np.unique(x), np.unique(y), *window))


def event_sync_distance(
    a: np.ndarray,
    b: np.ndarray,
    *,
    tau: float | None = None,
    tau_max: float | None = None,
) -> float:
    """Event-synchronization distance ``1 - Q`` (Quian Quiroga et al. 2002; seed 001 eqs. 12-14).

    ``Q = (c(a|b) + c(b|a)) / sqrt(N_a N_b)``, where ``c(a|b)`` counts pairs with
    ``0 < a_i - b_j <= tau_ij`` as 1 and exact coincidences as 1/2.

    tau: ``None`` (default) uses the adaptive window of eq. 12,
        ``tau_ij = min(a_{i+1} - a_i, a_i - a_{i-1}, b_{j+1} - b_j, b_j - b_{j-1}) / 2``, where
        intervals that do not exist (at the first and last spike) are left out of the minimum
        and a pair with no interval at all (single spikes) has ``tau_ij = inf``; a float [s]
        is a fixed window instead.
    tau_max: optional upper bound [s] on the window (``None`` = no bound).

    Edge cases: both trains empty -> 0; exactly one empty -> 1. ``Q`` is limited to 1: it can
    exceed 1 only when a spike lies exactly midway in an interval of the other train whose half
    equals ``tau_ij`` (counted on both sides), a measure-zero tie.
    """
    x, y = _one(a, b, "event_sync_distance")
    fixed, cap = _es_params(tau, tau_max)
    return float(K._es(x, y, fixed, cap))


def _pack(trains: Sequence[object], name: str, unique: bool, window) -> tuple:
    arrays = []
    for k, tr in enumerate(trains):
        arr = as_spike_times(tr, f"trains[{k}]", t_start=window[0], t_end=window[1])
        arrays.append(np.unique(arr) if unique else arr)
    offsets = np.zeros(len(arrays) + 1, dtype=np.int64)
    np.cumsum([a.size for a in arrays], out=offsets[1:])
    flat = np.concatenate(arrays) if arrays else np.empty(0)
    return np.ascontiguousarray(flat, dtype=np.float64), offsets


def cross(
    trains_a: Sequence[np.ndarray],
    trains_b: Sequence[np.ndarray],
    metric: str,
    **params: float,
) -> np.ndarray:
    """Distances between every train of ``trains_a`` and every train of ``trains_b``.

    Returns an ``(len(trains_a), len(trains_b))`` float64 array; ``metric`` is one of
    :data:`METRICS` (or vp, vr, isi, spike, es) and ``params`` its keyword parameters
    (``q``; ``tau``; ``t_start, t_end``; ``tau, tau_max``). The rows of a test set against a
    training set are what ``KNeighborsClassifier(metric="precomputed").predict`` takes.
    """
    return _matrix(trains_a, trains_b, metric, params)


def pairwise(trains: Sequence[np.ndarray], metric: str, **params: float) -> np.ndarray:
    """Symmetric ``(n, n)`` distance matrix of ``n`` spike trains (zero diagonal).

    ``metric`` and ``params`` as in :func:`cross`.
    """
    return _matrix(trains, None, metric, params)


def _matrix(trains_a, trains_b, metric: str, params: dict) -> np.ndarray:
    name = metric_name(metric)
    p0, p1, unique = _params(name, params)
    window = (p0, p1) if unique else (None, None)
    flat_a, off_a = _pack(trains_a, name, unique, window)
    if trains_b is None:
        return K.distance_matrix(_CODES[name], flat_a, off_a, flat_a, off_a, p0, p1, True)
    flat_b, off_b = _pack(trains_b, name, unique, window)
    return K.distance_matrix(_CODES[name], flat_a, off_a, flat_b, off_b, p0, p1, False)


__all__ = [
    "METRICS",
    "cross",
    "event_sync_distance",
    "isi_distance",
    "metric_name",
    "pairwise",
    "spike_distance",
    "van_rossum",
    "victor_purpura",
]
