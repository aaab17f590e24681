"""The contact problem of one compliance solved step after step (see :class:`ActiveSet`)."""

from __future__ import annotations

import numpy as np

from ...._jit import blas_alone
from ....errors import PhysicsError
from .inverse import NO_K
from .kernels import NO_P, force_loop, force_same_set, same_set_product, solve_loop
from .reference import MAX_ITER, TOL_REL


def skin_floor(C: np.ndarray) -> float:
    """The depth above which a node can touch, for compliance ``C``: 0 when every entry is
    >= 0 (a load only pushes the skin away from the plate), else -inf. A read-only ``C``
    (the skins' matrices, kept by content: :data:`~sim_tactile.cache.SETUP`) is read
    once in this process (:data:`_FLOORS`): each slide's two solvers of a 700-node skin read
    its 490 000 entries, 0.28 ms of a 12 ms PVDF slide. Read-only means read-only through
    and through: ``C`` and every array it is a view of (a matrix read from the disk cache is
    a view of the buffer it was read into, which the set-up memo makes read-only too)."""
    kept = read_only(C)
    if kept:
        hit = _FLOORS.get(id(C))
        if hit is not None and hit[0] is C:  # the entry holds C: its id is not reused
            return hit[1]
    floor = 0.0 if bool((C >= 0).all()) else -np.inf
    if kept:
        _FLOORS[id(C)] = (C, floor)
        while len(_FLOORS) > FLOORS_KEPT:
            del _FLOORS[next(iter(_FLOORS))]
    return floor


def read_only(a: np.ndarray) -> bool:
    """Whether ``a`` and every array it is a view of are read-only (a view of a writeable
    array changes with it), and the chain ends in an array that owns its data."""
    while True:
        if a.flags.writeable:
            return False
        if not isinstance(a.base, np.ndarray):
            return a.base is None
        a = a.base


#: The floors of read-only compliances, by the array's id (the entry holds the array).
_FLOORS: dict[int, tuple[np.ndarray, float]] = {}
FLOORS_KEPT = 16


#: block updates of a contact set's inverse before it is rebuilt from the compliance
REFRESH = 100
#: The same for ``auto``'s joint held solve (``held_solve = "joint"``), whose inverse is
#: rebuilt when its drift check asks (:data:`~.inverse.DRIFT_TOL`, checked at every update),
#: else after this many updates. :data:`REFRESH` predates that check and stays the
#: reference's schedule (the golden slides are bit for bit on it). On multilayer3x3x2's
#: hemispheres (some 850 updates a slide) it rebuilt a 450-node inverse 8.6 times a slide;
#: the check asked once, and a slide took 72.2 ms against 78.4 (perf/bench_refresh.py), its
#: recordings equal in float32.
JOINT_REFRESH = 1000


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

    A compliance that is not symmetric (friction coupled into the normal problem) takes
    ``symmetric=False``: the block updates then use the general Schur formulas, which read
    both off-diagonal blocks instead of taking one as the other's transpose.
    """

    def __init__(
        self,
        C: np.ndarray,
        K: np.ndarray | None = None,
        refresh: int = REFRESH,
        *,
        symmetric: bool = True,
    ):
        self.C, self.K, self.refresh = C, K, refresh
        self.symmetric = symmetric
        if C.shape[0]:
            blas_alone()  # its kernels multiply matrices
        #: the depth above which a node can touch: 0 when no load lifts any node toward the
        #: plate (C >= 0, the half-space), else -inf (a layered skin bulges around a load)
        self.floor = skin_floor(C)
        self.S = np.zeros(0, dtype=np.int64)  # contact set, in the order of M's rows
        self.M = np.zeros((0, 0))
        self.updates = 0
        self.rebuilds = 0
        self._in = np.zeros(C.shape[0], bool)
        #: the drift check's running sums ``C_SS v`` by node (:func:`~.inverse.set_sums`),
        #: kept in step with S by the kernels
        self._cu = np.zeros((C.shape[0], 2))
        self._rowsum, self._rowsum_of = np.zeros(0), None

    # -- the contact problem
    def solve(self, pen_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pressures [Pa] for node penetrations ``pen_m``, warm-started from the last set.
        Returns ``(p, active)`` as :func:`halfspace` does."""
        p = np.empty_like(pen_m)
        pS0 = NO_P
        if self.S.size:
            held, pS0 = same_set_product(
                self.M, self.S, pen_m, self.C, self._in, TOL_REL, p, self.floor
            )
            if held:
                return p, self._in.copy()  # the common case: the set holds, one product
        K = self.K if self.K is not None else NO_K
        status, M, S, updates, rebuilds = solve_loop(
            self.M,
            self.S,
            self._in,
            self.C,
            K,
            pen_m,
            TOL_REL,
            self.updates,
            self.refresh,
            MAX_ITER,
            p,
            self.floor,
            self.symmetric,
            self._cu,
            pS0,
        )
        self._take(M, S, updates, rebuilds)
        if status:
            return p, self._in.copy()
        raise PhysicsError(
            f"half-space contact solve did not converge in {MAX_ITER} iterations "
            f"({int((pen_m > 0).sum())} nodes)"
        )

    def solve_force(
        self, pen_m: np.ndarray, total_pa: float, max_iter: int = MAX_ITER
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
            dz = force_same_set(M, S, pen_m, C, in_set, TOL_REL, total_pa, p, rowsum, self.floor)
            if dz == dz:
                return p, dz
        K = self.K if self.K is not None else NO_K
        status, dz, M, S, updates, rebuilds = force_loop(
            self.M,
            self.S,
            self._in,
            self.C,
            K,
            pen_m,
            TOL_REL,
            float(total_pa),
            self.updates,
            self.refresh,
            max_iter,
            p,
            False,  # the same-set case was tried above
            self.floor,
            self.symmetric,
            self._cu,
        )
        self._take(M, S, updates, rebuilds)
        if status == 1:
            return p, dz
        if status == 2:
            raise PhysicsError("no skin node lies within the collider's margin of the plate")
        raise PhysicsError(
            f"the force-holding contact solve did not converge in {max_iter} iterations "
            f"(target {total_pa:.4g} Pa summed over the nodes)"
        )

    def same_set_state(self):
        """``(M, S, in_set, C, rowsum)``: what :func:`force_same_set` needs to try the current
        set; ``rowsum = M 1`` is kept while ``M`` stands."""
        if self._rowsum_of is not self.M:
            self._rowsum, self._rowsum_of = self.M.sum(axis=1), self.M
        return self.M, self.S, self._in, self.C, self._rowsum

    @property
    def sums(self) -> np.ndarray:
        """The drift check's running sums (``cu`` of :func:`~.kernels.solve_loop`), which a
        compiled step that solves this problem updates in place."""
        return self._cu

    def adopt(self, M, S, updates: int, rebuilds: int, rowsum) -> None:
        """Take the state a compiled step computed on this problem: the inverse ``M`` on the
        set ``S`` (in M's order), the update count since the last rebuild, the rebuilds it
        made, and ``rowsum = M 1``."""
        self._take(M, S, updates, rebuilds)
        self._rowsum, self._rowsum_of = rowsum, M

    def _take(self, M, S, updates: int, rebuilds: int) -> None:
        self.M, self.S, self.updates = M, S, updates
        self.rebuilds += rebuilds

    def stiffness_per_area(self) -> float:
        """d(total pressure integral)/d(uniform indentation) on the current set [Pa/m]:
        ``1' inv(C_SS) 1``; times the node area it is the pad's contact stiffness."""
        return float(self.M.sum())
