"""Plain-Python reference implementations of the spike-train distances.

Slow and written straight from the definitions (a full dynamic-programming table, double sums,
look-ups of the previous and next spike at each time), independently of the numba kernels in
:mod:`._kernels`. The tests demand that both agree; nothing else should call these.
"""

from __future__ import annotations

import bisect
import math


def victor_purpura(a, b, q):
    n, m = len(a), len(b)
    table = [[0.0] * (m + 1) for _ in range(n + 1)]
    for i in range(n + 1):
        table[i][0] = float(i)
    for j in range(m + 1):
        table[0][j] = float(j)
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            dt = abs(a[i - 1] - b[j - 1])
            if math.isinf(q):
                shift = 0.0 if dt == 0 else math.inf
            else:
                shift = q * dt
            table[i][j] = min(
                table[i - 1][j] + 1.0, table[i][j - 1] + 1.0, table[i - 1][j - 1] + shift
            )
    return table[n][m]


def van_rossum(a, b, tau):
    # (1/tau) * integral (f_a - f_b)^2 = 1/2 sum_ij s_i s_j exp(-|t_i - t_j| / tau)
    signed = [(t, 1.0) for t in a] + [(t, -1.0) for t in b]
    total = 0.0
    for ti, si in signed:
        for tj, sj in signed:
            total += si * sj * math.exp(-abs(ti - tj) / tau)
    return math.sqrt(max(0.5 * total, 0.0))


def _with_edges(train, t0, t1):
    return list(train) if len(train) else [t0, t1]


def _isi_at(s, t, t0, t1):
    """Instantaneous ISI of train s at a time t strictly inside a segment (PySpike's edges)."""
    n = len(s)
    k = bisect.bisect_right(s, t) - 1  # index of the last spike <= t, -1 if none
    if k == -1:
        first = s[0] - t0
        return max(first, s[1] - s[0]) if n > 1 else first
    if k == n - 1:
        last = t1 - s[-1]
        return max(last, s[-1] - s[-2]) if n > 1 else last
    return s[k + 1] - s[k]


def _breakpoints(a, b, t0, t1):
    pts = sorted({t0, t1, *[t for t in a if t0 < t < t1], *[t for t in b if t0 < t < t1]})
    return pts


def isi_distance(a, b, t0, t1):
    a = _with_edges(a, t0, t1)
    b = _with_edges(b, t0, t1)
    pts = _breakpoints(a, b, t0, t1)
    total = 0.0
    for lo, hi in zip(pts[:-1], pts[1:], strict=True):
        mid = 0.5 * (lo + hi)
        nu_a, nu_b = _isi_at(a, mid, t0, t1), _isi_at(b, mid, t0, t1)
        total += abs(nu_a - nu_b) / max(nu_a, nu_b) * (hi - lo)
    return total / (t1 - t0)


def _aux(s, t0, t1):
    if len(s) > 1:
        return min(t0, 2 * s[0] - s[1]), max(t1, 2 * s[-1] - s[-2])
    return t0, t1


def _dist_to(t, other, t0, t1):
    lo, hi = _aux(other, t0, t1)
    return min(abs(t - u) for u in [lo, *other, hi])


def _local(s, other, t, mid, t0, t1):
    """S_n(t) and the ISI of train s for t in the segment containing `mid`."""
    n = len(s)
    lo, hi = _aux(s, t0, t1)
    k = bisect.bisect_right(s, mid) - 1
    if k == -1:  # before the first spike: auxiliary spike, distance copied from the first
        tp, tf = lo, s[0]
        dp = df = _dist_to(s[0], other, t0, t1)
    elif k == n - 1:  # after the last spike
        tp = s[-1]
        dp = _dist_to(s[-1], other, t0, t1)
        if n == 1 and s[0] <= t0:
            tf, df = t1, _dist_to(t1, other, t0, t1)
        else:
            tf, df = hi, dp
    else:
        tp, tf = s[k], s[k + 1]
        dp, df = _dist_to(tp, other, t0, t1), _dist_to(tf, other, t0, t1)
    isi = tf - tp
    return (dp * (tf - t) + df * (t - tp)) / isi, isi


def spike_distance(a, b, t0, t1):
    a = _with_edges(a, t0, t1)
    b = _with_edges(b, t0, t1)
    pts = _breakpoints(a, b, t0, t1)
    total = 0.0
    for lo, hi in zip(pts[:-1], pts[1:], strict=True):
        mid = 0.5 * (lo + hi)
        values = []
        for t in (lo, hi):
            s1, isi1 = _local(a, b, t, mid, t0, t1)
            s2, isi2 = _local(b, a, t, mid, t0, t1)
            mean = 0.5 * (isi1 + isi2)
            values.append((s1 * isi2 + s2 * isi1) / (2 * mean * mean))
        total += 0.5 * (values[0] + values[1]) * (hi - lo)
    return total / (t1 - t0)


def _half_min_isi(s, i):
    gaps = []
    if i + 1 < len(s):
        gaps.append(s[i + 1] - s[i])
    if i > 0:
        gaps.append(s[i] - s[i - 1])
    return gaps


def event_sync_distance(a, b, tau=None, tau_max=math.inf):
    if len(a) == 0 and len(b) == 0:
        return 0.0
    if len(a) == 0 or len(b) == 0:
        return 1.0

    def c(x, y):
        total = 0.0
        for i in range(len(x)):
            for j in range(len(y)):
                if tau is None:
                    gaps = _half_min_isi(x, i) + _half_min_isi(y, j)
                    t_ij = 0.5 * min(gaps) if gaps else math.inf
                else:
                    t_ij = tau
                t_ij = min(t_ij, tau_max)
                d = x[i] - y[j]
                if d == 0:
                    total += 0.5
                elif 0 < d <= t_ij:
                    total += 1.0
        return total

    q = (c(a, b) + c(b, a)) / math.sqrt(len(a) * len(b))
    return 1.0 - min(q, 1.0)
