"""The vector work of an iteration of :class:`~.spectral.Spectral`'s conjugate gradients,
compiled: everything but the FFT products, in two calls an iteration instead of some
twenty-five numpy calls (whose per-call costs were most of a spectral solve's time on the
lattices of a curved pad or the iCub's patch).

The same arithmetic as the numpy iteration (:meth:`~.spectral.Spectral._cg_numpy`, the
reference) but for the sums over the contact set, taken here in node order where numpy
takes them pairwise or through BLAS: the two agree to the iteration's tolerance (tested),
not to the bit.
"""

from __future__ import annotations

import numpy as np

from ...._jit import njit


@njit
def gradient(u, pen, p, g, held):
    """``g = u - pen`` less its mean on the contact set (``p > 0``) when ``held``; returns
    ``(G, n_on)``: the squared norm of ``g`` on the set, and the set's size."""
    n = u.shape[0]
    s = 0.0
    c = 0
    for i in range(n):
        g[i] = u[i] - pen[i]
        if p[i] > 0.0:
            s += g[i]
            c += 1
    if c > 0 and held:
        m = s / c
        for i in range(n):
            g[i] -= m
    G = 0.0
    for i in range(n):
        if p[i] > 0.0:
            G += g[i] * g[i]
    return G, c


@njit
def direction(g, p, t, beta):
    """``t = where(p > 0, g + beta t, 0)`` in place."""
    for i in range(t.shape[0]):
        t[i] = g[i] + beta * t[i] if p[i] > 0.0 else 0.0


@njit
def step(r_raw, t, g, p, new, u, ok, held, total, G, rounding, direct_max, table, nx, scale):
    """The rest of an iteration after ``r_raw = C t``: the step length on the set, the
    projection onto ``p >= 0`` (nodes off the set that overlap the plate join), ``u = C p``
    carried (by direct sums where the projection moved at most ``direct_max`` nodes), the
    sum held at ``total``. Writes the new pressures into ``new`` and ``u`` in place.

    Returns ``(status, delta, change, carried, scale)``: status 1 where no direction is left
    on the set (the caller lets overlapping nodes join), else 0; ``delta`` 0 when nodes
    joined (the next direction restarts), else 1; ``carried`` False when ``u`` must be taken
    again by FFT."""
    n = p.shape[0]
    mean_r = 0.0
    c = 0
    umax = 0.0
    for i in range(n):
        a = abs(u[i])
        if a > umax:
            umax = a
        if p[i] > 0.0:
            mean_r += r_raw[i]
            c += 1
    if held and c > 0:
        mean_r /= c
    else:
        mean_r = 0.0
    rt = 0.0
    gt = 0.0
    for i in range(n):
        if p[i] > 0.0:
            rt += (r_raw[i] - mean_r) * t[i]
            gt += g[i] * t[i]
    floor = (rounding * umax) ** 2 * c
    if not rt > 0.0 or G <= floor:
        return 1, 0.0, 0.0, True, scale
    tau = gt / rt
    joined = False
    moved = np.empty(direct_max + 1, np.int64)
    dmove = np.empty(direct_max + 1)
    n_moved = 0
    for i in range(n):
        line = p[i] - tau * t[i]
        v = line if line > 0.0 else 0.0
        if v == 0.0 and g[i] < 0.0 and ok[i]:
            v -= tau * g[i]
            joined = True
        new[i] = v
        if v != line:
            if n_moved <= direct_max:
                moved[n_moved] = i
                dmove[n_moved] = v - line
            n_moved += 1
    carried = n_moved <= direct_max
    if carried:
        for i in range(n):
            u[i] = u[i] - tau * r_raw[i]
        add_columns(u.reshape(u.shape[0] // nx, nx), table, moved[:n_moved], dmove[:n_moved], nx)
    if held:
        tot = 0.0
        for i in range(n):
            tot += new[i]
        s = total / tot
        for i in range(n):
            new[i] *= s
        if carried:
            for i in range(n):
                u[i] *= s
    sum_new = 0.0
    diff = 0.0
    for i in range(n):
        sum_new += new[i]
        diff += abs(new[i] - p[i])
    if scale < 0.0:
        scale = max(sum_new, 1e-300)
    change = diff / max(sum_new, scale * 1e-12)
    return 0, 0.0 if joined else 1.0, change, carried, scale


@njit
def add_columns(u, table, nodes, dp, nx):
    """``u += C[:, nodes] @ dp`` on the lattice: each node's column is the kernel ``table``
    shifted to it (``u`` and ``table`` as (ny, nx))."""
    ny = u.shape[0]
    for k in range(nodes.size):
        jy, jx = divmod(nodes[k], nx)
        d = dp[k]
        for iy in range(ny):
            row = table[abs(iy - jy)]
            for ix in range(nx):
                u[iy, ix] += d * row[abs(ix - jx)]
