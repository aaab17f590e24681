"""Threshold encoding of seed paper 000 (Taunyazov et al. 2020, eq. 1): K thresholds give
2K + 1 spike trains per input channel.

Eq. 1 is garbled in the extracted text; this is our reading of its intent, with the K
thresholds ``theta_1 < ... < theta_K`` of a channel and samples ``y(t)``:

- channels ``1..K`` (``up``): a spike at sample ``t`` when the signal enters the region at or
  above ``theta_k``: ``y(t) >= theta_k`` and ``y(t-1) < theta_k`` (the legible first line);
- channels ``K+1..2K`` (``down``): a spike when it leaves that region:
  ``y(t) < theta_k`` and ``y(t-1) >= theta_k`` (the garbled second line reads as the downward
  crossing of the same thresholds; with this choice up and down spikes of one threshold
  strictly alternate);
- channel ``2K+1`` (``max``): ``y(t) = max y`` (third line). ``extra="global_max"`` (default)
  takes it literally: one spike at the first sample where the recording reaches its maximum.
  ``extra="local_max"`` instead fires at every local maximum (``y(t-1) < y(t) >= y(t+1)``),
  an alternative reading that carries more information.

Sample ``t`` (0-based) is at time ``t / rate_hz``; the first sample has no predecessor and so
never gives a crossing.
"""

from __future__ import annotations

import numpy as np

from .._validate import integer, one_of, positive
from ..errors import ConfigError
from ._common import check_current

EXTRA = ("global_max", "local_max")
SPACING = ("linspace", "quantile")


def thresholds_from_data(
    signals: np.ndarray, n_thresholds: int, spacing: str = "linspace"
) -> np.ndarray:
    """Per-channel thresholds from training data ``(samples, time, channels)``: shape (C, K).

    ``linspace``: K evenly spaced values strictly inside ``[min, max]`` of the channel,
    ``min + k (max - min) / (K + 1)``; ``quantile``: the ``k / (K + 1)`` quantiles.
    """
    k = integer("n_thresholds", n_thresholds, 1, None)
    spacing = one_of("spacing", spacing, SPACING)
    x = check_current(signals, "X")
    if x.ndim != 3:
        raise ConfigError(f"X must have shape (samples, time, channels), got {x.shape}")
    flat = x.transpose(2, 0, 1).reshape(x.shape[2], -1)
    frac = np.arange(1, k + 1) / (k + 1)
    if spacing == "quantile":
        return np.quantile(flat, frac, axis=1).T.copy()
    lo = flat.min(axis=1)[:, None]
    hi = flat.max(axis=1)[:, None]
    return lo + frac[None, :] * (hi - lo)


def threshold_channel_names(channel_names: list[str], n_thresholds: int) -> list[str]:
    """Names of the 2K + 1 output channels of each input channel, in output order."""
    out = []
    for c in channel_names:
        out += [f"{c}:up{k}" for k in range(n_thresholds)]
        out += [f"{c}:down{k}" for k in range(n_thresholds)]
        out.append(f"{c}:max")
    return out


def threshold_encode(
    signal: np.ndarray,
    rate_hz: float,
    thresholds: np.ndarray,
    *,
    extra: str = "global_max",
) -> list[np.ndarray]:
    """Encode one recording ``signal`` of shape ``(time, channels)`` (or 1-D).

    ``thresholds``: shape ``(K,)`` (same for all channels) or ``(channels, K)``, in the units
    of the signal, sorted or not. Returns ``channels * (2K + 1)`` spike-time arrays [s], for
    each input channel ``up_1..up_K, down_1..down_K, max`` (see the module docstring).
    """
    rate_hz = positive("rate_hz", rate_hz, unit="Hz")
    extra = one_of("extra", extra, EXTRA)
    y = check_current(signal, "signal")
    if y.ndim == 1:
        y = y[:, None]
    if y.ndim != 2 or y.shape[0] < 1:
        raise ConfigError(f"signal must have shape (time, channels), got {y.shape}")
    n_t, n_c = y.shape
    th = check_current(thresholds, "thresholds")
    if th.ndim == 1:
        th = np.broadcast_to(th, (n_c, th.size))
    if th.ndim != 2 or th.shape[0] != n_c or th.shape[1] < 1:
        raise ConfigError(
            f"thresholds must have shape (K,) or (channels={n_c}, K), got {np.shape(thresholds)}"
        )
    th = np.sort(th, axis=1)
    out: list[np.ndarray] = []
    for c in range(n_c):
        yc = y[:, c]
        above = yc[:, None] >= th[c][None, :]  # (T, K)
        ups, downs = [], []
        for k in range(th.shape[1]):
            change = np.flatnonzero(above[1:, k] != above[:-1, k]) + 1
            ups.append(change[above[change, k]] / rate_hz)
            downs.append(change[~above[change, k]] / rate_hz)
        if extra == "global_max":
            peaks = np.array([np.argmax(yc)]) if n_t else np.empty(0, dtype=np.int64)
        else:
            inner = np.arange(1, n_t - 1)
            peaks = inner[(yc[inner - 1] < yc[inner]) & (yc[inner] >= yc[inner + 1])]
        out += ups + downs + [peaks / rate_hz]
    return [np.asarray(t, dtype=np.float64) for t in out]
