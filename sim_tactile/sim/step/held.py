"""The held step: the pad moved to the height at which the skin carries the commanded force.

Under quasi-static force control a step is: the depth map at the bone's pose, the height at
which the skin carries the force (the skin's force-holding solve, see
:meth:`~sim_tactile.sim.skin.contact.ActiveSet.solve_force`), a new collision query wherever the
pad moved beyond the collider's margin (nodes further away could not join the contact), and
the taxel loads there. One step, two implementations with the same interface
(:class:`HeldStep`: ``step(qpos, jz, total, taxel_out) -> (force, deepest node)`` and
``describe()``), tested equal:

- :class:`PlainHeldStep`: the plain loop, over any collider and any skin model: the reference,
  and the path of the spectral skin and of plates that MuJoCo must collide;
- :class:`CompiledHeldStep`: the whole step in one numba call (:func:`_held_kernel`) with a
  compiled collider (the plate's features, the rough plates' profile, or a height map's
  samples), so no step pays Python's per-call costs more than once, on the smallest exact
  problem:

  - **columns** (:meth:`PrimitiveCollider.y_invariant`, :meth:`SurfaceCollider.y_invariant`):
    when every plate geom is a box or drafted ridge that runs past the whole pad in y
    (ridges across the slide), or the pad lies inside a rough profile's y extent, a node's
    depth does not depend on its y; the collider computes one node per distinct (x, z,
    radius, margin), the rest are copies (bit-identical). A height map never reduces
    (:meth:`~sim_tactile.plates.define.surface.Surface.y_invariant`): its collider computes every
    node;
  - **mirror** halving: when, in addition, the node grid is symmetric about the pad's centre
    line (nodes at y and -y alike), the depth map, and so the unique contact solution, are
    symmetric. The solve then runs on the nodes with y >= 0 only. Its unknowns are the summed
    pressure of each mirror pair, ``f = p_a + p_a'`` (``p_a`` on the centre line), and its
    compliance ``C_f[a, b] = (C[a, b] + C[a, b']) / 2`` is symmetric positive definite
    (``V' C V`` for the pair-averaging ``V``). The total force is the plain sum of ``f``, so
    the force-holding solve is unchanged; the taxels read ``f`` through ``W_f[:, b] =
    (W[:, b] + W[:, b']) / 2``. Equal to the full solve to round-off (tested); the set
    updates, which dominate a sliding step, cost about a third.

  L0's Winkler bed takes the same call in closed form (:func:`_winkler_force`).
"""

from __future__ import annotations

from functools import partial
from typing import Protocol

import numpy as np

from ..._jit import njit
from ...cache import setup_memo
from ...errors import PhysicsError
from ...hashing import array_digest
from ..collide.choose import probe_depths
from ..collide.height import SurfaceCollider
from ..collide.primitive import PrimitiveCollider
from ..skin import contact
from ..skin.contact.inverse import NO_K
from ..skin.contact.kernels import (
    force_loop,
    joint_loop,
    ordered_product,
    set_trial,
    spread,
)
from ..skin.models import CoupledSkin, SkinModel, SpectralSkin

#: Collision queries one step may take before it gives up (the pad falling through).
QS_COLLISIONS = 50
#: Relative tolerance of the mirror-symmetry check of the compliance.
_SYM_RTOL = 1e-10


def _no_height(force_n: float, margin: float) -> PhysicsError:
    return PhysicsError(
        f"quasi-static force control: the pad found no height carrying {force_n:g} N "
        f"within {QS_COLLISIONS} collision queries (it fell more than "
        f"{QS_COLLISIONS * margin * 1e3:g} mm in one step)"
    )


class HeldStep(Protocol):
    """What every held step answers (the plain and compiled steps here, the plate's own cells
    in :mod:`.plate_held`); :func:`~.choose.make_held_step` chooses one."""

    def step(
        self, qpos: np.ndarray, jz: int, total: float, taxel_out: np.ndarray
    ) -> tuple[float, float]:
        """Move the pad (``qpos[jz]``) to the height where the node pressures sum to
        ``total`` [Pa over the pad lattice's nodes], write the taxel loads [N] into
        ``taxel_out``; ``(force [N], deepest node [m])``."""
        ...

    def describe(self) -> str:
        """Which skin problem the step solves, for a recording's ``skin_problem``."""
        ...


class PlainHeldStep:
    """The held step as a plain loop over ``collider`` (any, with ``depths_at``:
    :meth:`~sim_tactile.sim.collide.primitive.PrimitiveCollider.depths_at`) and
    ``skin`` (any skin model, with ``solve_force``); ``W`` maps node loads to taxel loads."""

    def __init__(self, collider, skin: SkinModel, W: np.ndarray, area_m2: float, margin: float):
        self.collider, self.skin, self.W = collider, skin, W
        self.area, self.margin = area_m2, margin
        self.pen = np.zeros(W.shape[1])
        self.p = np.zeros(W.shape[1])  # the pressures [Pa] of the last step

    def describe(self) -> str:
        if isinstance(self.skin, SpectralSkin):
            return f"full problem, {self.skin.describe()}"
        return "full problem"

    def step(self, qpos, jz, total, taxel_out) -> tuple[float, float]:
        """Move the pad (``qpos[jz]``) to the height where the node pressures sum to ``total``
        [Pa], write the taxel loads [N] into ``taxel_out``; ``(force [N], deepest node [m])``."""
        pen = self.pen
        for _ in range(QS_COLLISIONS):
            if not self.collider.depths_at(qpos, pen):  # nothing near: sink by most of the
                qpos[jz] -= 0.9 * self.margin  # margin, look again
                continue
            p, dz = self.skin.solve_force(pen, total)
            qpos[jz] -= dz
            pen += dz  # the depths at the new height
            if abs(dz) <= self.margin:
                break
        else:
            raise _no_height(total * self.area, self.margin)
        self.p = p
        loads = p * self.area
        np.matmul(self.W, loads, out=taxel_out)
        return float(loads.sum()), float(pen.max())


def _halved_arrays(skin: CoupledSkin, nodes: np.ndarray, pair: np.ndarray):
    """The mirror-halved compliance ``C_f`` on ``nodes`` (their mirrors ``pair``) and its
    inverse (None when the skin keeps none)."""
    C = skin.C
    Cf = 0.5 * (C[np.ix_(nodes, nodes)] + C[np.ix_(nodes, pair)])
    if skin.symmetric:
        Cf = np.ascontiguousarray(0.5 * (Cf + Cf.T))
        return Cf, np.ascontiguousarray(np.linalg.inv(Cf))
    Cf = np.ascontiguousarray(Cf)  # friction coupled in: C is not symmetric
    return Cf, None if skin.K is None else np.ascontiguousarray(np.linalg.inv(Cf))


def _halved(skin: CoupledSkin, nodes: np.ndarray, pair: np.ndarray):
    """:func:`_halved_arrays`, kept in this process under the skin's content key when it has
    one (every slide of a scene halves the same skin)."""
    if skin.key is None:
        return _halved_arrays(skin, nodes, pair)
    parts = {"skin": skin.key, "nodes": array_digest(nodes), "pair": array_digest(pair)}
    compute = lambda: _halved_arrays(skin, nodes, pair)  # noqa: E731
    return setup_memo("mirror-halved skin", parts, compute, (__name__,))


class CompiledHeldStep:
    """The held step in one compiled call on the reduced problem (see the module docstring).

    ``pen`` and ``f`` live on the reduced nodes ``nodes`` (all nodes when no reduction
    applies, or ``reduce`` is False); ``f`` sums each mirror pair's pressures, so
    ``area * f.sum()`` is the normal force and ``W @ (area * f)`` the taxel loads. ``joint``:
    a contact set that does not hold is solved together with the pad's shift
    (:func:`~sim_tactile.sim.skin.contact.kernels.joint_loop`, ``StepOptions.held_solve =
    "joint"``), its inverse rebuilt where its drift check asks (at most every
    :data:`~sim_tactile.sim.skin.contact.active_set.JOINT_REFRESH` updates), else by the
    reference's Newton iteration on the shift alone, rebuilt every
    :data:`~sim_tactile.sim.skin.contact.active_set.REFRESH` updates."""

    def __init__(
        self,
        collider: PrimitiveCollider | SurfaceCollider,
        skin: SkinModel,
        W: np.ndarray,
        area_m2: float,
        margin: float,
        reduce: bool = True,
        joint: bool = False,
    ):
        n = W.shape[1]
        self.area = area_m2
        self.margin = margin
        self.bone0, self.jx = collider.bone0, collider.jx
        nodes = np.arange(n)
        coupled = isinstance(skin, CoupledSkin)
        C, K = (skin.C, skin.K) if coupled else (None, None)
        self.winkler_k = 0.0 if coupled else skin.k
        self.columns = reduce and collider.y_invariant(float(self.bone0[1]))
        self.mirrored = False
        mult = np.ones(n)
        if self.columns:
            mirror = _mirror_of(collider)
            if mirror is not None and (not coupled or _symmetric(skin, mirror)):
                self.mirrored = True
                nodes = np.flatnonzero(collider.local[:, 1] >= 0.0)
                pair = mirror[nodes]
                mult = np.where(pair != nodes, 2.0, 1.0)
                if coupled:
                    C, K = _halved(skin, nodes, pair)
                W = 0.5 * (W[:, nodes] + W[:, pair])
        self.nodes = nodes
        self.n_full = n
        self.n = nodes.size
        self.mult = mult
        # the Winkler bed keeps no contact set: an empty solver stands in for it
        refresh = contact.JOINT_REFRESH if joint else contact.REFRESH
        self.solver = (
            contact.ActiveSet(C, K, refresh, symmetric=skin.symmetric)
            if coupled
            else contact.ActiveSet(np.zeros((0, 0)))
        )
        self.W = np.ascontiguousarray(W, dtype=np.float64)
        probes = partial(_probes, collider, nodes, self.columns)
        kept = getattr(collider, "kept", None)  # shared by the slides of one model or surface
        key = ("held probes", self.columns, nodes.tobytes())
        sub, self.group = kept(key, probes) if kept else probes()
        #: the collider of the reduced problem's probes
        self.probes = sub
        self.n_probes = len(sub.radius)
        self.pen = np.empty(self.n)
        self.f = np.zeros(self.n)
        self._small = np.empty(self.n_probes)
        self._reduced = (self._small, self.group, self.mult)
        self._limits = (contact.TOL_REL, contact.MAX_ITER, QS_COLLISIONS, self.margin, joint)

    @property
    def joint(self) -> bool:
        """Whether a contact set that does not hold is solved with the pad's shift (the
        kernel's ``limits``, as :meth:`kernel_args` passes them)."""
        return self._limits[4]

    def describe(self) -> str:
        how = []
        if self.columns:
            how.append(f"{self.n_probes} collider probes (depths constant along y)")
        if self.mirrored:
            how.append(f"mirror-halved solve on {self.n} nodes")
        return f"{self.n_full} nodes: {', '.join(how) or 'full problem'}"

    def depths(self, bone: np.ndarray) -> bool:
        """The reduced depth map at the bone's world position into ``pen``."""
        near = probe_depths(bone, self.probes.probe, self._small)
        np.take(self._small, self.group, out=self.pen)
        return near

    def kernel_args(self) -> tuple:
        """``(probe, reduced, skin, state, limits)``: the arguments of :func:`_held_kernel`
        this step keeps, the contact set's state as it stands (:meth:`step`, and the
        compiled slide's :func:`~.held_run.held_steps`); the limits say whether a set that
        does not hold is solved with its shift (``joint``)."""
        s = self.solver
        M, S, in_set, C, rowsum = s.same_set_state()
        K = s.K if s.K is not None else NO_K
        skin = (self.winkler_k, C, K, s.floor, s.symmetric)
        state = (M, S, in_set, s.sums, rowsum, s.updates, s.refresh)
        return self.probes.probe, self._reduced, skin, state, self._limits

    def step(self, qpos, jz, total, taxel_out) -> tuple[float, float]:
        """:meth:`PlainHeldStep.step` in one call on the reduced problem; the contact set is
        updated when it changes."""
        probe, reduced, skin, state, limits = self.kernel_args()
        st, force, top, M2, S2, updates, rebuilds, rowsum2 = _held_kernel(
            (self.bone0, qpos, self.jx, jz),
            probe,
            reduced,
            skin,
            state,
            limits,
            total,
            (self.pen, self.f, self.W, self.area, taxel_out),
        )
        if M2 is not state[0]:  # the set changed
            self.solver.adopt(M2, S2, updates, rebuilds, rowsum2)
        if st == 0:
            return force, top
        self.fail(st, total)

    def fail(self, st: int, total: float):
        """Raise the error of the kernel's status ``st`` (not 0) at ``total`` [Pa]."""
        if st == 1:
            raise _no_height(total * self.area, self.margin)
        if st == 3:
            raise PhysicsError("no skin node lies within the collider's margin of the plate")
        raise PhysicsError(
            f"the force-holding contact solve did not converge in {contact.MAX_ITER} iterations "
            f"(target {total:.4g} Pa summed over the nodes)"
        )


def _probes(collider, nodes: np.ndarray, columns: bool) -> tuple:
    """``(probes, group)``: the collider of the nodes ``nodes``, reduced to one probe per
    distinct (x, z, radius, margin) where the depths are ``columns`` (constant along y),
    and each node's probe. The step reads the probes' arrays (``probe``) and passes the
    bone's position itself: the slides that share them (``collider.kept``) never read a
    pose from them."""
    sub = collider.subset(nodes)
    if not columns:
        return sub, np.arange(len(nodes), dtype=np.int64)
    key = np.column_stack([sub.local[:, 0], sub.local[:, 2], sub.radius, sub.margin])
    _, first, group = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return sub.subset(first), group.ravel().astype(np.int64)


def _mirror_of(c: PrimitiveCollider | SurfaceCollider) -> np.ndarray | None:
    """Each node's mirror image across y = 0 (same x, z, radius, margin; y negated,
    bit-exact), or None if some node has none: :func:`_mirror_pairs`, kept in this process
    under the nodes' content key (every slide of a scene pairs the same nodes)."""
    parts = {"nodes": array_digest(c.local, c.radius, c.margin)}
    compute = lambda: (_mirror_pairs(c),)  # noqa: E731
    return setup_memo("mirror pairs of skin nodes", parts, compute, (__name__,))[0]


def _mirror_pairs(c: PrimitiveCollider | SurfaceCollider) -> np.ndarray | None:
    """Each node's mirror image (see :func:`_mirror_of`), or None if some node has none."""
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


def _symmetric(skin: CoupledSkin, mirror: np.ndarray) -> bool:
    """:func:`_mirror_symmetric` of the skin's compliance, kept in this process under the
    skin's content key when it has one (every slide of a scene asks of the same skin)."""
    if skin.key is None:
        return _mirror_symmetric(skin.C, mirror)
    parts = {"skin": skin.key, "mirror": array_digest(mirror)}
    compute = lambda: (np.array([_mirror_symmetric(skin.C, mirror)]),)  # noqa: E731
    return bool(setup_memo("mirror symmetry of a skin", parts, compute, (__name__,))[0][0])


@njit
def _held_kernel(pose, probe, reduced, skin, state, limits, total, out):
    """:meth:`CompiledHeldStep.step`. The arguments, grouped:

    - ``pose``: ``(bone0, qpos, jx, jz)``, the bone's rest position and the joints;
    - ``probe``: the collider's ``probe`` (a named tuple whose class picks its depth
      kernel: :func:`~sim_tactile.sim.collide.choose.probe_depths`);
    - ``reduced``: ``(small, group, mult)``: the probes' depths, each node's probe, the nodes
      each reduced node stands for;
    - ``skin``: ``(winkler_k, C, K, floor, sym)``: the Winkler stiffness (> 0 for L0), else
      the reduced compliance, its inverse, the depth above which a node can touch and
      whether the compliance is symmetric;
    - ``state``: ``(M, S, in_set, cu, rowsum, updates, refresh)``: the contact set's state
      (``cu``: the drift check's running sums, updated in place);
    - ``limits``: ``(tol_rel, max_iter, n_collisions, qs_margin, joint)``; ``joint``: a set
      that does not hold is first solved together with its shift (:func:`joint_loop`;
      ``held_solve = "joint"``, as ``auto`` takes it), else by the reference's Newton
      iteration on the shift (:func:`force_loop`), which also takes over where the joint
      loop stops;
    - ``out``: ``(pen, f, W, area, taxel_out)``: the depths and pressures it writes, and the
      taxel readout.

    Returns ``(status, force, top, M, S, updates, rebuilds, rowsum)``; status 0 done, 1 no
    height within the collision queries, 2 the contact solve did not converge, 3 no node
    within the margin (from the contact solve)."""
    bone0, qpos, jx, jz = pose
    small, group, mult = reduced
    winkler_k, C, K, floor, sym = skin
    M, S, in_set, cu, rowsum, updates, refresh = state
    tol_rel, max_iter, n_collisions, qs_margin, joint = limits
    pen, f, W, area, taxel_out = out
    n = pen.shape[0]
    bone = np.empty(3)
    rebuilds = 0
    done = False
    for _ in range(n_collisions):
        bone[0] = bone0[0] + qpos[jx]
        bone[1] = bone0[1]
        bone[2] = bone0[2] + qpos[jz]
        near = probe_depths(bone, probe, small)
        for i in range(n):
            pen[i] = small[group[i]]
        if not near:  # nothing within the margin: sink by most of it and look again
            qpos[jz] -= 0.9 * qs_margin
            continue
        dz = np.nan
        # kernels.NOT_TRIED, made here: numba reads a global array as read-only, another type
        tried = (np.empty(0), np.nan, np.empty(0), np.zeros(0, np.bool_), np.empty(0, np.int64))
        if winkler_k > 0.0:  # L0: the Winkler bed, in closed form
            dz = _winkler_force(pen, mult, winkler_k, total, f)
            if dz != dz:
                return 3, 0.0, 0.0, M, S, updates, rebuilds, rowsum
        elif S.size:  # the common case: the set holds at the shift it implies
            dz, pS, drop, A = set_trial(M, S, pen, C, in_set, tol_rel, total, rowsum, floor)
            if dz == dz and not drop.any() and A.size == 0:
                spread(pS, S, f)
            else:
                tried = (rowsum, dz, pS, drop, A)
                dz = np.nan
        if dz != dz:  # the set changes: solved with the shift, with M 1 for the new M
            st, dz, M, S, updates, rb, rowsum = _changed_set(
                (M, S, in_set, C, K, pen, tol_rel, total, updates, refresh, max_iter, f),
                (floor, sym, cu),
                joint,
                tried,
            )
            rebuilds += rb
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
    load = np.empty(n)
    for i in range(n):
        load[i] = f[i] * area
    taxel_out[:] = ordered_product(W, np.arange(W.shape[0]), np.arange(n), load)
    top = -np.inf
    for i in range(n):
        if pen[i] > top:
            top = pen[i]
    return 0, force, top, M, S, updates, rebuilds, rowsum


@njit
def _changed_set(problem, how, joint, tried):
    """The held solve of a step whose contact set does not hold: ``problem`` is ``(M, S,
    in_set, C, K, pen, tol_rel, total, updates, refresh, max_iter, p)`` and ``how`` is
    ``(floor, sym, cu)``, as :func:`force_loop` takes them. Where ``joint``, the set and
    the shift are solved together first (:func:`joint_loop`, from the failed same-set check
    ``tried``), and the Newton iteration on the shift goes on from where that stops; else the
    Newton iteration alone (the reference). Returns force_loop's ``(status, dz, M, S,
    updates, rebuilds)`` and ``M 1`` of the M returned."""
    M, S, updates = problem[0], problem[1], problem[8]
    rebuilds = 0
    if joint and S.size:
        st, dz, M, S, updates, rebuilds, b = joint_loop(*problem, *how, tried)
        if st == 1:
            return st, dz, M, S, updates, rebuilds, b  # b: M 1, as below forms it
    rest = (M, S) + problem[2:8] + (updates,) + problem[9:]  # from the state it left
    st, dz, M, S, updates, rb = force_loop(*rest, False, *how)
    return st, dz, M, S, updates, rebuilds + rb, M @ np.ones(S.size)  # BLAS


@njit
def _winkler_force(pen, mult, k, total, f):
    """:func:`~sim_tactile.sim.skin.contact.winkler_force` with node weights ``mult`` (the nodes each reduced node
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
