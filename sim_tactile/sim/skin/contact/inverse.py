"""The contact set's inverse ``inv(C_SS)`` kept across changes of the set S (numba): built
from C or from the inverse of the whole compliance, moved by block updates as nodes leave or
join, and checked for drift as each update writes it. The active-set loops of
:mod:`.kernels` use it."""

from __future__ import annotations

import numpy as np

from ...._jit import njit

#: No inverse of the whole compliance at hand (:func:`inverse_subset`'s ``K``).
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
    running_sums(C, S, S, cu, 0.0)


@njit
def running_sums(C, rows, cols, cu, sign):
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
def rebuilt(C, K, S, sym, cu):
    """inv(C[S, S]) afresh (:func:`inverse_subset`), and the running sums with it."""
    if cu.shape[0]:
        set_sums(C, S, cu)
    return inverse_subset(C, K, S, sym)


@njit
def checked(M, C, K, S, sym, updates, rebuilds, cu, off):
    """After a block update: M rebuilt from C (S sorted) if it has drifted (``off``: the
    update's own drift check, :func:`_row_off` of each row)."""
    if off:
        S = np.sort(S)
        return rebuilt(C, K, S, sym, cu), S, 0, rebuilds + 1
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
