"""The contact problem on a node lattice, solved with FFT products: for pads of many nodes.

On a lattice of equal node patches the skin's compliance depends on the offset between two
nodes alone (a half-space, or a stack of layers: any translation-invariant skin), so the
deflection ``u = C p`` is a convolution of the pressures with the compliance kernel. Padded
to twice the lattice on each side, the convolution is exact (no wrap-around) and costs two
FFTs: ``O(N log N)`` time and ``O(N)`` memory, where the dense solve of
:class:`~.active_set.ActiveSet` stores ``C`` and its inverse (``O(N^2)``) and factorises
(``O(N^3)``).

:class:`Spectral` solves the same complementarity problem as :func:`~.reference.halfspace`
(``p >= 0, C p >= pen, p (C p - pen) = 0``) by the constrained conjugate-gradient method of
Polonsky and Keer (Wear 231, 1999): conjugate directions on the nodes in contact, a
projection onto ``p >= 0``, and, where a node outside the set overlaps the plate, a restart
that lets it join. Held at a normal force (:meth:`Spectral.solve_force`) it keeps the sum of
the pressures at the target on every iteration, and the pad's shift is the mean gap on the
contact set (the Lagrange multiplier of that sum). Each solve starts from the previous
step's pressures, which on a sliding pad are close.

An iteration takes one FFT product: the deflection ``C p`` is carried from the last one
through the search direction's product, and the nodes the projection moves are added by
direct sums (:data:`DIRECT_MAX`); a loosened held solve starts from the last answer with
the product its shift took (:meth:`Spectral._warm_product`). The iteration ends where the
gaps on the set agree to the deflections' rounding (:data:`ROUNDING`). Where it cycles
(:data:`CYCLE_ITER`), as it can when thousands of nodes join and leave at once, a last start
lets few join at a time (:data:`JOIN_SHARE`).

Where the nodes within the collider's reach fill a small block of the lattice (a curved
pad), the solve runs on that block alone (:data:`BLOCK_SHARE`): the nodes outside it cannot
carry load, and the kernel depends on offsets only, so the block's problem is the whole
lattice's, solved with smaller FFTs.

The answer agrees with the dense solve to the iteration's tolerance (:data:`TOL`, on the
change of the pressures summed over the nodes, relative to their sum); tested. It needs a
symmetric positive definite ``C``: a skin whose sliding friction is coupled into the normal
problem (not symmetric) takes the dense solve.
"""

from __future__ import annotations

import numpy as np

from ....errors import PhysicsError
from . import cg_kernels

#: scipy.fft, its own pocketfft binding (None where this scipy has none) and whether
#: :meth:`Spectral.apply` takes the direct transforms: loaded with the first spectral skin
#: (:func:`_load_fft`), not with the module: scipy.fft's import took 0.4-0.7 s of every
#: command's start-up, most of which solve no skin spectrally
fft = _pocketfft = None
_DIRECT = False
_LOADED = False


def _load_fft() -> None:
    """Import scipy.fft and its binding once, and check the direct transforms
    (:func:`_direct_works`)."""
    global fft, _pocketfft, _DIRECT, _LOADED
    if _LOADED:
        return
    from scipy import fft as scipy_fft

    fft = scipy_fft
    try:  # scipy.fft's own pocketfft binding, without its dispatch (see Spectral.apply)
        from scipy.fft._pocketfft import pypocketfft

        _pocketfft = pypocketfft
    except ImportError:  # pragma: no cover (another scipy: the public path)
        _pocketfft = None
    _LOADED = True
    _DIRECT = _direct_works()


#: Convergence of the conjugate-gradient iteration: the pressures' change in one iteration,
#: summed over the nodes, relative to their sum (Polonsky and Keer's criterion). At 1e-10
#: the taxel loads agree with the dense solve to about 1e-8 (tested at 1e-6).
TOL = 1e-10
#: Iterations before a solve gives up.
MAX_ITER = 2000
#: Iterations from the last step's pressures before the solve starts afresh (see
#: :meth:`Spectral._starts`); a sliding step converges in 1-60.
WARM_ITER = 300
#: A start is given up when the pressures change by more than this share of their sum for
#: :data:`CYCLE_ITER` iterations running: the iteration is cycling (measured: icub60 pressed
#: on textures20/boxes-4.5mm at 0.385 mm, 5926 nodes in reach, alternated between two sets
#: of 3394 and 3762 nodes, some 1600 nodes leaving and joining each iteration, changing the
#: pressures by 121% of their sum, for good).
CYCLE_CHANGE = 0.5
CYCLE_ITER = 50
#: ... and a slide solved step by step (:meth:`Spectral.stepwise`) gives up the last step's
#: pressures after this many: there a warm start that cycles does not come back (measured on
#: textures20-icub60-v1's boxes-4.5mm, two slides: none of those cycling for 10 iterations
#: converged by 50; the slides' records are equal bit for bit, with 14% fewer FFT products,
#: 1.17x), while a phase table's phases, each started from its neighbour's answer, often
#: converge after a short cycle (at 10 there, icub60-v2-grids took 1.25x longer).
STEP_CYCLE_ITER = 10
#: The last start lets at most this share of the contact set's nodes join in one iteration
#: (those overlapping the plate most): the cycle above then converges in 95 iterations.
JOIN_SHARE = 0.02
#: The deflection ``C p`` is carried from one iteration to the next (``C (p - tau t)`` from
#: the direction's product, which each iteration computes anyway), and the nodes the
#: projection moves off that line are added by direct sums over the kernel, up to this many
#: (a direct sum costs about N operations a node, an FFT product some 50 N); more, and the
#: product is taken again by FFT.
DIRECT_MAX = 24
#: ... and it is taken again by FFT every this many iterations, so that rounding never
#: accumulates.
REFRESH_EVERY = 16
#: A solve runs on the smallest block of the lattice that holds every node in reach (the
#: nodes beyond the collider's margin carry no load, and the kernel depends on offsets only,
#: so the block's problem is the lattice's) when that block has at most this share of its
#: nodes: the FFTs and every vector of the iteration shrink with it (a curved finger touches
#: a patch of its lattice: finger7-v2's 5785 nodes, some 600 in reach).
BLOCK_SHARE = 0.5
#: Solvers of blocks kept, by their shape (a sliding pad's block changes shape now and then).
BLOCKS_KEPT = 8
#: The gaps on the contact set are equal when their spread is below this share of the
#: largest deflection (a thousand times double precision): below it the gradient is the
#: rounding of ``C p``, and a step along it can throw the pressures anywhere (measured: a
#: converging held step of finger7/bumps-3x3 took a step 1e12 times its predecessors' on
#: such a gradient and stopped far from the answer).
ROUNDING = 1e-13
#: The tightest tolerance at which a solve takes its FFT products in single precision
#: (``float32`` transforms, some 1.45 times quicker than ``float64``'s on the iCub's
#: lattices; everything else stays in double precision): a change of the pressures below
#: this share of their sum is near the rounding of the products (24 bits). ``auto``'s
#: loosened solves (``solve_tol = 1e-3``) take it; the reference (``1e-10``) never does.
#: Measured on the batched solve's iCub poses (``perf/bench_batched_solve.py``; its
#: arithmetic all single): at 1e-5 the answers are 2.5e-5 off the reference, as the
#: double solve's at 1e-5 are 2.1e-5 off.
FLOAT32_MIN_TOL = 1e-5
#: :data:`ROUNDING` where the products are single: the gaps on the contact set are equal
#: when their spread is below this share of the largest deflection (four times the
#: precision). Measured on the same poses: the double share scaled by the precision
#: (5.4e-5) stopped the solve 1.2e-3 off the reference at a tolerance of 1e-4 (double:
#: 3.4e-4); from 2e-6 down the single solve reaches its tolerance, and from 5e-7 down it
#: agrees with itself.
ROUNDING_FLOAT32 = 5e-7


def _mean_gap(u: np.ndarray, pen: np.ndarray, on: np.ndarray) -> float:
    """The mean of the deflection less the penetration on the contact set ``on``: the pad's
    shift at which the pressures hold their total."""
    return float(np.mean(u[on] - pen[on]))


def _held_start(p: np.ndarray, total: float | None, u0: np.ndarray | None):
    """``(p, u)``: a start (a copy), its pressures scaled to sum to ``total`` where it is
    held, and its product ``u0`` scaled alike (None where not given)."""
    if total is None:
        return p.copy(), (None if u0 is None else u0.copy())
    f = total / p.sum()
    return p * f, (None if u0 is None else u0 * f)


class Spectral:
    """The contact problem of the ``(ny, nx)`` compliance kernel ``table`` [m/Pa] (entry
    ``[j, i]``: nodes ``i`` pitches apart along x and ``j`` along y; even in each axis) on a
    lattice of ``nx`` by ``ny`` nodes numbered row by row (``index = iy * nx + ix``, as
    :func:`~sim_tactile.scene.nodes.skin_grid` numbers them)."""

    #: the iteration's vector work in compiled calls (False: numpy, the reference)
    compiled = True

    def __init__(
        self,
        table: np.ndarray,
        tol: float = TOL,
        max_iter: int = MAX_ITER,
        single: bool | None = None,
    ):
        _load_fft()
        table = np.asarray(table, dtype=np.float64)
        ny, nx = table.shape
        self.nx, self.ny, self.n = nx, ny, nx * ny
        self.tol, self.max_iter = tol, max_iter
        # the kernel on a periodic lattice at least 2 n - 1 long on each side (so the circular
        # convolution is the linear one), of a length the FFT factors well: offset i at i,
        # offset -i at L - i
        Ly, Lx = fft.next_fast_len(2 * ny - 1, real=True), fft.next_fast_len(2 * nx - 1, real=True)
        ext = np.zeros((Ly, Lx))
        ext[:ny, :nx] = table
        ext[Ly - ny + 1 :, :nx] = table[:0:-1, :]
        ext[:ny, Lx - nx + 1 :] = table[:, :0:-1]
        ext[Ly - ny + 1 :, Lx - nx + 1 :] = table[:0:-1, :0:-1]
        self.shape = ext.shape
        self.khat = fft.rfft2(ext)
        #: whether the FFT products are taken in single precision (``single``; None: where
        #: the tolerance allows it, :data:`FLOAT32_MIN_TOL`)
        self.single = tol >= FLOAT32_MIN_TOL if single is None else bool(single)
        self.rounding = ROUNDING_FLOAT32 if self.single else ROUNDING
        real, cplx = (np.float32, np.complex64) if self.single else (np.float64, np.complex128)
        # the kernel's spectrum as the products take it (``khat`` itself in double)
        self._khat = self.khat.astype(cplx, copy=False)
        # the product's buffers: the loads padded along x, the spectrum padded along y
        self._padded = np.zeros((ny, Lx), dtype=real)
        self._spectrum = np.zeros(self.khat.shape, dtype=cplx)
        self.direct = _DIRECT
        self.table = table
        self.diag = float(table[0, 0])
        self.p = np.zeros(self.n)  # the last solve's pressures: the next one's start
        self.iterations = 0  # of the last solve
        self._last = (None, None, None)  # (pen, total, answer) of the last solve
        #: iterations a cycling warm start runs before it gives way (:meth:`stepwise`)
        self.warm_cycle_iter = CYCLE_ITER
        #: ``(p, C p)`` of the last held solve's answer, its product taken for the pad's
        #: shift: the next solve's warm start where it is that answer (:meth:`_warm_product`)
        self._answered: tuple[np.ndarray, np.ndarray] | None = None
        self._blocks: dict[tuple[int, int], Spectral] = {}  # solvers of blocks, by shape

    def stepwise(self) -> None:
        """Solve a slide step by step: a warm start, the last step's pressures, gives way
        after :data:`STEP_CYCLE_ITER` large changes running (:data:`CYCLE_ITER` otherwise)."""
        self.warm_cycle_iter = STEP_CYCLE_ITER

    def apply(self, p: np.ndarray) -> np.ndarray:
        """``C p`` [m]: the deflection of the nodes under pressures ``p`` [Pa]. The padded
        lattice's extra rows hold no load and its extra columns are not read: the transforms
        along x skip them (half the work of a plain 2D transform).

        The four transforms call scipy.fft's pocketfft binding directly (``direct``),
        the same transforms bit for bit (tested, and checked when this module loads) without
        the dispatch that cost as much as a small block's arithmetic (30 against 18 us on a
        curved finger's 25 x 30 block); else :meth:`apply_public`, scipy.fft's functions.
        A solver of a loose tolerance (:attr:`single`) transforms in single precision and
        returns double."""
        if not self.direct:
            return self.apply_public(p)
        ny, nx = self.ny, self.nx
        Lx = self.shape[1]
        x = self._padded
        x[:, :nx] = p.reshape(ny, nx)
        a = _pocketfft.r2c(x, (1,), True, 0, None, 1)
        b = self._spectrum
        b[:ny] = a
        b[ny:] = 0.0
        _pocketfft.c2c(b, (0,), True, 0, b, 1)
        b *= self._khat
        _pocketfft.c2c(b, (0,), False, 2, b, 1)
        u = _pocketfft.c2r(b[:ny], (1,), Lx, False, 2, None, 1)[:, :nx]
        return u.astype(np.float64, copy=False).ravel()

    def apply_public(self, p: np.ndarray) -> np.ndarray:
        """:meth:`apply` through scipy.fft's public functions (the reference)."""
        ny, nx = self.ny, self.nx
        Ly, Lx = self.shape
        a = fft.rfft(p.reshape(ny, nx).astype(self._padded.dtype, copy=False), n=Lx, axis=1)
        a = fft.fft(a, n=Ly, axis=0)
        a *= self._khat
        a = fft.ifft(a, axis=0, overwrite_x=True)[:ny]
        return fft.irfft(a, n=Lx, axis=1)[:, :nx].astype(np.float64, copy=False).ravel()

    # -- the contact problem
    def solve(self, pen_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pressures [Pa] for node penetrations ``pen_m`` (``-inf``: out of reach), and the
        nodes in contact."""
        p, _ = self._answer(pen_m, None)
        return p, p > 0

    def solve_force(self, pen_m: np.ndarray, total_pa: float) -> tuple[np.ndarray, float]:
        """The pad held at a normal force: pressures [Pa] summing to ``total_pa`` and the pad's
        downward shift ``dz`` [m] at which they hold (as
        :meth:`~.active_set.ActiveSet.solve_force`)."""
        if not total_pa > 0:
            raise PhysicsError(f"solve_force needs a positive total pressure, got {total_pa!r}")
        return self._answer(pen_m, float(total_pa))

    def _answer(self, pen: np.ndarray, total: float | None) -> tuple[np.ndarray, float]:
        """``(p, dz)`` (``dz`` 0 without a total). A problem equal to the last one (a flat pad
        over flat tops between two edge crossings) returns the last answer."""
        pen = np.asarray(pen, dtype=np.float64)
        last_pen, last_total, last = self._last
        if last_pen is not None and total == last_total and np.array_equal(pen, last_pen):
            return last[0].copy(), last[1]
        box = self._box(np.isfinite(pen))
        if box is None:
            p = self._solve(pen, total)
            dz = 0.0 if total is None else self._shift(p, pen)
        else:
            p, dz = self._solve_block(pen, total, box)
        self._last = (pen.copy(), total, (p.copy(), dz))
        return p, dz

    def _box(self, ok: np.ndarray) -> tuple[int, int, int, int] | None:
        """``(y0, y1, x0, x1)``: the block of rows and columns that holds every node in reach
        ``ok``, when it has at most :data:`BLOCK_SHARE` of the nodes (else None)."""
        if not ok.any():
            return None
        grid = ok.reshape(self.ny, self.nx)
        rows = np.flatnonzero(grid.any(axis=1))
        cols = np.flatnonzero(grid.any(axis=0))
        y0, y1, x0, x1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
        if (y1 - y0) * (x1 - x0) > BLOCK_SHARE * self.n:
            return None
        return int(y0), int(y1), int(x0), int(x1)

    def _solve_block(self, pen, total, box) -> tuple[np.ndarray, float]:
        """The solve on the block ``box`` of the lattice (its own FFTs, started from this
        solver's last pressures there); the pressures on the whole lattice and ``dz``."""
        y0, y1, x0, x1 = box
        shape = (y1 - y0, x1 - x0)
        sub = self._blocks.pop(shape, None)
        if sub is None:
            sub = Spectral(self.table[: shape[0], : shape[1]], self.tol, self.max_iter, self.single)
            sub.compiled = self.compiled
        sub.warm_cycle_iter = self.warm_cycle_iter
        self._blocks[shape] = sub  # most recently used last
        while len(self._blocks) > BLOCKS_KEPT:
            del self._blocks[next(iter(self._blocks))]
        pen_b = np.ascontiguousarray(pen.reshape(self.ny, self.nx)[y0:y1, x0:x1]).ravel()
        sub.p = np.ascontiguousarray(self.p.reshape(self.ny, self.nx)[y0:y1, x0:x1]).ravel()
        p_b = sub._solve(pen_b, total)
        self.iterations = sub.iterations
        p = np.zeros(self.n)
        p.reshape(self.ny, self.nx)[y0:y1, x0:x1] = p_b.reshape(shape)
        self.p = p
        dz = 0.0 if total is None else sub._shift(p_b, pen_b)
        return p.copy(), dz

    def _shift(self, p: np.ndarray, pen: np.ndarray) -> float:
        """The pad's shift ``dz`` at which the held answer ``p`` (this solver's last, equal
        to :attr:`p`) holds its total; its product ``C p`` is kept for the next solve's warm
        start (:meth:`_warm_product`)."""
        u = self.apply(p)
        self._answered = (self.p, u)
        return _mean_gap(u, pen, p > 0)

    def _starts(self, ok: np.ndarray, pen: np.ndarray, total: float | None):
        """The first iterates, in the order they are tried: the last solve's pressures where
        those nodes can still touch (on a sliding pad, close to the answer), then a uniform
        pressure on every node in reach (Polonsky and Keer's start). The iteration can cycle
        from a start far from the answer (measured: a warm start of 45 loaded nodes when the
        answer loads some 900 never converged; the uniform start took 83 iterations), so a
        warm start that has not converged within :data:`WARM_ITER` iterations gives way."""
        warm = np.where(ok, self.p, 0.0)
        if warm.any():
            yield warm, min(WARM_ITER, self.max_iter), None, self.warm_cycle_iter
        flat = ok.astype(np.float64)
        if total is None:  # the pressure that lifts the deepest node out, spread
            flat *= max(pen[ok].max(), 0.0) / (self.diag * ok.sum()) + 1e-300
        yield flat, self.max_iter, None, CYCLE_ITER
        yield flat, self.max_iter, JOIN_SHARE, CYCLE_ITER  # where the plain iteration cycles

    def _solve(self, pen: np.ndarray, total: float | None) -> np.ndarray:
        """Polonsky and Keer's iteration; ``total`` None: the pad at its place (no mean gap
        removed, no scaling), else the sum of the pressures held at ``total``."""
        ok = np.isfinite(pen)  # nodes beyond the collider's margin cannot join
        if not ok.any() and total is not None:
            raise PhysicsError("no skin node lies within the collider's margin of the plate")
        if total is None and not (ok.any() and pen[ok].max() > 0):
            self.p = np.zeros(self.n)  # nothing touches: no load is the solution
            return self.p.copy()
        pen_ok = np.where(ok, pen, 0.0)
        u0 = self._warm_product(ok, total)
        for start, budget, join, patience in self._starts(ok, pen_ok, total):
            p, it, change = self._cg(start, pen_ok, ok, total, budget, join, patience, u0)
            u0 = None  # the warm start's alone
            if p is not None:
                self.p, self.iterations = p, it
                return p.copy()
        raise PhysicsError(
            f"the spectral contact solve did not converge in {self.max_iter} iterations "
            f"({int(ok.sum())} nodes within reach; last change {change:.3g})"
        )

    def _warm_product(self, ok: np.ndarray, total: float | None) -> np.ndarray | None:
        """``C p`` of the warm start where it is the last held solve's answer, whose product
        was taken for its shift (:meth:`_answer`): a solve of single products
        (:attr:`single`) then takes it, scaled, instead of taking it again (one FFT product of
        the 10-11 a held iCub solve takes at ``auto``'s tolerance); None elsewhere. The
        reference's solves take their own."""
        kept, self._answered = self._answered, None
        if kept is None or total is None or not self.single:
            return None
        p, u = kept
        if p is not self.p and not np.array_equal(p, self.p):  # another start
            return None
        if not ok[p > 0].all():  # loaded nodes out of reach: the warm start is not ``p``
            return None
        return u

    def _cg(self, p, pen_ok, ok, total, budget, join_share=None, patience=CYCLE_ITER, u0=None):
        """Iterate from ``p``: ``(p, iterations, change)``, ``p`` None if ``budget``
        iterations did not converge or the iteration cycles (``patience`` large changes
        running); ``join_share``: at most that share of the set's nodes join in one
        iteration; ``u0``: ``C p`` of the start (None: taken by FFT). The vector work in
        compiled calls (:mod:`.cg_kernels`); with ``join_share``, and as the reference,
        :meth:`_cg_numpy`."""
        if join_share is not None or not self.compiled:
            return self._cg_numpy(p, pen_ok, ok, total, budget, join_share, patience, u0)
        held = total is not None
        p, u = _held_start(p, total, u0)  # u: C p, carried between iterations
        new = np.empty(self.n)
        g = np.empty(self.n)
        t = np.zeros(self.n)
        g_old, delta = 1.0, 0.0
        scale = total if held else -1.0
        total_f = float(total) if held else 0.0
        change = np.inf
        gap_tol = 1e-9 * max(float(np.abs(pen_ok).max()), 1e-12)
        stuck = 0
        for it in range(1, budget + 1):
            if not p.max() > 0.0:  # every node let go (the pad at its place above the plate)
                return p, it, 0.0
            if u is None or it % REFRESH_EVERY == 0:  # by FFT
                u = self.apply(p)
            G, _ = cg_kernels.gradient(u, pen_ok, p, g, held)
            cg_kernels.direction(g, p, t, delta * G / g_old)
            g_old = G if G > 0 else 1.0
            r_raw = self.apply(t)
            st, delta, ch, carried, scale = cg_kernels.step(
                r_raw,
                t,
                g,
                p,
                new,
                u,
                ok,
                held,
                total_f,
                G,
                self.rounding,
                DIRECT_MAX,
                self.table,
                self.nx,
                scale,
            )
            if st == 1:  # no direction left on the set: solved, unless nodes off it overlap
                joined = self._joined(p, g, ok, gap_tol, total)
                if joined is None:
                    return p, it, 0.0
                p, t, delta, u = joined, np.zeros(self.n), 0.0, None
                continue
            if not carried:
                u = None  # taken again by FFT at the next iteration
            p, new = new, p
            change = ch
            verdict, stuck = self._judge(change, stuck, patience)
            if verdict:
                return (p if verdict == 1 else None), it, change
        return None, budget, change

    def _joined(self, p, g, ok, gap_tol, total):
        """Where no direction is left on the set: the pressures with the nodes off it that
        overlap the plate joined, each with the pressure that would lift it alone (the sum
        held at ``total``), or None if none overlaps (solved)."""
        join = (p == 0) & (g < -gap_tol) & ok
        if not join.any():
            return None
        p = p.copy()
        p[join] = -g[join] / self.diag
        if total is not None:
            p *= total / p.sum()
        return p

    def _judge(self, change: float, stuck: int, patience: int = CYCLE_ITER) -> tuple[int, int]:
        """``(verdict, stuck)`` after an iteration that changed the pressures by ``change``:
        1 converged, 2 cycling (``patience`` large changes running), else 0."""
        if change < self.tol:
            return 1, stuck
        stuck = stuck + 1 if change > CYCLE_CHANGE else 0
        return (2 if stuck >= patience else 0), stuck

    def _cg_numpy(
        self, p, pen_ok, ok, total, budget, join_share=None, patience=CYCLE_ITER, u0=None
    ):
        """:meth:`_cg` in numpy: the reference of the compiled iteration, and the path of
        the start that lets few nodes join at a time."""
        p, u = _held_start(p, total, u0)  # u: C p, carried between iterations
        t = np.zeros(self.n)
        g_old, delta = 1.0, 0.0
        scale = total if total is not None else None
        change = np.inf
        gap_tol = 1e-9 * max(float(np.abs(pen_ok).max()), 1e-12)
        stuck = 0  # iterations running whose change was above CYCLE_CHANGE
        for it in range(1, budget + 1):
            on = p > 0
            if not on.any():  # every node let go (the pad at its place above the plate)
                return p, it, 0.0
            if u is None or it % REFRESH_EVERY == 0:  # by FFT
                u = self.apply(p)
            g = u - pen_ok
            if total is not None:
                g -= g[on].mean()
            G = float(g[on] @ g[on])
            t = np.where(on, g + (delta * G / g_old) * t, 0.0)
            g_old = G if G > 0 else 1.0
            r_raw = self.apply(t)
            r = r_raw - r_raw[on].mean() if total is not None else r_raw
            rt = float(r[on] @ t[on])
            floor = (self.rounding * float(np.abs(u).max())) ** 2 * float(on.sum())
            if not rt > 0 or G <= floor:  # no direction left on the set (or the gaps on it
                # agree to the deflections' rounding, where a step would follow the noise):
                # solved, unless a node off it overlaps the plate (a set whose gaps are all
                # equal, e.g. one node, has no gradient; returning then kept a one-node warm
                # start where the whole face touched). Those nodes join with the pressure
                # that would lift them alone.
                joined = self._joined(p, g, ok, gap_tol, total)
                if joined is None:
                    return p, it, 0.0
                p, t, delta, u = joined, np.zeros(self.n), 0.0, None
                continue
            tau = float(g[on] @ t[on]) / rt
            p_old = p
            line = p - tau * t
            p = np.maximum(line, 0.0)
            overlap = (p == 0) & (g < 0) & ok
            if join_share is not None:
                cap = max(1, int(join_share * on.sum()))
                if overlap.sum() > cap:  # the nodes overlapping most
                    overlap &= g <= np.partition(g[overlap], cap - 1)[cap - 1]
            if overlap.any():
                delta = 0.0
                p[overlap] -= tau * g[overlap]
            else:
                delta = 1.0
            u = self._carry(u, tau, r_raw, line, p)
            if total is not None:
                s = total / p.sum()
                p *= s
                if u is not None:
                    u *= s
            if scale is None:
                scale = max(float(p.sum()), 1e-300)
            change = float(np.abs(p - p_old).sum()) / max(float(p.sum()), scale * 1e-12)
            verdict, stuck = self._judge(change, stuck, patience)
            if verdict:
                return (p if verdict == 1 else None), it, change
        return None, budget, change

    def _carry(self, u, tau, r_raw, line, p):
        """``C p`` from ``C (p_old - tau t) = u - tau C t`` and the nodes where ``p`` left
        that line (clipped at zero, or joining), by direct sums where they are few."""
        moved = np.flatnonzero(p != line)
        if moved.size > DIRECT_MAX:
            return None  # taken again by FFT at the next iteration
        u = u - tau * r_raw
        if moved.size:
            u2 = u.reshape(self.ny, self.nx)
            cg_kernels.add_columns(u2, self.table, moved, p[moved] - line[moved], self.nx)
        return u

    def stiffness_per_area(self, p: np.ndarray, tol: float = 1e-8) -> float:
        """``1' inv(C_SS) 1`` on the contact set of ``p`` [Pa/m] (as
        :meth:`~.active_set.ActiveSet.stiffness_per_area`), by conjugate gradients on the
        set."""
        on = p > 0
        if not on.any():
            return 0.0
        b = on.astype(np.float64)
        x = np.zeros(self.n)
        r = b.copy()
        d = r.copy()
        rr = float(r @ r)
        for _ in range(self.max_iter):
            q = np.where(on, self.apply(d), 0.0)
            a = rr / float(d @ q)
            x += a * d
            r -= a * q
            rr_new = float(r @ r)
            if rr_new < (tol * tol) * float(b @ b):
                break
            d = r + (rr_new / rr) * d
            rr = rr_new
        return float(x.sum())


def _direct_works() -> bool:
    """Whether the direct transforms give the public ones' product bit for bit here, in
    double and in single precision."""
    if _pocketfft is None:
        return False
    rng = np.random.default_rng(0)
    table = np.abs(rng.standard_normal((5, 7)))
    p = rng.standard_normal(table.size)
    try:
        for tol in (TOL, FLOAT32_MIN_TOL):
            s = Spectral(table, tol=tol)
            s.direct = True
            if not np.array_equal(s.apply(p), s.apply_public(p)):
                return False
        return True
    except Exception:  # noqa: BLE001  (another binding's signature: the public path)
        return False
