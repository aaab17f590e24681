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
        x -= K[np.ix_(S, T)] @ np.linalg.solve(K[np.ix_(T, T)], K[np.ix_(T, S)] @ rhs)
    return x


def halfspace(
    pen_m: np.ndarray, C: np.ndarray, active: np.ndarray | None = None, K: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Exact half-space contact pressures [Pa] for node penetrations ``pen_m`` (N,).

    ``C`` (N, N) compliance [m/Pa]; ``active`` an optional boolean warm start (the previous
    step's contact set); ``K`` optionally ``inv(C)``, which makes large contact sets cheap. Returns ``(p, active)``. Raises PhysicsError if the active set does
    not converge (it always does for a positive definite C; the check guards bad input).
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
