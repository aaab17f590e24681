"""Numba kernels of the spike-train distances (fast path).

Every function here has a plain-Python counterpart in :mod:`._reference` written from the
definitions, and the tests demand equality within rounding. Sets of trains are passed packed:
``flat`` holds all spike times one train after another and ``offsets`` (length n + 1) marks
where train ``i`` starts and ends (``flat[offsets[i]:offsets[i + 1]]``).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit

VP, VR, ISI, SPIKE, ES = 0, 1, 2, 3, 4


@njit
def _vp(x, y, q, row):
    n = x.size
    m = y.size
    if n == 0:
        return float(m)
    if m == 0:
        return float(n)
    for j in range(m + 1):
        row[j] = j
    q_inf = math.isinf(q)
    for i in range(1, n + 1):
        diag = row[0]
        row[0] = i
        xi = x[i - 1]
        for j in range(1, m + 1):
            d = abs(xi - y[j - 1])
            if q_inf:
                shift = 0.0 if d == 0.0 else 2.0
            else:
                shift = min(q * d, 2.0)
            best = diag + shift
            a = row[j] + 1.0
            if a < best:
                best = a
            b = row[j - 1] + 1.0
            if b < best:
                best = b
            diag = row[j]
            row[j] = best
    return row[m]


@njit
def _vr(x, y, tau):
    # f_x - f_y right after each merged event is g; between events it decays as exp(-t/tau),
    # so the integral of its square is a sum of non-negative terms (no cancellation).
    n = x.size
    m = y.size
    i = 0
    j = 0
    g = 0.0
    acc = 0.0
    t_prev = 0.0
    first = True
    while i < n or j < m:
        if j >= m or (i < n and x[i] <= y[j]):
            t = x[i]
            s = 1.0
            i += 1
        else:
            t = y[j]
            s = -1.0
            j += 1
        if not first:
            dt = t - t_prev
            acc += g * g * (-math.expm1(-2.0 * dt / tau))
            g = g * math.exp(-dt / tau)
        g += s
        t_prev = t
        first = False
    acc += g * g
    return math.sqrt(0.5 * acc)


@njit
def _nonempty(x, t0, t1):
    if x.size > 0:
        return x
    out = np.empty(2)
    out[0] = t0
    out[1] = t1
    return out


@njit
def _isi_nu(s, k, t0, t1):
    n = s.size
    if k < 0:
        return max(s[0] - t0, s[1] - s[0]) if n > 1 else s[0] - t0
    if k < n - 1:
        return s[k + 1] - s[k]
    return max(t1 - s[n - 1], s[n - 1] - s[n - 2]) if n > 1 else t1 - s[n - 1]


@njit
def _isi(x, y, t0, t1):
    a = _nonempty(x, t0, t1)
    b = _nonempty(y, t0, t1)
    na = a.size
    nb = b.size
    ka = 0 if a[0] <= t0 else -1
    kb = 0 if b[0] <= t0 else -1
    t = t0
    acc = 0.0
    while True:
        ta = a[ka + 1] if ka + 1 < na else np.inf
        tb = b[kb + 1] if kb + 1 < nb else np.inf
        tn = min(ta, tb, t1)
        if tn > t:
            nu_a = _isi_nu(a, ka, t0, t1)
            nu_b = _isi_nu(b, kb, t0, t1)
            top = max(nu_a, nu_b)
            if top > 0.0:
                acc += abs(nu_a - nu_b) / top * (tn - t)
        if tn >= t1:
            break
        if ta == tn:
            ka += 1
        if tb == tn:
            kb += 1
        t = tn
    return acc / (t1 - t0)


@njit
def _aux(s, t0, t1):
    n = s.size
    if n > 1:
        return min(t0, 2.0 * s[0] - s[1]), max(t1, 2.0 * s[n - 1] - s[n - 2])
    return t0, t1


@njit
def _nearest(t, s, lo, hi, start):
    # distance from t to the nearest of {lo, s..., hi}; s sorted, scanning from `start`
    d = min(abs(t - lo), abs(hi - t))
    k = start
    n = s.size
    while k < n and s[k] < t:
        k += 1
    if k < n:
        d = min(d, s[k] - t)
    if k > 0:
        d = min(d, t - s[k - 1])
    return d, k


@njit
def _spike_knots(x, y, t0, t1):
    """Knot times and values of the local weighted distance S_x (PySpike's edge rules)."""
    n = x.size
    ylo, yhi = _aux(y, t0, t1)
    xlo, xhi = _aux(x, t0, t1)
    lead = 1 if x[0] > t0 else 0
    kt = np.empty(n + 1 + lead)
    kv = np.empty(n + 1 + lead)
    k = 0
    for i in range(n):
        d, k = _nearest(x[i], y, ylo, yhi, k)
        kt[i + lead] = x[i]
        kv[i + lead] = d
    if lead:
        kt[0] = xlo
        kv[0] = kv[1]
    if n == 1 and x[0] <= t0:
        d, k = _nearest(t1, y, ylo, yhi, 0)
        kt[n + lead] = t1
        kv[n + lead] = d
    else:
        kt[n + lead] = xhi
        kv[n + lead] = kv[n + lead - 1]
    return kt, kv


@njit
def _spike_at(t, k1, v1, k2, v2, i1, i2):
    isi1 = k1[i1 + 1] - k1[i1]
    isi2 = k2[i2 + 1] - k2[i2]
    s1 = (v1[i1] * (k1[i1 + 1] - t) + v1[i1 + 1] * (t - k1[i1])) / isi1 if isi1 > 0 else v1[i1]
    s2 = (v2[i2] * (k2[i2 + 1] - t) + v2[i2 + 1] * (t - k2[i2])) / isi2 if isi2 > 0 else v2[i2]
    tot = isi1 + isi2
    if tot <= 0.0:
        return 0.0
    # 2 (s1 isi2 + s2 isi1) / tot^2, scaled first so that tiny intervals do not underflow
    return 2.0 * ((s1 / tot) * (isi2 / tot) + (s2 / tot) * (isi1 / tot))


@njit
def _spike(x, y, t0, t1):
    a = _nonempty(x, t0, t1)
    b = _nonempty(y, t0, t1)
    ka, va = _spike_knots(a, b, t0, t1)
    kb, vb = _spike_knots(b, a, t0, t1)
    ia = 0
    ib = 0
    t = t0
    acc = 0.0
    while True:
        ta = ka[ia + 1]
        tb = kb[ib + 1]
        tn = min(ta, tb, t1)
        if tn > t:
            y0 = _spike_at(t, ka, va, kb, vb, ia, ib)
            y1 = _spike_at(tn, ka, va, kb, vb, ia, ib)
            acc += 0.5 * (y0 + y1) * (tn - t)
        if tn >= t1:
            break
        if ta == tn:
            ia += 1
        if tb == tn:
            ib += 1
        t = tn
    return acc / (t1 - t0)


@njit
def _es_counts(x, y, tau_fixed, tau_max):
    """c(x|y) of Quian Quiroga et al. (2002): spikes of y shortly before spikes of x."""
    n = x.size
    m = y.size
    c = 0.0
    start = 0
    for i in range(n):
        xi = x[i]
        rx = np.inf
        if i + 1 < n:
            rx = min(rx, x[i + 1] - xi)
        if i > 0:
            rx = min(rx, xi - x[i - 1])
        window = min(tau_fixed, tau_max) if tau_fixed > 0.0 else min(0.5 * rx, tau_max)
        while start < m and y[start] < xi - window:
            start += 1
        j = start
        while j < m and y[j] <= xi:
            if tau_fixed > 0.0:
                tau = tau_fixed
            else:
                ry = np.inf
                if j + 1 < m:
                    ry = min(ry, y[j + 1] - y[j])
                if j > 0:
                    ry = min(ry, y[j] - y[j - 1])
                tau = 0.5 * min(rx, ry)
            tau = min(tau, tau_max)
            d = xi - y[j]
            if d == 0.0:
                c += 0.5
            elif d <= tau:
                c += 1.0
            j += 1
    return c


@njit
def _es(x, y, tau_fixed, tau_max):
    n = x.size
    m = y.size
    if n == 0 and m == 0:
        return 0.0
    if n == 0 or m == 0:
        return 1.0
    q = (_es_counts(x, y, tau_fixed, tau_max) + _es_counts(y, x, tau_fixed, tau_max)) / math.sqrt(
        n * m
    )
    return 1.0 - min(q, 1.0)


@njit
def _pair(metric, x, y, p0, p1, row):
    if metric == VP:
        return _vp(x, y, p0, row)
    if metric == VR:
        return _vr(x, y, p0)
    if metric == ISI:
        return _isi(x, y, p0, p1)
    if metric == SPIKE:
        return _spike(x, y, p0, p1)
    return _es(x, y, p0, p1)


@njit
def distance_matrix(metric, flat_a, off_a, flat_b, off_b, p0, p1, symmetric):
    """(n_a, n_b) matrix of one metric between two packed sets of trains.

    ``symmetric`` means both sets are the same: only the upper triangle is computed, the
    diagonal is zero and the lower triangle is mirrored.
    """
    na = off_a.size - 1
    nb = off_b.size - 1
    longest = 0
    for j in range(nb):
        longest = max(longest, off_b[j + 1] - off_b[j])
    row = np.empty(longest + 1)
    out = np.zeros((na, nb))
    for i in range(na):
        x = flat_a[off_a[i] : off_a[i + 1]]
        j0 = i + 1 if symmetric else 0
        for j in range(j0, nb):
            y = flat_b[off_b[j] : off_b[j + 1]]
            d = _pair(metric, x, y, p0, p1, row)
            out[i, j] = d
            if symmetric:
                out[j, i] = d
    return out
