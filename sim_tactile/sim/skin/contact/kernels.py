"""Compiled kernels of :class:`~.active_set.ActiveSet` (numba): the same-set checks, the
active-set loop with block updates of the inverse, and the force-holding loop. The held step
(:mod:`sim_tactile.sim.step.held`) calls them from its own compiled step."""

from __future__ import annotations

import numpy as np

from ...._jit import njit
from .inverse import check_vectors, checked, inverse_with, inverse_without, rebuilt, running_sums

#: No product at hand (:func:`solve_loop`'s ``pS0``).
NO_P = np.zeros(0)


@njit
def same_set_product(M, S, pen, C, in_set, tol_rel, p, floor):
    """Whether the contact set S still solves the problem for ``pen``, and the product
    ``M pen_S`` it made (empty where it stopped before it: where the set does not hold,
    :func:`solve_loop` starts from it). If it holds, the pressures go to ``p``. Checks the
    three conditions :meth:`ActiveSet.solve` would: every node of S can touch and carries
    compression, and no other node that can touch is left inside the plate. ``floor``: the
    depth above which a node can touch (``ActiveSet.floor``)."""
    n = pen.shape[0]
    m = S.shape[0]
    big = 0.0
    for j in range(n):
        if pen[j] > big:
            big = pen[j]
    for k in range(m):
        if pen[S[k]] <= floor:
            return False, np.empty(0)
    tol = tol_rel * big
    pen_S = np.empty(m)
    for k in range(m):
        pen_S[k] = pen[S[k]]
    pS = M @ pen_S  # BLAS
    for i in range(m):
        if pS[i] < 0.0:
            return False, pS
    rows = np.empty(n, np.int64)
    cnt = 0
    for j in range(n):
        if pen[j] > floor and not in_set[j]:
            rows[cnt] = j
            cnt += 1
    rows = rows[:cnt]
    u = ordered_product(C, rows, S, pS)
    for r in range(cnt):
        if pen[rows[r]] - u[r] > tol:
            return False, pS
    spread(pS, S, p)
    return True, pS


@njit
def spread(pS, S, p):
    """The set's pressures ``pS`` written to its nodes ``S`` of ``p``, zero elsewhere: the
    answer of a set that holds (:func:`same_set_product`, :func:`force_same_set`,
    :func:`joint_loop`, the held step)."""
    for j in range(p.shape[0]):
        p[j] = 0.0
    for k in range(S.shape[0]):
        p[S[k]] = pS[k]


@njit
def ordered_product(X, rows, cols, v):
    """``X[rows][:, cols] @ v``, each row's sum over ``cols`` in their order, as a plain loop
    sums it (bit for bit), four rows at once: their chains of additions overlap instead of
    each waiting on the last. The same-set checks' displacements at the nodes outside the set
    (``C``, the set ``S``, its pressures), their largest cost; the held step's taxel loads."""
    m = cols.size
    nr = rows.size
    u = np.empty(nr)
    r = 0
    while r + 4 <= nr:
        a, b, c, d = rows[r], rows[r + 1], rows[r + 2], rows[r + 3]
        ua = 0.0
        ub = 0.0
        uc = 0.0
        ud = 0.0
        for k in range(m):
            col = cols[k]
            q = v[k]
            ua += X[a, col] * q
            ub += X[b, col] * q
            uc += X[c, col] * q
            ud += X[d, col] * q
        u[r] = ua
        u[r + 1] = ub
        u[r + 2] = uc
        u[r + 3] = ud
        r += 4
    for t in range(r, nr):
        j = rows[t]
        acc = 0.0
        for k in range(m):
            acc += X[j, cols[k]] * v[k]
        u[t] = acc
    return u


@njit
def _reset(C, K, S, sym, cu, in_set, rebuilds):
    """The set S (sorted) with its inverse rebuilt (:func:`~.inverse.rebuilt`; none for an
    empty set) and its count of updates restarted: ``(M, S, 0, rebuilds + 1)``."""
    S = np.sort(S)
    M = rebuilt(C, K, S, sym, cu) if S.size else np.zeros((0, 0))
    in_set[:] = False
    in_set[S] = True
    return M, S, 0, rebuilds + 1


@njit
def _leave(M, S, drop, in_set, C, K, sym, cu, updates, refresh, rebuilds):
    """The set S without the nodes ``drop`` marks (a mask over S), its inverse moved by a
    block update (:func:`~.inverse.inverse_without`), or rebuilt where the set empties or
    ``refresh`` updates have passed: ``(M, S, updates, rebuilds)``."""
    keep = ~drop
    if not keep.any() or updates >= refresh:
        return _reset(C, K, S[keep], sym, cu, in_set, rebuilds)
    if cu.shape[0]:
        running_sums(C, S[keep], S[drop], cu, -1.0)
    u = check_vectors(C, S[keep], cu)
    M, off = inverse_without(M, np.flatnonzero(keep), np.flatnonzero(drop), sym, S, u)
    in_set[S[drop]] = False
    S = S[keep]
    return checked(M, C, K, S, sym, updates + 1, rebuilds, cu, off)


@njit
def _join(M, S, A, in_set, C, K, sym, cu, updates, refresh, rebuilds):
    """The set S with the nodes A after it, its inverse moved by a block update
    (:func:`~.inverse.inverse_with`), or rebuilt where S is empty or ``refresh`` updates
    have passed: ``(M, S, updates, rebuilds)``."""
    if S.size == 0 or updates >= refresh:
        return _reset(C, K, np.concatenate((S, A)), sym, cu, in_set, rebuilds)
    T = np.concatenate((S, A))
    if cu.shape[0]:
        running_sums(C, S, A, cu, 1.0)  # the set's nodes gain A's columns
        running_sums(C, A, T, cu, 0.0)  # and A's own, afresh
    M, off = inverse_with(M, C, S, A, sym, check_vectors(C, T, cu))
    in_set[A] = True
    return checked(M, C, K, T, sym, updates + 1, rebuilds, cu, off)


@njit
def solve_loop(
    M, S, in_set, C, K, pen, tol_rel, updates, refresh, max_iter, p, floor, sym, cu, pS0
):
    """The active-set iteration of :meth:`ActiveSet.solve` from the current set: nodes that
    can no longer touch or carry tension leave, nodes left inside the plate join; the
    inverse ``M`` follows by block updates, rebuilt every ``refresh`` updates. A node can
    touch when its depth exceeds ``floor``: 0 where no load lifts the skin toward the plate
    (the half-space), -inf where one can (a layered skin), though the set starts from the
    nodes that overlap the plate. ``sym``: C is symmetric (the block updates use it); a
    compliance that is not (friction coupled in) takes the general formulas. ``cu``: the
    running sums of the drift check (:func:`~.inverse.set_sums`, kept in step with S; :data:`~.inverse.NO_SUMS`:
    none kept; passed, not defaulted: numba keeps no compiled kernel whose omitted argument
    defaults to an array, and would compile it again in every process). ``pS0``: the product
    ``M pen_S`` that a same-set check made of this M, S and ``pen`` (:func:`same_set_product`;
    :data:`NO_P`: none), the loop's first product while the set stands, not made again.
    Returns ``(converged, M, S, updates, rebuilds)`` and writes the pressures to ``p``."""
    n = pen.shape[0]
    rebuilds = 0
    for j in range(n):
        p[j] = 0.0
    touching = pen > floor
    overlap = pen > 0.0
    if not overlap.any():
        if S.size:
            M = np.zeros((0, 0))
            S = S[:0]
            updates = 0
            rebuilds += 1
            in_set[:] = False
        return True, M, S, updates, rebuilds
    big = 0.0
    for j in range(n):
        if overlap[j] and pen[j] > big:
            big = pen[j]
    tol = tol_rel * big
    first = S.size > 0 and pS0.shape[0] == S.size  # the check's product, while S stands
    for it in range(max_iter + 2):
        if it == 0:  # nodes that no longer touch leave
            drop = np.empty(S.size, np.bool_)
            for k in range(S.size):
                drop[k] = not touching[S[k]]
        elif S.size == 0:  # start from every node that overlaps the plate
            drop = np.zeros(0, np.bool_)
        else:
            if it == 1 and first:
                pS = pS0
            else:
                pS = M @ np.ascontiguousarray(pen[S])
            drop = pS < 0.0
        if drop.any():
            first = False
            M, S, updates, rebuilds = _leave(
                M, S, drop, in_set, C, K, sym, cu, updates, refresh, rebuilds
            )
            if S.size == 0 and it > 0:
                return True, M, S, updates, rebuilds  # everything left: no load
            continue
        if it == 0:
            continue
        if S.size == 0:
            A = np.flatnonzero(overlap)
        else:
            rest = np.flatnonzero(touching & ~in_set)
            u = ordered_product(C, rest, S, pS)
            cnt = 0
            A = np.empty(rest.size, np.int64)
            for r in range(rest.size):
                j = rest[r]
                if pen[j] - u[r] > tol:
                    A[cnt] = j
                    cnt += 1
            A = A[:cnt]
        if A.size:  # nodes still inside the plate join the set
            M, S, updates, rebuilds = _join(
                M, S, A, in_set, C, K, sym, cu, updates, refresh, rebuilds
            )
            continue
        for k in range(S.size):
            p[S[k]] = pS[k]
        return True, M, S, updates, rebuilds
    return False, M, S, updates, rebuilds


@njit
def force_loop(
    M,
    S,
    in_set,
    C,
    K,
    pen,
    tol_rel,
    total,
    updates,
    refresh,
    max_iter,
    p,
    try_same,
    floor,
    sym,
    cu,
):
    """:meth:`ActiveSet.solve_force` in one call (``cu``: as :func:`solve_loop` takes it).
    Returns ``(status, dz, M, S, updates, rebuilds)``: status 1 converged (pressures in
    ``p``), 0 not converged, 2 no node within the margin."""
    n = pen.shape[0]
    rebuilds = 0
    if try_same and S.size:  # the common case: the set holds at the shift it implies
        d = force_same_set(M, S, pen, C, in_set, tol_rel, total, p, M @ np.ones(S.size), floor)
        if d == d:
            return 1, d, M, S, updates, rebuilds
    top = -np.inf
    for j in range(n):
        if pen[j] > top:
            top = pen[j]
    if top == -np.inf:
        return 2, 0.0, M, S, updates, rebuilds
    dz = 0.0
    shifted = np.empty(n)
    # the total is continuous and increasing in dz (on each contact set its slope is
    # 1' inv(C_SS) 1 > 0); where C is not of the half-space's kind (a layered skin, whose
    # surface lifts around a load) it need not be convex, and the Newton shift can jump
    # between two sets: a bracket [lo, hi] of shifts below and above the target catches that
    # and bisects
    lo, hi = -np.inf, np.inf
    for _ in range(max_iter):
        finite = S.size > 0
        for k in range(S.size):
            if not np.isfinite(pen[S[k]]):
                finite = False
        if finite:  # else the solve below updates the set first
            kk = (M @ np.ones(S.size)).sum()  # BLAS: a plain sum over M is sequential
            if kk > 0:
                dz = (total - (M @ np.ascontiguousarray(pen[S])).sum()) / kk
        if not (lo < dz < hi) and np.isfinite(lo) and np.isfinite(hi):
            dz = 0.5 * (lo + hi)
        for sink in range(2):
            for j in range(n):
                shifted[j] = pen[j] + dz
            held, pS0 = False, np.empty(0)
            if S.size:
                held, pS0 = same_set_product(M, S, shifted, C, in_set, tol_rel, p, floor)
            if not held:
                ok, M, S, updates, rb = solve_loop(
                    M,
                    S,
                    in_set,
                    C,
                    K,
                    shifted,
                    tol_rel,
                    updates,
                    refresh,
                    max_iter,
                    p,
                    floor,
                    sym,
                    cu,
                    pS0,
                )
                rebuilds += rb
                if not ok:
                    return 0, dz, M, S, updates, rebuilds
            got = p.sum()
            if abs(got - total) <= 1e-9 * total:
                return 1, dz, M, S, updates, rebuilds
            if S.size:
                if got < total:
                    lo = max(lo, dz)
                else:
                    hi = min(hi, dz)
            if S.size or sink:
                break
            # nothing touches at this shift: sink to the first touch and solve there
            dz = -top
            dz += 1e-9 * max(abs(dz), 1e-6)
    return 0, dz, M, S, updates, rebuilds


@njit
def force_same_set(M, S, pen, C, in_set, tol_rel, total, p, b, floor=0.0) -> float:
    """:meth:`ActiveSet.solve_force` on the set S alone: the shift ``dz`` at which the set's
    pressures sum to ``total``, and the pressures (into ``p``) if S still solves the contact
    problem at ``pen + dz`` (the checks of :func:`same_set_product`); NaN if it does not. ``b``:
    the row sums of M."""
    dz, pS, drop, A = set_trial(M, S, pen, C, in_set, tol_rel, total, b, floor)
    if dz != dz or drop.any() or A.size:
        return np.nan
    spread(pS, S, p)
    return dz


@njit
def set_trial(M, S, pen, C, in_set, tol_rel, total, b, floor):
    """The set S tried at the shift it implies (``b = M 1``): ``(dz, pS, drop, A)``, the shift
    (:func:`set_shift`; NaN where it has none), the set's pressures there, the nodes of S
    that must leave (tension, or no longer within reach of the plate) and, where none must,
    the nodes outside it that the shifted plate still presses into (:func:`pressed_in`),
    else none. S solves the problem at ``pen + dz`` where dz is a number, nothing drops and
    A is empty. :func:`force_same_set` and each pass of :func:`joint_loop`."""
    m = S.shape[0]
    dz, a, pen_S = set_shift(M, S, pen, total, b)
    pS = np.empty(m)
    drop = np.zeros(m, np.bool_)
    if dz != dz:
        return dz, pS, drop, np.empty(0, np.int64)
    dropped = False
    for i in range(m):
        pS[i] = a[i] + dz * b[i]
        drop[i] = pS[i] < 0.0 or pen_S[i] + dz <= floor
        dropped = dropped or drop[i]
    if dropped:
        return dz, pS, drop, np.empty(0, np.int64)
    return dz, pS, drop, pressed_in(C, S, in_set, pen, dz, pS, floor, tol_rel)


@njit
def set_shift(M, S, pen, total, b):
    """``(dz, a, pen_S)``: the shift ``dz`` at which the set's pressures ``M (pen_S + dz)``
    sum to ``total`` (``b = M 1``), with ``a = M pen_S`` and the set's depths ``pen_S``; dz is
    NaN where a node of S is out of reach (its depth not finite) or ``b`` sums to no
    stiffness."""
    m = S.shape[0]
    pen_S = np.empty(m)
    for i in range(m):
        if not np.isfinite(pen[S[i]]):
            return np.nan, pen_S, pen_S
        pen_S[i] = pen[S[i]]
    a = M @ pen_S  # BLAS
    ra = 0.0
    rb = 0.0
    for i in range(m):
        ra += a[i]
        rb += b[i]
    if not rb > 0.0:
        return np.nan, a, pen_S
    return (total - ra) / rb, a, pen_S


@njit
def pressed_in(C, S, in_set, pen, dz, pS, floor, tol_rel):
    """The nodes outside the set S that the plate, shifted by ``dz``, still presses into
    beyond the tolerance (``tol_rel`` of the deepest shifted depth) under the set's
    pressures ``pS``: the nodes that must join it (:func:`force_same_set`,
    :func:`joint_loop`)."""
    n = pen.shape[0]
    big = 0.0
    for j in range(n):
        if pen[j] + dz > big:
            big = pen[j] + dz
    tol = tol_rel * big
    rows = np.empty(n, np.int64)
    cnt = 0
    for j in range(n):
        if pen[j] + dz > floor and not in_set[j]:
            rows[cnt] = j
            cnt += 1
    rows = rows[:cnt]
    u = ordered_product(C, rows, S, pS)
    A = np.empty(cnt, np.int64)
    na = 0
    for r in range(cnt):
        if pen[rows[r]] + dz - u[r] > tol:
            A[na] = rows[r]
            na += 1
    return A[:na]


#: No trial at hand (:func:`joint_loop`'s ``tried``).
NOT_TRIED = (np.zeros(0), np.nan, np.zeros(0), np.zeros(0, np.bool_), np.zeros(0, np.int64))


@njit
def joint_loop(
    M, S, in_set, C, K, pen, tol_rel, total, updates, refresh, max_iter, p, floor, sym, cu, tried
):
    """:meth:`ActiveSet.solve_force` from a set S that does not hold, with the set and the
    shift solved together: on each set, the shift ``dz`` at which its pressures sum to
    ``total`` (exact on a fixed set, as :func:`force_same_set` finds it), then the nodes that
    carry tension or can no longer touch leave, else the nodes the shifted plate still
    presses into join, until neither happens. The same discrete problem as
    :func:`force_loop`, whose Newton iteration solves the set to convergence at each trial
    shift: those trial sets are never built here, so a step whose set changes by a few nodes
    takes fewer block updates of the inverse (on multilayer3-v1's hemispheres, 1.1-1.15x the
    held solves' speed, the pressures equal to 3e-13 of the largest). ``tried``: ``(b, dz,
    pS, drop, A)``, the row sums ``M 1`` and :func:`set_trial` of this M, S, ``pen`` and
    ``total`` where the caller has tried the set (its first pass, not made again), else
    :data:`NOT_TRIED`. Returns ``(status, dz, M, S, updates, rebuilds, b)`` with the
    pressures in ``p`` and ``b = M 1`` of the M returned where it converged (else empty):
    status 1 converged, 0 not (an empty set, a node of S out of reach, no convergence within
    ``max_iter`` set changes; the state returned is valid, for :func:`force_loop` to go on
    from)."""
    rebuilds = 0
    for it in range(max_iter):
        m = S.size
        if m == 0:
            return 0, 0.0, M, S, updates, rebuilds, np.empty(0)
        if it == 0 and tried[0].shape[0] == m:
            b = tried[0]
            dz, pS, drop, A = tried[1], tried[2], tried[3], tried[4]
        else:
            b = M @ np.ones(m)  # BLAS
            dz, pS, drop, A = set_trial(M, S, pen, C, in_set, tol_rel, total, b, floor)
        if dz != dz:
            return 0, 0.0, M, S, updates, rebuilds, np.empty(0)
        if drop.any():
            if drop.all():
                return 0, dz, M, S, updates, rebuilds, np.empty(0)
            M, S, updates, rebuilds = _leave(
                M, S, drop, in_set, C, K, sym, cu, updates, refresh, rebuilds
            )
            continue
        if A.size:
            M, S, updates, rebuilds = _join(
                M, S, A, in_set, C, K, sym, cu, updates, refresh, rebuilds
            )
            continue
        spread(pS, S, p)
        return 1, dz, M, S, updates, rebuilds, b
    return 0, 0.0, M, S, updates, rebuilds, np.empty(0)
