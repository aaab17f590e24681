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

import numpy as np

from ..errors import PhysicsError

#: Complementarity tolerance relative to the largest penetration.
_TOL_REL = 1e-9
_MAX_ITER = 100


def winkler(pen_m: np.ndarray, k_pa_per_m: float) -> np.ndarray:
    """Pressure [Pa] of a Winkler foundation: ``k * max(pen, 0)``."""
    return k_pa_per_m * np.maximum(pen_m, 0.0)


class FactorCache:
    """Cholesky factors of recent contact sets. While the pad slides, its contact set changes
    only when a node crosses a feature's edge (every few steps), so most steps reuse a factor
    and cost O(n^2) instead of O(n^3)."""

    def __init__(self, size: int = 8):
        self.size = size
        self._d: dict[tuple[str, bytes], tuple] = {}
        self.hits = 0
        self.misses = 0

    def factor(self, kind: str, idx: np.ndarray, M: np.ndarray):
        from scipy.linalg import cho_factor

        key = (kind, idx.tobytes())
        f = self._d.pop(key, None)
        if f is None:
            self.misses += 1
            f = cho_factor(M[np.ix_(idx, idx)], check_finite=False)
            if len(self._d) >= self.size:
                self._d.pop(next(iter(self._d)))
        else:
            self.hits += 1
        self._d[key] = f  # most recently used last
        return f


def _solve_subset(
    C: np.ndarray,
    K: np.ndarray | None,
    S: np.ndarray,
    rhs: np.ndarray,
    cache: FactorCache | None = None,
) -> np.ndarray:
    """Solve C[S, S] x = rhs. With K = inv(C), a large S is solved through its small
    complement T instead: inv(C_SS) = K_SS - K_ST inv(K_TT) K_TS (a Schur complement), so the
    cost is min(|S|, |T|)^3 rather than |S|^3. ``cache`` reuses factors of recent sets."""
    from scipy.linalg import cho_solve

    n = C.shape[0]
    if K is None or 2 * S.size <= n:
        if cache is None:
            return np.linalg.solve(C[np.ix_(S, S)], rhs)
        return cho_solve(cache.factor("S", S, C), rhs, check_finite=False)
    mask = np.ones(n, bool)
    mask[S] = False
    T = np.flatnonzero(mask)
    x = K[np.ix_(S, S)] @ rhs
    if T.size:
        y = K[np.ix_(T, S)] @ rhs
        if cache is None:
            z = np.linalg.solve(K[np.ix_(T, T)], y)
        else:
            z = cho_solve(cache.factor("T", T, K), y, check_finite=False)
        x -= K[np.ix_(S, T)] @ z
    return x


def halfspace(
    pen_m: np.ndarray,
    C: np.ndarray,
    active: np.ndarray | None = None,
    K: np.ndarray | None = None,
    cache: FactorCache | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Exact half-space contact pressures [Pa] for node penetrations ``pen_m`` (N,).

    ``C`` (N, N) compliance [m/Pa]; ``active`` an optional boolean warm start (the previous
    step's contact set); ``K`` optionally ``inv(C)``, which makes large contact sets cheap; ``cache`` a
    :class:`FactorCache` bound to this ``C``. Returns ``(p, active)``. Raises PhysicsError if
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
        pS = _solve_subset(C, K, S, pen_m[S], cache)
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
