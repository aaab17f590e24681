"""The skin's part of one held-force step, in one numba call, on the smallest exact problem.

Under quasi-static force control with the primitive collider, a step is: the depth map at the
bone's position, the height at which the skin carries the commanded force (the force-holding
contact solve), and the taxel loads there. :class:`HeldSkin` does all of it in one compiled
call (:func:`_held_kernel`): the common case (the contact set holds, the pad moves less than
the collider's margin) and the rest (nodes join or leave: the active-set updates of
:mod:`.contact`; nothing near or a long move: re-collide at the new height), so no step pays
Python's per-call costs more than once. L0's Winkler bed takes the same path in closed form.

It also solves the smallest problem that gives the same answer:

- **columns** (:meth:`PrimitiveCollider.y_invariant`): when every plate geom is a box that
  runs past the whole pad in y (ridges across the slide), a node's depth does not depend on
  its y; the collider computes one node per distinct (x, z, radius, margin), the rest are
  copies (bit-identical);
- **mirror** halving: when, in addition, the node grid is symmetric about the pad's centre
  line (nodes at y and -y alike), the depth map, and so the unique contact solution, are
  symmetric. The solve then runs on the nodes with y >= 0 only. Its unknowns are the summed
  pressure of each mirror pair, ``f = p_a + p_a'`` (``p_a`` on the centre line), and its
  compliance ``C_f[a, b] = (C[a, b] + C[a, b']) / 2`` is symmetric positive definite
  (``V' C V`` for the pair-averaging ``V``). The total force is the plain sum of ``f``, so
  the force-holding solve is unchanged; the taxels read ``f`` through ``W_f[:, b] =
  (W[:, b] + W[:, b']) / 2``. Equal to the full solve to round-off (tested); the set
  updates, which dominate a sliding step, cost about a third.
"""

from __future__ import annotations

import numba
import numpy as np

from ..errors import ConfigError, PhysicsError
from . import contact
from .collide import PrimitiveCollider, _depths

#: Collision queries one step may take before it gives up (the pad falling through).
_QS_COLLISIONS = 50
#: Relative tolerance of the mirror-symmetry check of the compliance.
_SYM_RTOL = 1e-10


class HeldSkin:
    """Depths, force-holding solve and taxel readout of one scene under quasi-static force
    control with the primitive collider.

    ``pen`` and ``f`` live on the reduced nodes ``nodes`` (all nodes when no reduction
    applies, or ``reduce`` is False); ``f`` sums each mirror pair's pressures, so
    ``area * f.sum()`` is the normal force and ``W @ (area * f)`` the taxel loads."""

    def __init__(
        self,
        scene,
        collider: PrimitiveCollider,
        bone_y: float,
        margin: float,
        reduce: bool = True,
        winkler_k_pa_per_m: float | None = None,
    ):
        n = scene.n_nodes
        self.area = scene.grid.area_m2
        self.margin = margin
        nodes = np.arange(n)
        C, K, W = scene.C, scene.K, scene.W
        winkler = C is None
        if winkler and not (winkler_k_pa_per_m and winkler_k_pa_per_m > 0):
            raise ConfigError(
                f"winkler_k_pa_per_m = {winkler_k_pa_per_m!r}: a skin without coupling (L0) "
                "needs its Winkler stiffness; valid: > 0"
            )
        self.winkler_k = float(winkler_k_pa_per_m) if winkler else 0.0
        self.columns = reduce and collider.y_invariant(bone_y)
        self.mirrored = False
        mult = np.ones(n)
        if self.columns:
            mirror = _mirror_of(collider)
            if mirror is not None and (winkler or _mirror_symmetric(C, mirror)):
                self.mirrored = True
                nodes = np.flatnonzero(collider.local[:, 1] >= 0.0)
                pair = mirror[nodes]
                mult = np.where(pair != nodes, 2.0, 1.0)
                if not winkler:
                    Cf = 0.5 * (C[np.ix_(nodes, nodes)] + C[np.ix_(nodes, pair)])
                    C = np.ascontiguousarray(0.5 * (Cf + Cf.T))
                    K = np.ascontiguousarray(np.linalg.inv(C))
                W = 0.5 * (W[:, nodes] + W[:, pair])
        self.nodes = nodes
        self.n_full = n
        self.n = nodes.size
        self.mult = mult
        self.solver = None if winkler else contact.ActiveSet(C, K)
        self.W = np.ascontiguousarray(W, dtype=np.float64)
        sub = collider.subset(nodes)
        if self.columns:  # one probe per distinct (x, z, radius, margin)
            key = np.column_stack([sub.local[:, 0], sub.local[:, 2], sub.radius, sub.margin])
            _, first, group = np.unique(key, axis=0, return_index=True, return_inverse=True)
            sub = sub.subset(first)
            self.group = group.ravel().astype(np.int64)
        else:
            self.group = np.arange(self.n, dtype=np.int64)
        self.probe = sub
        self.n_probes = len(sub.radius)
        self.pen = np.empty(self.n)
        self.f = np.zeros(self.n)
        self._small = np.empty(self.n_probes)
        self._none = contact.ActiveSet(np.zeros((0, 0)))  # the Winkler bed keeps no set

    def describe(self) -> str:
        how = []
        if self.columns:
            how.append(f"{self.n_probes} collider probes (depths constant along y)")
        if self.mirrored:
            how.append(f"mirror-halved solve on {self.n} nodes")
        return f"{self.n_full} nodes: {', '.join(how) or 'full problem'}"

    def depths(self, bone: np.ndarray) -> bool:
        """The reduced depth map at the bone's world position into ``pen``."""
        near = _depths(bone, *self.probe.arrays, self._small)
        np.take(self._small, self.group, out=self.pen)
        return near

    def step(self, bone0, qpos, jx, jz, total, taxel_out) -> tuple[float, float]:
        """One held-force step in one call: the depths at the bone (from ``qpos``), the height
        that carries ``total`` (the pressure sum), the pad moved there (``qpos[jz]``), the
        taxel loads into ``taxel_out``. Re-collides when the pad moves beyond the margin and
        updates the contact set when it changes. Returns ``(force [N], deepest node [m])``."""
        s = self.solver or self._none
        M, S, in_set, C, rowsum = s.same_set_state()
        st, force, top, M2, S2, updates, rebuilds, rowsum2 = _held_kernel(
            bone0,
            qpos,
            jx,
            jz,
            self.probe.arrays,
            self._small,
            self.group,
            self.winkler_k,
            self.mult,
            M,
            S,
            in_set,
            C,
            s.K if s.K is not None else contact._NO_K,
            rowsum,
            contact._TOL_REL,
            total,
            self.margin,
            s.updates,
            s.refresh,
            contact._MAX_ITER,
            _QS_COLLISIONS,
            self.pen,
            self.f,
            self.W,
            self.area,
            taxel_out,
        )
        if M2 is not M:  # the set changed
            s.M, s.S, s.updates = M2, S2, updates
            s.rebuilds += rebuilds
            s._rowsum, s._rowsum_of = rowsum2, M2
        if st == 0:
            return force, top
        if st == 1:
            raise PhysicsError(
                f"quasi-static force control: the pad found no height carrying {total * self.area:g} N "
                f"within {_QS_COLLISIONS} collision queries (it fell more than "
                f"{_QS_COLLISIONS * self.margin * 1e3:g} mm in one step)"
            )
        if st == 3:
            raise PhysicsError("no skin node lies within the collider's margin of the plate")
        raise PhysicsError(
            f"the force-holding contact solve did not converge in {contact._MAX_ITER} iterations "
            f"(target {total:.4g} Pa summed over the nodes)"
        )


def _mirror_of(c: PrimitiveCollider) -> np.ndarray | None:
    """Each node's mirror image across y = 0 (same x, z, radius, margin; y negated,
    bit-exact), or None if some node has none."""
    key = {
        (x, y, z, r, m): i
        for i, ((x, y, z), r, m) in enumerate(
            zip(c.local.tolist(), c.radius, c.margin, strict=True)
        )
    }
    if len(key) != len(c.radius):
        return None
    out = np.empty(len(key), dtype=np.int64)
    for (x, y, z, r, m), i in key.items():
        j = key.get((x, -y, z, r, m))  # -0.0 == 0.0: the centre line maps to itself
        if j is None:
            return None
        out[i] = j
    return out


def _mirror_symmetric(C: np.ndarray, mirror: np.ndarray) -> bool:
    return bool(np.allclose(C[np.ix_(mirror, mirror)], C, rtol=_SYM_RTOL, atol=0.0))


@numba.njit(cache=True)
def _held_kernel(
    bone0,
    qpos,
    jx,
    jz,
    probe,
    small,
    group,
    winkler_k,
    mult,
    M,
    S,
    in_set,
    C,
    K,
    rowsum,
    tol_rel,
    total,
    qs_margin,
    updates,
    refresh,
    max_iter,
    n_collisions,
    pen,
    f,
    W,
    area,
    taxel_out,
):
    """:meth:`HeldSkin.step`; ``probe``: the collider's arrays (:attr:`PrimitiveCollider.arrays`).
    Returns ``(status, force, top, M, S, updates, rebuilds,
    rowsum)``; status 0 done, 1 no height within the collision queries, 2 the contact solve
    did not converge, 3 no node within the margin (from the contact solve)."""
    n = pen.shape[0]
    bone = np.empty(3)
    rebuilds = 0
    done = False
    for _ in range(n_collisions):
        bone[0] = bone0[0] + qpos[jx]
        bone[1] = bone0[1]
        bone[2] = bone0[2] + qpos[jz]
        near = _depths(bone, *probe, small)
        for i in range(n):
            pen[i] = small[group[i]]
        if not near:  # nothing within the margin: sink by most of it and look again
            qpos[jz] -= 0.9 * qs_margin
            continue
        dz = np.nan
        if winkler_k > 0.0:  # L0: the Winkler bed, in closed form
            dz = _winkler_force(pen, mult, winkler_k, total, f)
            if dz != dz:
                return 3, 0.0, 0.0, M, S, updates, rebuilds, rowsum
        elif S.size:  # the common case: the set holds at the shift it implies
            dz = contact._force_same_set(M, S, pen, C, in_set, tol_rel, total, f, rowsum)
        if dz != dz:
            st, dz, M, S, updates, rb = contact._force_loop(
                M, S, in_set, C, K, pen, tol_rel, total, updates, refresh, max_iter, f, False
            )
            rebuilds += rb
            rowsum = M @ np.ones(S.size)  # M 1 for the new M (BLAS, as _force_loop forms it)
            if st != 1:
                return 3 if st == 2 else 2, 0.0, 0.0, M, S, updates, rebuilds, rowsum
        qpos[jz] -= dz
        for i in range(n):
            pen[i] += dz
        if abs(dz) <= qs_margin:
            done = True
            break
    if not done:
        return 1, 0.0, 0.0, M, S, updates, rebuilds, rowsum
    force = 0.0
    for i in range(n):
        force += f[i] * area
    for t in range(W.shape[0]):
        acc = 0.0
        for i in range(n):
            acc += W[t, i] * (f[i] * area)
        taxel_out[t] = acc
    top = -np.inf
    for i in range(n):
        if pen[i] > top:
            top = pen[i]
    return 0, force, top, M, S, updates, rebuilds, rowsum


@numba.njit(cache=True)
def _winkler_force(pen, mult, k, total, f):
    """:func:`contact.winkler_force` with node weights ``mult`` (the nodes each reduced node
    stands for): the shift ``dz`` at which ``sum(mult * k * max(pen + dz, 0)) = total``, and
    those pair sums into ``f``; NaN if no node is finite. Equal to it bit for bit at unit
    weights (the same sequential sums, deepest first)."""
    n = pen.shape[0]
    cnt = 0
    for i in range(n):
        if np.isfinite(pen[i]):
            cnt += 1
    if cnt == 0:
        return np.nan
    idx = np.empty(cnt, np.int64)
    c = 0
    for i in range(n):
        if np.isfinite(pen[i]):
            idx[c] = i
            c += 1
    order = np.argsort(-pen[idx], kind="mergesort")  # deepest first; ties keep their order
    need = total / k
    csum = 0.0
    wsum = 0.0
    dz = 0.0
    for m in range(cnt):
        i = idx[order[m]]
        csum += mult[i] * pen[i]
        wsum += mult[i]
        dz = (need - csum) / wsum
        nxt = pen[idx[order[m + 1]]] if m + 1 < cnt else -np.inf
        if dz + nxt <= 0:
            break
    for i in range(n):
        d = pen[i] + dz
        f[i] = mult[i] * (k * d) if d > 0.0 else 0.0
    return dz
