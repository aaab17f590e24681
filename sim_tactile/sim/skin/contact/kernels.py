"""Compiled kernels of :class:`~.active_set.ActiveSet` (numba): the same-set checks, the
active-set loop with block updates of the inverse, and the force-holding loop. The held step
(:mod:`sim_tactile.sim.step.held`) calls them from its own compiled step."""

from __future__ import annotations

import numpy as np

from ...._jit import njit

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
    for j in range(n):
        p[j] = 0.0
    for k in range(m):
        p[S[k]] = pS[k]
    return True, pS


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


NO_K = np.zeros((0, 0))


@njit
def take(X, rows, cols):
    """X[rows][:, cols] as a new C-contiguous array."""
    out = np.empty((rows.size, cols.size))
    for i in range(rows.size):
        for j in range(cols.size):
            out[i, j] = X[rows[i], cols[j]]
    return out


#: Largest residual |M C_SS v - v| (v: ones, and each node's sign: + for even nodes, - for
#: odd) that a block-updated inverse may carry before it is rebuilt from C. The updates can
#: amplify round-off geometrically: on finger7's ridges at 0.25 x 2 mm nodes it grew about
#: 1.6x per update, to 5e-3 within the 100 updates of REFRESH (taxel loads 3% off, mirror
#: taxels unequal); at 0.5 x 2 mm it stayed below 1e-12. Checked after every update.
DRIFT_TOL = 1e-9
#: The running sums of an :class:`~.active_set.ActiveSet` where none are kept (a caller that
#: renumbers its set): the drift check then sums ``C_SS v`` afresh.
NO_SUMS = np.zeros((0, 2))


@njit
def _sign(node) -> float:
    """The drift check's second vector at ``node``: + for even nodes, - for odd ones (a
    node's own, whatever its place in the set, so that the sums follow the set's changes)."""
    return 1.0 if node % 2 == 0 else -1.0


@njit
def set_sums(C, S, cu):
    """``cu[j] = ((C_SS 1)_j, (C_SS s)_j)`` for every node j of S, afresh (s: :func:`_sign`)."""
    _sums(C, S, S, cu, 0.0)


@njit
def _sums(C, rows, cols, cu, sign):
    """The running sums of the nodes ``rows`` over the columns ``cols`` (T): set to
    ``((C_jT 1), (C_jT s))`` afresh (``sign`` 0), or moved by those columns joining (1) or
    leaving (-1) the set, O(|rows| |cols|)."""
    for i in range(rows.size):
        row = rows[i]
        a = 0.0
        b = 0.0
        for k in range(cols.size):
            c = C[row, cols[k]]
            a += c
            b += _sign(cols[k]) * c
        if sign == 0.0:
            cu[row, 0] = a
            cu[row, 1] = b
        else:
            cu[row, 0] += sign * a
            cu[row, 1] += sign * b


@njit
def check_vectors(C, T, cu):
    """The drift check's vectors for the set ``T`` (in M's order): ``(C_TT 1, C_TT s)``, read
    from the running sums ``cu`` where they are kept, else summed afresh (s: :func:`_sign`)."""
    m = T.size
    if cu.shape[0] == 0:
        own = np.empty((C.shape[0], 2))
        set_sums(C, T, own)
        cu = own
    u = np.empty((2, m))
    for i in range(m):
        u[0, i] = cu[T[i], 0]
        u[1, i] = cu[T[i], 1]
    return u


@njit(fastmath={"reassoc"})
def _row_off(row, u, sign, tol) -> bool:
    """Whether one row of M fails the drift check: ``|row . u_0 - 1|`` or ``|row . u_1 -
    sign|`` above ``tol``. The sums may be reordered (``reassoc``: vectorised): a check against
    a tolerance far above round-off, not a value kept."""
    a = 0.0
    b = 0.0
    for j in range(row.size):
        a += row[j] * u[0, j]
        b += row[j] * u[1, j]
    return abs(a - 1.0) > tol or abs(b - sign) > tol


@njit
def _rebuilt(C, K, S, sym, cu):
    """inv(C[S, S]) afresh (:func:`inverse_subset`), and the running sums with it."""
    if cu.shape[0]:
        set_sums(C, S, cu)
    return inverse_subset(C, K, S, sym)


@njit
def _checked(M, C, K, S, sym, updates, rebuilds, cu, off):
    """After a block update: M rebuilt from C (S sorted) if it has drifted (``off``: the
    update's own drift check, :func:`_row_off` of each row)."""
    if off:
        S = np.sort(S)
        return _rebuilt(C, K, S, sym, cu), S, 0, rebuilds + 1
    return M, S, updates, rebuilds


@njit
def inverse_subset(C, K, S, sym=True):
    """inv(C[S, S]); a large S goes through its small complement T with K = inv(C):
    inv(C_SS) = K_SS - K_ST inv(K_TT) K_TS. ``K`` of shape (0, 0) stands for no inverse.
    ``sym``: C (and K) symmetric, K_TS taken as K_ST's transpose; else read as it is."""
    n = C.shape[0]
    m = S.size
    if K.shape[0] == 0 or 2 * m <= n:
        return np.ascontiguousarray(np.linalg.inv(take(C, S, S)))
    mask = np.ones(n, np.bool_)
    for i in range(m):
        mask[S[i]] = False
    T = np.flatnonzero(mask)
    t = T.size
    KSS = take(K, S, S)
    if t == 0:
        return KSS
    KST = take(K, S, T)
    KTT = take(K, T, T)
    KTS = np.ascontiguousarray(KST.T) if sym else take(K, T, S)
    return np.ascontiguousarray(KSS - KST @ np.linalg.solve(KTT, KTS))


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
    running sums of the drift check (:func:`set_sums`, kept in step with S; :data:`NO_SUMS`:
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
            keep = ~drop
            if not keep.any() or updates >= refresh:
                S = np.sort(S[keep])
                M = _rebuilt(C, K, S, sym, cu) if S.size else np.zeros((0, 0))
                updates = 0
                rebuilds += 1
                in_set[:] = False
                in_set[S] = True
            else:
                if cu.shape[0]:
                    _sums(C, S[keep], S[drop], cu, -1.0)
                u = check_vectors(C, S[keep], cu)
                M, off = inverse_without(M, np.flatnonzero(keep), np.flatnonzero(drop), sym, S, u)
                in_set[S[drop]] = False
                S = S[keep]
                M, S, updates, rebuilds = _checked(M, C, K, S, sym, updates + 1, rebuilds, cu, off)
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
            if S.size == 0 or updates >= refresh:
                S = np.sort(np.concatenate((S, A)))
                M = _rebuilt(C, K, S, sym, cu)
                updates = 0
                rebuilds += 1
                in_set[:] = False
                in_set[S] = True
            else:
                T = np.concatenate((S, A))
                if cu.shape[0]:
                    _sums(C, S, A, cu, 1.0)  # the set's nodes gain A's columns
                    _sums(C, A, T, cu, 0.0)  # and A's own, afresh
                M, off = inverse_with(M, C, S, A, sym, check_vectors(C, T, cu))
                S = T
                in_set[A] = True
                M, S, updates, rebuilds = _checked(M, C, K, S, sym, updates + 1, rebuilds, cu, off)
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
    n = pen.shape[0]
    m = S.shape[0]
    pen_S = np.empty(m)
    for i in range(m):
        if not np.isfinite(pen[S[i]]):
            return np.nan
        pen_S[i] = pen[S[i]]
    a = M @ pen_S  # M pen_S (BLAS); b = M 1
    ra = 0.0
    rb = 0.0
    for i in range(m):
        ra += a[i]
        rb += b[i]
    if not rb > 0.0:
        return np.nan
    dz = (total - ra) / rb
    big = 0.0
    for j in range(n):
        if pen[j] + dz > big:
            big = pen[j] + dz
    for k in range(m):
        if pen[S[k]] + dz <= floor:
            return np.nan
    pS = np.empty(m)
    for i in range(m):
        pS[i] = a[i] + dz * b[i]
        if pS[i] < 0.0:
            return np.nan
    tol = tol_rel * big
    rows = np.empty(n, np.int64)
    cnt = 0
    for j in range(n):
        if pen[j] + dz > floor and not in_set[j]:
            rows[cnt] = j
            cnt += 1
    rows = rows[:cnt]
    u = ordered_product(C, rows, S, pS)
    for r in range(cnt):
        if pen[rows[r]] + dz - u[r] > tol:
            return np.nan
    for j in range(n):
        p[j] = 0.0
    for k in range(m):
        p[S[k]] = pS[k]
    return dz


@njit
def inverse_without(M, keep, drop, sym, S, u):
    """inv(C_KK) from M = inv(C_SS), S = K + R: the Schur complement M_KK - M_KR inv(M_RR) M_RK
    (``sym``: M_RK taken as M_KR's transpose). Returns it and whether it has drifted from
    the inverse: M C_KK v against v, for the vectors ``u = C_KK v`` of the set ``S[keep]``
    (:func:`check_vectors`), checked row by row as it is written (:func:`_row_off`)."""
    Mkr = take(M, keep, drop)
    Mrr = take(M, drop, drop)
    Mrk = np.ascontiguousarray(Mkr.T) if sym else take(M, drop, keep)
    X = np.linalg.solve(Mrr, Mrk)
    P = Mkr @ X
    k = keep.size
    out = np.empty((k, k))
    off = False
    for i in range(k):  # M[keep][:, keep] - P, read where it lies, as the expression computes it
        row = keep[i]
        for j in range(k):
            out[i, j] = M[row, keep[j]] - P[i, j]
        if not off:
            off = _row_off(out[i], u, _sign(S[row]), DRIFT_TOL)
    return out, off


@njit
def inverse_with(M, C, S, A, sym, u):
    """inv(C_TT) for T = S + A from M = inv(C_SS), through the Schur complement of C_SS:
    Z = C_AA - C_AS M C_SA, inv = [[M + M C_SA Z^-1 C_AS M, -M C_SA Z^-1],
    [-Z^-1 C_AS M, Z^-1]]; ``sym``: C_AS = C_SA' and M symmetric, which the symmetric
    formulas use. Returns it and whether it fails the drift check against the vectors ``u``
    of T (:func:`inverse_without`), checked row by row as it is written."""
    n, a = S.size, A.size
    B = take(C, S, A)
    D = take(C, A, A)
    MB = M @ B
    if sym:
        Zi = np.linalg.inv(D - np.ascontiguousarray(B.T) @ MB)
        G = MB @ Zi
        H = G @ np.ascontiguousarray(MB.T)
        L = G.T  # the lower-left block is -G'
    else:
        E = take(C, A, S) @ M  # C_AS M
        Zi = np.linalg.inv(D - E @ B)
        G = MB @ Zi
        H = G @ E
        L = Zi @ E
    out = np.empty((n + a, n + a))
    off = False
    for i in range(n):
        for j in range(n):
            out[i, j] = M[i, j] + H[i, j]
        for j in range(a):
            out[i, n + j] = -G[i, j]
        if not off:
            off = _row_off(out[i], u, _sign(S[i]), DRIFT_TOL)
    for i in range(a):
        for j in range(n):
            out[n + i, j] = -L[i, j]
        for j in range(a):
            out[n + i, n + j] = Zi[i, j]
        if not off:
            off = _row_off(out[n + i], u, _sign(A[i]), DRIFT_TOL)
    return out, off
