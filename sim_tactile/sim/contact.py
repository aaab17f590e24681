"""Quasi-static skin contact: from the penetration-depth map of the undeformed pad to the
pressure on each skin node.

- :func:`winkler`: local elastic foundation, ``p = k_w * pen`` (no coupling).
- :func:`halfspace`: elastic half-space contact, the linear complementarity problem
  ``p >= 0, C p >= pen, p (C p - pen) = 0`` solved exactly by an active-set method (the
  deflection of the surface, ``u = C p``, must lift every penetrating node out of the plate;
  nodes whose deflection would lift them further carry no load). ``C`` is the dense
  compliance of :func:`sim_tactile.scene.elastic.compliance_matrix`: the elastic coupling.

Only nodes that penetrate (pen > 0) can carry load: u = C p >= 0 everywhere, so a node that
does not touch the undeformed pad cannot be pushed into the plate by its neighbours.
"""

from __future__ import annotations

import numba
import numpy as np

from ..errors import PhysicsError

#: Complementarity tolerance relative to the largest penetration.
_TOL_REL = 1e-9
_MAX_ITER = 100


def winkler(pen_m: np.ndarray, k_pa_per_m: float) -> np.ndarray:
    """Pressure [Pa] of a Winkler foundation: ``k * max(pen, 0)``."""
    return k_pa_per_m * np.maximum(pen_m, 0.0)


def winkler_force(
    pen_m: np.ndarray, k_pa_per_m: float, total_pa: float
) -> tuple[np.ndarray, float]:
    """The Winkler bed held at a given force: the downward shift ``dz`` [m] of the pad and
    the pressures [Pa] at it such that ``sum(p) = total_pa``, where ``p = k max(pen + dz,
    0)``. The sum is piecewise linear and increasing in ``dz``: the nodes are taken deepest
    first until the shift that carries the total lies within the last node's segment."""
    if not total_pa > 0:
        raise PhysicsError(f"winkler_force needs a positive total pressure, got {total_pa!r}")
    finite = np.isfinite(pen_m)
    if not finite.any():
        raise PhysicsError("no skin node lies within the collider's margin of the plate")
    d = np.sort(pen_m[finite])[::-1]  # deepest first
    need = total_pa / k_pa_per_m  # sum of (pen + dz) over the touching nodes
    csum = np.cumsum(d)
    m = np.arange(1, d.size + 1)
    dz_m = (need - csum) / m  # the shift if exactly the m deepest nodes touch
    # the first m whose shift keeps the (m+1)-th node out of contact
    nxt = np.append(d[1:], -np.inf)
    ok = dz_m + nxt <= 0
    j = int(np.argmax(ok))
    dz = float(dz_m[j])
    return k_pa_per_m * np.maximum(pen_m + dz, 0.0), dz


class ActiveSet:
    """The half-space contact problem of one compliance ``C``, solved step after step with the
    inverse of ``C`` on the contact set kept up to date.

    While the pad slides, its contact set changes by a few nodes when a node crosses a
    feature's edge. Instead of factorising ``C[S, S]`` anew for each set (O(|S|^3)), the
    inverse ``M = inv(C[S, S])`` is updated by block formulas (O(|S|^2) per changed node): a
    node leaves through the Schur complement of ``M``, a node joins through the Schur
    complement of ``C``. A step that keeps its set costs one matrix-vector product, and the
    pad's contact stiffness is ``sum(M)`` times the node area. ``M`` is recomputed from ``C``
    after ``refresh`` updates (a block of nodes joining or leaving is one), which bounds
    round-off drift; the schedule is deterministic, so equal inputs give bit-identical
    outputs. Same answer as :func:`halfspace` (tested).
    """

    def __init__(self, C: np.ndarray, K: np.ndarray | None = None, refresh: int = 100):
        self.C, self.K, self.refresh = C, K, refresh
        self.S = np.zeros(0, dtype=np.int64)  # contact set, in the order of M's rows
        self.M = np.zeros((0, 0))
        self.updates = 0
        self.rebuilds = 0
        self._in = np.zeros(C.shape[0], bool)
        self._rowsum, self._rowsum_of = np.zeros(0), None

    # -- the contact problem
    def solve(self, pen_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pressures [Pa] for node penetrations ``pen_m``, warm-started from the last set.
        Returns ``(p, active)`` as :func:`halfspace` does."""
        p = np.empty_like(pen_m)
        if self.S.size and _kkt_same_set(self.M, self.S, pen_m, self.C, self._in, _TOL_REL, p):
            return p, self._in.copy()  # the common case: the set holds, one product
        K = self.K if self.K is not None else _NO_K
        status, M, S, updates, rebuilds = _solve_loop(
            self.M,
            self.S,
            self._in,
            self.C,
            K,
            pen_m,
            _TOL_REL,
            self.updates,
            self.refresh,
            _MAX_ITER,
            p,
        )
        self.M, self.S, self.updates = M, S, updates
        self.rebuilds += rebuilds
        if status:
            return p, self._in.copy()
        raise PhysicsError(
            f"half-space contact solve did not converge in {_MAX_ITER} iterations "
            f"({int((pen_m > 0).sum())} nodes)"
        )

    def solve_force(
        self, pen_m: np.ndarray, total_pa: float, max_iter: int = _MAX_ITER
    ) -> tuple[np.ndarray, float]:
        """The pad held at a given normal force: the downward shift ``dz`` [m] of the pad
        and the pressures [Pa] at it, such that ``sum(p) = total_pa`` (the force over the
        node area). Moving the pad down by ``dz`` deepens every node by ``dz`` (a negative
        ``dz`` lifts the pad): exact for depths measured to a horizontal face; a node
        against a feature's side wall is taken to clear it as the pad rises, so the pad
        climbs a step's edge instead of sticking to its wall.

        On a fixed contact set the total is linear in ``dz``, so each iteration solves it
        exactly on the current set, then re-solves the contact problem at that shift; the
        total is increasing and convex in ``dz`` (nodes join as the pad sinks), so this
        Newton iteration converges, in one pass whenever the set holds. Nodes at ``-inf``
        (no contact within the collider's margin) cannot join."""
        if not total_pa > 0:
            raise PhysicsError(f"solve_force needs a positive total pressure, got {total_pa!r}")
        p = np.empty_like(pen_m)
        if not (pen_m.flags.c_contiguous and pen_m.dtype == np.float64):
            pen_m = np.ascontiguousarray(pen_m, dtype=np.float64)
        if self.S.size:  # the common case, without the loop's call and return costs
            M, S, in_set, C, rowsum = self.same_set_state()
            dz = _force_same_set(M, S, pen_m, C, in_set, _TOL_REL, total_pa, p, rowsum)
            if dz == dz:
                return p, dz
        K = self.K if self.K is not None else _NO_K
        status, dz, M, S, updates, rebuilds = _force_loop(
            self.M,
            self.S,
            self._in,
            self.C,
            K,
            pen_m,
            _TOL_REL,
            float(total_pa),
            self.updates,
            self.refresh,
            max_iter,
            p,
            False,  # the same-set case was tried above
        )
        self.M, self.S, self.updates = M, S, updates
        self.rebuilds += rebuilds
        if status == 1:
            return p, dz
        if status == 2:
            raise PhysicsError("no skin node lies within the collider's margin of the plate")
        raise PhysicsError(
            f"the force-holding contact solve did not converge in {max_iter} iterations "
            f"(target {total_pa:.4g} Pa summed over the nodes)"
        )

    def same_set_state(self):
        """``(M, S, in_set, C, rowsum)``: what :func:`_force_same_set` needs to try the current
        set; ``rowsum = M 1`` is kept while ``M`` stands."""
        if self._rowsum_of is not self.M:
            self._rowsum, self._rowsum_of = self.M.sum(axis=1), self.M
        return self.M, self.S, self._in, self.C, self._rowsum

    def stiffness_per_area(self) -> float:
        """d(total pressure integral)/d(uniform indentation) on the current set [Pa/m]:
        ``1' inv(C_SS) 1``; times the node area it is the pad's contact stiffness."""
        return float(self.M.sum())


@numba.njit(cache=True)
def _kkt_same_set(M, S, pen, C, in_set, tol_rel, p) -> bool:
    """Whether the contact set S still solves the problem for ``pen``; if so, write the
    pressures to ``p``. Checks the three conditions :meth:`ActiveSet.solve` would: every node
    of S touches and carries compression, and no other touching node is left inside the plate."""
    n = pen.shape[0]
    m = S.shape[0]
    big = 0.0
    for j in range(n):
        if pen[j] > big:
            big = pen[j]
    for k in range(m):
        if pen[S[k]] <= 0.0:
            return False
    tol = tol_rel * big
    pen_S = np.empty(m)
    for k in range(m):
        pen_S[k] = pen[S[k]]
    pS = M @ pen_S  # BLAS
    for i in range(m):
        if pS[i] < 0.0:
            return False
    for j in range(n):
        if pen[j] > 0.0 and not in_set[j]:
            u = 0.0
            for k in range(m):
                u += C[j, S[k]] * pS[k]
            if pen[j] - u > tol:
                return False
    for j in range(n):
        p[j] = 0.0
    for k in range(m):
        p[S[k]] = pS[k]
    return True


_NO_K = np.zeros((0, 0))


@numba.njit(cache=True)
def _take(X, rows, cols):
    """X[rows][:, cols] as a new C-contiguous array."""
    out = np.empty((rows.size, cols.size))
    for i in range(rows.size):
        for j in range(cols.size):
            out[i, j] = X[rows[i], cols[j]]
    return out


@numba.njit(cache=True)
def _inverse_subset_nb(C, K, S):
    """inv(C[S, S]); a large S goes through its small complement T with K = inv(C):
    inv(C_SS) = K_SS - K_ST inv(K_TT) K_TS. ``K`` of shape (0, 0) stands for no inverse."""
    n = C.shape[0]
    m = S.size
    if K.shape[0] == 0 or 2 * m <= n:
        return np.ascontiguousarray(np.linalg.inv(_take(C, S, S)))
    mask = np.ones(n, np.bool_)
    for i in range(m):
        mask[S[i]] = False
    T = np.flatnonzero(mask)
    t = T.size
    KSS = _take(K, S, S)
    if t == 0:
        return KSS
    KST = _take(K, S, T)
    KTT = _take(K, T, T)
    return np.ascontiguousarray(KSS - KST @ np.linalg.solve(KTT, np.ascontiguousarray(KST.T)))


@numba.njit(cache=True)
def _solve_loop(M, S, in_set, C, K, pen, tol_rel, updates, refresh, max_iter, p):
    """The active-set iteration of :meth:`ActiveSet.solve` from the current set: nodes that
    stop touching or carry tension leave, touching nodes left inside the plate join; the
    inverse ``M`` follows by block updates, rebuilt every ``refresh`` updates. Returns
    ``(converged, M, S, updates, rebuilds)`` and writes the pressures to ``p``."""
    n = pen.shape[0]
    rebuilds = 0
    for j in range(n):
        p[j] = 0.0
    touching = pen > 0.0
    if not touching.any():
        if S.size:
            M = np.zeros((0, 0))
            S = S[:0]
            updates = 0
            rebuilds += 1
            in_set[:] = False
        return True, M, S, updates, rebuilds
    big = 0.0
    for j in range(n):
        if touching[j] and pen[j] > big:
            big = pen[j]
    tol = tol_rel * big
    for it in range(max_iter + 2):
        if it == 0:  # nodes that no longer touch leave
            drop = np.empty(S.size, np.bool_)
            for k in range(S.size):
                drop[k] = not touching[S[k]]
        elif S.size == 0:  # start from every touching node
            drop = np.zeros(0, np.bool_)
        else:
            pS = M @ np.ascontiguousarray(pen[S])
            drop = pS < 0.0
        if drop.any():
            keep = ~drop
            if not keep.any() or updates >= refresh:
                S = np.sort(S[keep])
                M = _inverse_subset_nb(C, K, S) if S.size else np.zeros((0, 0))
                updates = 0
                rebuilds += 1
                in_set[:] = False
                in_set[S] = True
            else:
                M = _inverse_without(M, np.flatnonzero(keep), np.flatnonzero(drop))
                in_set[S[drop]] = False
                S = S[keep]
                updates += 1
            if S.size == 0 and it > 0:
                return True, M, S, updates, rebuilds  # everything left: no load
            continue
        if it == 0:
            continue
        if S.size == 0:
            A = np.flatnonzero(touching)
        else:
            rest = np.flatnonzero(touching & ~in_set)
            m = S.size
            cnt = 0
            A = np.empty(rest.size, np.int64)
            for r in range(rest.size):
                j = rest[r]
                u = 0.0
                for k in range(m):
                    u += C[j, S[k]] * pS[k]
                if pen[j] - u > tol:
                    A[cnt] = j
                    cnt += 1
            A = A[:cnt]
        if A.size:  # nodes still inside the plate join the set
            if S.size == 0 or updates >= refresh:
                S = np.sort(np.concatenate((S, A)))
                M = _inverse_subset_nb(C, K, S)
                updates = 0
                rebuilds += 1
                in_set[:] = False
                in_set[S] = True
            else:
                M = _inverse_with(M, C, S, A)
                S = np.concatenate((S, A))
                in_set[A] = True
                updates += 1
            continue
        for k in range(S.size):
            p[S[k]] = pS[k]
        return True, M, S, updates, rebuilds
    return False, M, S, updates, rebuilds


@numba.njit(cache=True)
def _force_loop(
    M, S, in_set, C, K, pen, tol_rel, total, updates, refresh, max_iter, p, try_same=True
):
    """:meth:`ActiveSet.solve_force` in one call. Returns ``(status, dz, M, S, updates,
    rebuilds)``: status 1 converged (pressures in ``p``), 0 not converged, 2 no node within
    the margin."""
    n = pen.shape[0]
    rebuilds = 0
    if try_same and S.size:  # the common case: the set holds at the shift it implies
        d = _force_same_set(M, S, pen, C, in_set, tol_rel, total, p, M @ np.ones(S.size))
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
    for _ in range(max_iter):
        finite = S.size > 0
        for k in range(S.size):
            if not np.isfinite(pen[S[k]]):
                finite = False
        if finite:  # else the solve below updates the set first
            kk = (M @ np.ones(S.size)).sum()  # BLAS: a plain sum over M is sequential
            if kk > 0:
                dz = (total - (M @ np.ascontiguousarray(pen[S])).sum()) / kk
        for sink in range(2):
            for j in range(n):
                shifted[j] = pen[j] + dz
            if not (S.size and _kkt_same_set(M, S, shifted, C, in_set, tol_rel, p)):
                ok, M, S, updates, rb = _solve_loop(
                    M, S, in_set, C, K, shifted, tol_rel, updates, refresh, max_iter, p
                )
                rebuilds += rb
                if not ok:
                    return 0, dz, M, S, updates, rebuilds
            got = p.sum()
            if abs(got - total) <= 1e-9 * total:
                return 1, dz, M, S, updates, rebuilds
            if S.size or sink:
                break
            # nothing touches at this shift: sink to the first touch and solve there
            dz = -top
            dz += 1e-9 * max(abs(dz), 1e-6)
    return 0, dz, M, S, updates, rebuilds


@numba.njit(cache=True)
def _force_same_set(M, S, pen, C, in_set, tol_rel, total, p, b) -> float:
    """:meth:`ActiveSet.solve_force` on the set S alone: the shift ``dz`` at which the set's
    pressures sum to ``total``, and the pressures (into ``p``) if S still solves the contact
    problem at ``pen + dz`` (the checks of :func:`_kkt_same_set`); NaN if it does not. ``b``:
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
        if pen[S[k]] + dz <= 0.0:
            return np.nan
    pS = np.empty(m)
    for i in range(m):
        pS[i] = a[i] + dz * b[i]
        if pS[i] < 0.0:
            return np.nan
    tol = tol_rel * big
    for j in range(n):
        if pen[j] + dz > 0.0 and not in_set[j]:
            u = 0.0
            for k in range(m):
                u += C[j, S[k]] * pS[k]
            if pen[j] + dz - u > tol:
                return np.nan
    for j in range(n):
        p[j] = 0.0
    for k in range(m):
        p[S[k]] = pS[k]
    return dz


@numba.njit(cache=True)
def _inverse_without(M, keep, drop):
    """inv(C_KK) from M = inv(C_SS), S = K + R: the Schur complement M_KK - M_KR inv(M_RR) M_RK."""
    Mkr = _take(M, keep, drop)
    Mrr = _take(M, drop, drop)
    Mkk = _take(M, keep, keep)
    X = np.linalg.solve(Mrr, np.ascontiguousarray(Mkr.T))
    return Mkk - Mkr @ X


@numba.njit(cache=True)
def _inverse_with(M, C, S, A):
    """inv(C_TT) for T = S + A from M = inv(C_SS), through the Schur complement of C_SS:
    Z = C_AA - C_AS M C_SA, inv = [[M + M B Z^-1 B' M, -M B Z^-1], [-Z^-1 B' M, Z^-1]]."""
    n, a = S.size, A.size
    B = _take(C, S, A)
    D = _take(C, A, A)
    MB = M @ B
    Zi = np.linalg.inv(D - np.ascontiguousarray(B.T) @ MB)
    G = MB @ Zi
    out = np.empty((n + a, n + a))
    out[:n, :n] = M + G @ np.ascontiguousarray(MB.T)
    out[:n, n:] = -G
    out[n:, :n] = -G.T
    out[n:, n:] = Zi
    return out


def _solve_subset(
    C: np.ndarray, K: np.ndarray | None, S: np.ndarray, rhs: np.ndarray
) -> np.ndarray:
    """Solve C[S, S] x = rhs. With K = inv(C), a large S is solved through its small
    complement T instead: inv(C_SS) = K_SS - K_ST inv(K_TT) K_TS (a Schur complement), so the
    cost is min(|S|, |T|)^3 rather than |S|^3."""
    n = C.shape[0]
    if K is None or 2 * S.size <= n:
        return np.linalg.solve(C[np.ix_(S, S)], rhs)
    mask = np.ones(n, bool)
    mask[S] = False
    T = np.flatnonzero(mask)
    x = K[np.ix_(S, S)] @ rhs
    if T.size:
        y = K[np.ix_(T, S)] @ rhs
        x -= K[np.ix_(S, T)] @ np.linalg.solve(K[np.ix_(T, T)], y)
    return x


def halfspace(
    pen_m: np.ndarray,
    C: np.ndarray,
    active: np.ndarray | None = None,
    K: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Exact half-space contact pressures [Pa] for node penetrations ``pen_m`` (N,).

    ``C`` (N, N) compliance [m/Pa]; ``active`` an optional boolean warm start (the previous
    step's contact set); ``K`` optionally ``inv(C)``, which makes large contact sets cheap. Returns ``(p, active)``. Raises PhysicsError if
    the active set does not converge (it always does for a positive definite C; the check guards bad input).
    """
    cand = np.flatnonzero(pen_m > 0)
    p = np.zeros_like(pen_m)
    if cand.size == 0:
        return p, np.zeros(pen_m.shape, bool)
    tol = _TOL_REL * float(pen_m[cand].max())
    S = cand if active is None else cand[active[cand]]
    if S.size == 0:
        S = cand
    for _ in range(_MAX_ITER):
        pS = _solve_subset(C, K, S, pen_m[S])
        neg = pS < 0
        if neg.any():
            # drop the nodes pulled into tension, keep the rest, and solve again
            S = S[~neg]
            if S.size == 0:
                S = cand[:0]
                break
            continue
        in_s = np.zeros(pen_m.shape, bool)
        in_s[S] = True
        rest = cand[~in_s[cand]]
        if rest.size:
            gap = pen_m[rest] - C[np.ix_(rest, S)] @ pS
            add = rest[gap > tol]
            if add.size:
                S = np.sort(np.concatenate([S, add]))
                continue
        p[S] = pS
        return p, in_s
    if S.size == 0:
        return p, np.zeros(pen_m.shape, bool)
    raise PhysicsError(
        f"half-space contact solve did not converge in {_MAX_ITER} iterations ({cand.size} nodes)"
    )
