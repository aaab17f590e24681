"""The vector work of an iteration of :class:`~.batched.BatchedSpectral`, in torch: each
row of a ``(b, n)`` tensor one pose, each per-pose number a ``(b, 1)`` column.

The arithmetic of :mod:`.cg_kernels` (the numpy solve's compiled iteration), in two pure
functions around the iteration's FFT product, so that they can be compiled
(``torch.compile``: inductor fuses their element-wise work and sums into a few kernels; it
generates no complex kernels, so the product stays outside). This module imports torch: it is
imported when a batched solver is made, never by the CPU path.
"""

from __future__ import annotations

import torch


def starts(pen, warm, total, diag: float, held: bool):
    """The poses' starts (:meth:`~.spectral.Spectral._starts`) from their depths ``pen``
    (``-inf`` out of reach) and last pressures ``warm``: ``(ok, pen_ok, flat, first,
    has_warm, gap_tol)``: the nodes in reach, the depths there (0 elsewhere), the uniform
    start, the first start (the warm pressures where some are in reach, else the uniform
    one; held at ``total``), whether each pose has a warm start, and the gap beyond which a
    node off the set overlaps."""
    ok = torch.isfinite(pen)
    pen_ok = torch.where(ok, pen, 0.0)
    okf = ok.to(pen.dtype)
    count = okf.sum(1, keepdim=True)
    if held:
        flat = okf * (total / count)
    else:  # the pressure that lifts the deepest node out, spread
        top = torch.where(ok, pen, -torch.inf).amax(1, keepdim=True).clamp_min(0.0)
        tiny = 1e-300 if pen.dtype == torch.float64 else torch.finfo(pen.dtype).tiny
        flat = okf * (top / (diag * count) + tiny)
    first = torch.where(ok, warm, 0.0)
    has_warm = (first != 0).any(1, keepdim=True)
    if held:
        first = first * (total / torch.where(has_warm, first.sum(1, keepdim=True), 1.0))
    first = torch.where(has_warm, first, flat)
    gap_tol = 1e-9 * pen_ok.abs().amax(1, keepdim=True).clamp_min(1e-12)
    return ok, pen_ok, flat, first, has_warm, gap_tol


def mean_gaps(u, pen_ok, P):
    """Each pose's mean of ``u - pen_ok`` on its contact set (``P > 0``), (b, 1): the pad's
    shift at which the pressures hold their total."""
    on = P > 0
    return torch.where(on, u - pen_ok, 0.0).sum(1, keepdim=True) / on.sum(1, keepdim=True)


def gradient(P, U, pen, T, delta, g_old, held: bool):
    """The gradient on the contact set and the next direction: ``(onf, c, g, G, t, g_old,
    umax)``, ``onf`` the set as 0 or 1. ``g = U - pen`` less its mean on the set (``P > 0``) when ``held``; ``G`` its
    squared norm on the set, ``c`` the set's size, ``t`` the conjugate direction on the set,
    ``umax`` the largest deflection."""
    on = P > 0
    onf = on.to(P.dtype)
    c = onf.sum(1, keepdim=True)
    g = U - pen
    if held:
        g = g - (g * onf).sum(1, keepdim=True) / c
    g_on = g * onf
    G = (g_on * g_on).sum(1, keepdim=True)
    t = torch.where(on, g + (delta * G / g_old) * T, 0.0)
    g_old = torch.where(G > 0, G, 1.0)
    umax = U.abs().amax(1, keepdim=True)
    return onf, c, g, G, t, g_old, umax


def project(P, U, g, t, r, onf, c, G, umax, ok, total, scale, gap_tol, consts, held: bool):
    """The rest of the iteration after ``r = C t`` (:func:`~.cg_kernels.step` and
    :meth:`~.spectral.Spectral._joined`): the step length on the set, the projection onto
    ``P >= 0`` (nodes off the set that overlap join), ``U`` carried, the sum held at
    ``total``; where no direction is left, the nodes off the set that overlap the plate
    join. ``consts``: ``(tol, rounding, diag)``.

    Returns ``(P, U, T, delta, stale, conv, go, change, scale)``: the new pressures,
    deflections and direction, ``delta`` 0 where the next direction restarts, ``stale``
    where ``U`` must be taken again by FFT, ``conv`` where the pose is solved, ``go`` where
    it took a step, ``change`` the step's relative change of the pressures."""
    tol, rounding, diag = consts
    dtype = P.dtype
    if held:
        r_mean = (r * onf).sum(1, keepdim=True) / c
        rt = ((r - r_mean) * t).sum(1, keepdim=True)
    else:
        rt = (r * t).sum(1, keepdim=True)
    gt = (g * t).sum(1, keepdim=True)
    nodir = ~(rt > 0) | (G <= (rounding * umax) ** 2 * c)  # no direction left on the set
    tau = torch.where(nodir, 0.0, gt / rt)
    line = P - tau * t
    v = line.clamp_min(0.0)
    overlap = (v == 0) & (g < 0) & ok
    v = torch.where(overlap, -tau * g, v)
    joined = overlap.any(1, keepdim=True)
    moved = (v != line).any(1, keepdim=True)
    u = U - tau * r
    if held:
        s = total / v.sum(1, keepdim=True)
        v = v * s
        u = u * s
    sum_new = v.sum(1, keepdim=True)
    if not held:  # (1e-300 as the numpy solve, the smallest normal number in float32)
        tiny = 1e-300 if dtype == torch.float64 else torch.finfo(dtype).tiny
        scale = torch.where(scale < 0, sum_new.clamp_min(tiny), scale)
    change = (v - P).abs().sum(1, keepdim=True) / torch.maximum(sum_new, scale * 1e-12)
    # no direction left: solved, unless nodes off the set overlap the plate; those join with
    # the pressure that would lift them alone
    join = nodir & (P == 0) & (g < -gap_tol) & ok
    rejoin = join.any(1, keepdim=True)
    if not held:  # every node let go: the pad at its place above the plate (solved)
        rejoin = rejoin & (P.amax(1, keepdim=True) > 0)
    p_join = torch.where(join, g / -diag, P)
    if held:
        p_join = p_join * (total / p_join.sum(1, keepdim=True))
    go = ~nodir
    conv = (go & (change < tol)) | (nodir & ~rejoin)
    P = torch.where(go, v, torch.where(rejoin, p_join, P))
    T = torch.where(go, t, 0.0)
    delta = (go & ~joined).to(dtype)
    stale = (go & moved) | (nodir & rejoin)
    return P, u, T, delta, stale, conv, go, change, scale


def product(x, khat, shape: tuple[int, int, int, int]):
    """``C x`` of each row of ``x`` (b, ny * nx) by the padded FFTs of
    :meth:`~.spectral.Spectral.apply` (``shape``: ``(ny, nx, Ly, Lx)``, the lattice and the
    padded transform; ``khat`` the kernel's transform, (Ly, Lx // 2 + 1))."""
    ny, nx, Ly, Lx = shape
    b = x.shape[0]
    a = torch.fft.rfft(x.view(b, ny, nx), n=Lx, dim=2)
    a = torch.fft.fft(a, n=Ly, dim=1)
    a *= khat
    a = torch.fft.ifft(a, dim=1)[:, :ny]
    return torch.fft.irfft(a, n=Lx, dim=2)[:, :, :nx].reshape(b, ny * nx)
