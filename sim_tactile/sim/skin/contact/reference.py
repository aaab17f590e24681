"""The plain solutions of the skin's contact problem: the Winkler bed (free and held at a
force) and the half-space problem by a straightforward active-set loop. The fast paths
(:class:`.active_set.ActiveSet`, the held step) are tested against these."""

from __future__ import annotations

import numpy as np

from ....errors import PhysicsError

#: Complementarity tolerance relative to the largest penetration.
TOL_REL = 1e-9
#: Most iterations of an active-set solve.
MAX_ITER = 100


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
    tol = TOL_REL * float(pen_m[cand].max())
    S = cand if active is None else cand[active[cand]]
    if S.size == 0:
        S = cand
    for _ in range(MAX_ITER):
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
        f"half-space contact solve did not converge in {MAX_ITER} iterations ({cand.size} nodes)"
    )
