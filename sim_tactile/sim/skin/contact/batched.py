"""The spectral contact problem of many poses at once, in torch, on the CPU or a GPU.

:class:`BatchedSpectral` solves B problems of one skin lattice together: B slides stepped in
lockstep, the phases of a phase table, or both. It is :class:`~.spectral.Spectral`'s
iteration (Polonsky and Keer's constrained conjugate gradients, held at a force or not), with
its stopping rule and tolerance (``tol``: the change of the pressures in one iteration,
summed over the nodes, relative to their sum), its starts (the given warm pressures for at
most :data:`~.spectral.WARM_ITER` iterations, then a uniform pressure on the nodes in reach,
then one that lets few nodes join at a time), its test for a cycling iteration, its restart
where no direction is left and nodes off the set overlap, and its end where the gaps agree
to the deflections' rounding. Each pose runs its own iteration on a row of the batch: it
stops at its own tolerance (its answer is taken then and it leaves the batch, which runs to
its last pose), and it restarts on its own.

Where it differs from the numpy solve, and why (the answers agree to the tolerance; tested):

- **the deflection** ``u = C p`` is carried from one iteration to the next as there, and
  taken again by FFT every :data:`~.spectral.REFRESH_EVERY` iterations; where the
  projection moved a node off the step's line it is taken again by FFT at the next
  iteration (the numpy solve adds up to :data:`~.spectral.DIRECT_MAX` such nodes by direct
  sums over the kernel: a gather per node, which on a GPU costs as much as a product);
- **the block**: where the nodes in reach of every pose of the batch fill a small block of
  the lattice (:data:`~.spectral.BLOCK_SHARE`), the batch is solved on that block (the
  numpy solve takes each pose's own);
- **the last start** (few nodes join at a time), taken only where the plain iteration
  cycled from both others, runs in the numpy solve (:meth:`~.spectral.Spectral._cg_numpy`)
  for those poses alone;
- **a repeated problem** is solved again (the numpy solve returns its last answer when it is
  given the same depths twice);
- **the arithmetic**: the FFTs are torch's (MKL's or pocketfft's on a CPU, cuFFT's on a
  GPU), not scipy's pocketfft, and the sums over the nodes are taken in another order, so
  the answers are not the numpy solve's bit for bit, and a pose can stop an iteration
  earlier or later (near the tolerance).

On a GPU the host looks at the batch once an iteration, to take the stale rows' deflections
again (those rows alone, padded to a power of two of them: cuFFT keeps a plan per batch
size), and learns which poses are done every :data:`CHECK_EVERY` iterations (a pose that
converges in between keeps its answer: it is taken when it converges; one whose start
failed in between waits for its next start till then); the batch shrinks to the poses
still running when they are half of it or fewer, in powers of two. In ``float32`` the
rounding floor is :data:`~.spectral.ROUNDING_FLOAT32` and the tolerance must be at least
:data:`~.spectral.FLOAT32_MIN_TOL`.

torch is imported when a solver is made, not when this module is imported.
"""

from __future__ import annotations

import numpy as np

from ....errors import ConfigError, PhysicsError
from .device import require_device
from .spectral import (
    BLOCK_SHARE,
    BLOCKS_KEPT,
    CYCLE_CHANGE,
    CYCLE_ITER,
    FLOAT32_MIN_TOL,
    JOIN_SHARE,
    REFRESH_EVERY,
    ROUNDING,
    ROUNDING_FLOAT32,
    WARM_ITER,
    Spectral,
    _mean_gap,
)

#: Iterations between the host's looks at the batch on a GPU (which poses are done, which
#: failed a start, whether the batch can shrink): each look waits for the GPU to finish its
#: queue. On the CPU the host looks after every iteration (it costs nothing there).
CHECK_EVERY = 8
DTYPES = ("float64", "float32")


class _Product:
    """``C p`` of each row of a ``(b, ny * nx)`` tensor on one lattice
    (``_cg_torch.product``; the kernel's transform is the numpy solver's, cast to the
    dtype), with the numpy solve of that lattice (``ref``) and a count of the rows it
    multiplied (the poses' products)."""

    def __init__(self, torch, table: np.ndarray, device, dtype) -> None:
        self.ref = Spectral(table)
        self.ny, self.nx, self.n = self.ref.ny, self.ref.nx, self.ref.n
        self.shape = (self.ny, self.nx, *self.ref.shape)
        cdtype = torch.complex128 if dtype == torch.float64 else torch.complex64
        self.khat = torch.as_tensor(self.ref.khat).to(device=device, dtype=cdtype)
        self.diag = self.ref.diag
        self.count = 0

    def __call__(self, x):
        from . import _cg_torch

        self.count += x.shape[0]
        return _cg_torch.product(x, self.khat, self.shape)


class _Rows:
    """The state of the poses still iterating, one row each (``rows``: their index in the
    batch; per-pose numbers as ``(b, 1)`` columns); :meth:`keep` shrinks every row tensor
    at once."""

    NAMES = (
        "rows pen ok flat total gap_tol P T U g_old delta scale stuck it budget start stale done "
        "failed fallback p_out it_out"
    ).split()

    def keep(self, idx) -> None:
        for name in self.NAMES:
            v = getattr(self, name)
            if v is not None:
                setattr(self, name, v.index_select(0, idx))


class BatchedSpectral:
    """The contact problem of B poses of one spectral skin at once.

    ``skin``: a :class:`~sim_tactile.sim.skin.models.SpectralSkin` (or its
    :class:`~.spectral.Spectral`); its kernel, tolerance and iteration cap are taken.
    ``device``: ``cpu``, ``cuda`` or ``cuda:N`` (:func:`~.device.require_device`: a GPU
    asked for and absent is a ConfigError). ``dtype``: ``float64`` (the reference) or
    ``float32``. ``tol``: replaces the skin's tolerance. ``compile``: the iteration's
    element-wise work through ``torch.compile`` (fewer kernels on a GPU, untried there; the
    first call compiles for a minute or more: 100 s on a busy CPU).

    After a call, ``steps`` is the number of lockstep iterations the batch ran and
    ``products`` the FFT products it took, counted per pose."""

    def __init__(
        self,
        skin,
        *,
        device: str = "cpu",
        dtype: str = "float64",
        tol: float | None = None,
        compile: bool = False,
    ) -> None:
        solver = getattr(skin, "solver", skin)
        if not isinstance(solver, Spectral):
            raise ConfigError(
                f"skin = {type(skin).__name__}: the batched solve needs a spectral skin "
                "(SpectralSkin or Spectral)"
            )
        if dtype not in DTYPES:
            raise ConfigError(f"dtype = {dtype!r}; valid: {', '.join(DTYPES)}")
        self.tol = float(solver.tol if tol is None else tol)
        if not self.tol > 0:
            raise ConfigError(f"tol = {tol!r}; valid: a positive number")
        if dtype == "float32" and self.tol < FLOAT32_MIN_TOL:
            raise ConfigError(
                f"tol = {self.tol:g} in float32; valid: at least {FLOAT32_MIN_TOL:g} "
                "(or dtype 'float64')"
            )
        self.device = require_device(device)
        import torch

        from . import _cg_torch

        self.torch = torch
        self._cg = _cg_torch
        self._gradient, self._project = _cg_torch.gradient, _cg_torch.project
        if compile:  # inductor fuses the element-wise work (the FFTs stay eager)
            self._gradient = torch.compile(_cg_torch.gradient, dynamic=True)
            self._project = torch.compile(_cg_torch.project, dynamic=True)
        self.dtype = torch.float64 if dtype == "float64" else torch.float32
        self.max_iter = solver.max_iter
        self.table = solver.table
        self.nx, self.ny, self.n = solver.nx, solver.ny, solver.n
        self.rounding = ROUNDING if dtype == "float64" else ROUNDING_FLOAT32
        self.check_every = 1 if self.device.type == "cpu" else CHECK_EVERY
        self._products: dict[tuple[int, int], _Product] = {}
        self.steps = 0
        self.products = 0

    # -- the public calls
    def solve_force(
        self, pen_m: np.ndarray, total_pa, warm: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The pads held at normal forces: ``pen_m`` (B, n) the node penetrations [m]
        (``-inf``: out of reach), ``total_pa`` (B,) or one number, the pressures' sum [Pa],
        ``warm`` (B, n) each pose's start (its last pressures [Pa]; None: a uniform start).
        Returns ``(p, dz, iterations)``: the pressures (B, n) [Pa] summing to ``total_pa``,
        each pad's downward shift (B,) [m] at which they hold (as
        :meth:`~.spectral.Spectral.solve_force`), and each pose's iterations (B,) (of the
        start that converged, as the numpy solve counts them)."""
        pen = self._pens(pen_m)
        total = np.broadcast_to(np.asarray(total_pa, dtype=np.float64), (pen.shape[0],))
        if not np.all(total > 0) or not np.all(np.isfinite(total)):
            bad = total[~((total > 0) & np.isfinite(total))][0]
            raise PhysicsError(f"solve_force needs a positive total pressure, got {bad!r}")
        empty = ~np.isfinite(pen).any(axis=1)
        if empty.any():
            raise PhysicsError(
                f"pose {int(np.flatnonzero(empty)[0])}: no skin node lies within the "
                "collider's margin of the plate"
            )
        return self._answer(pen, total.copy(), warm)

    def solve(
        self, pen_m: np.ndarray, warm: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """The pads where they are: ``pen_m`` (B, n) as in :meth:`solve_force`; returns the
        pressures (B, n) [Pa] and each pose's iterations (B,) (as
        :meth:`~.spectral.Spectral.solve`)."""
        p, _, its = self._answer(self._pens(pen_m), None, warm)
        return p, its

    # -- the batch
    def _pens(self, pen_m) -> np.ndarray:
        pen = np.asarray(pen_m, dtype=np.float64)
        if pen.ndim != 2 or pen.shape[1] != self.n:
            raise ConfigError(
                f"pen_m has shape {pen.shape}; valid: (B, {self.n}), B poses of the "
                f"{self.nx} x {self.ny} lattice"
            )
        return pen

    def _warm(self, warm, shape) -> np.ndarray:
        if warm is None:
            return np.zeros(shape)
        w = np.asarray(warm, dtype=np.float64)
        if w.shape != shape or not np.all(np.isfinite(w)):
            raise ConfigError(f"warm has shape {w.shape}; valid: {shape}, finite pressures")
        return w

    def _answer(self, pen, total, warm) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(p, dz, iterations)`` of the batch (``dz`` 0 without totals), solved on the
        block that holds every pose's nodes in reach when it is small."""
        B = pen.shape[0]
        warm = self._warm(warm, pen.shape)
        p_all = np.zeros((B, self.n))
        dz = np.zeros(B)
        its = np.zeros(B, dtype=np.int64)
        self.steps = self.products = 0
        ok = np.isfinite(pen)
        live = np.ones(B, bool)
        if total is None:  # nothing touches: no load is the solution
            live = (np.where(ok, pen, -np.inf) > 0).any(axis=1)
        if not live.any():
            return p_all, dz, its
        y0, y1, x0, x1 = self._box(ok[live])
        h, w = y1 - y0, x1 - x0

        def crop(a):
            a = a[live].reshape(-1, self.ny, self.nx)[:, y0:y1, x0:x1]
            return np.ascontiguousarray(a).reshape(-1, h * w)

        prod = self._product(h, w)
        before = prod.count
        p_b, dz[live], its[live] = self._run(
            prod, crop(pen), None if total is None else total[live], crop(warm)
        )
        p_all.reshape(B, self.ny, self.nx)[live, y0:y1, x0:x1] = p_b.reshape(-1, h, w)
        self.products = prod.count - before
        return p_all, dz, its

    def _box(self, ok: np.ndarray) -> tuple[int, int, int, int]:
        """The rows and columns that hold every node in reach of the batch, when that block
        has at most :data:`~.spectral.BLOCK_SHARE` of the nodes, else the lattice."""
        grid = ok.any(axis=0).reshape(self.ny, self.nx)
        rows, cols = np.flatnonzero(grid.any(axis=1)), np.flatnonzero(grid.any(axis=0))
        y0, y1, x0, x1 = int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1
        if (y1 - y0) * (x1 - x0) > BLOCK_SHARE * self.n:
            return 0, self.ny, 0, self.nx
        return y0, y1, x0, x1

    def _product(self, h: int, w: int) -> _Product:
        prod = self._products.pop((h, w), None)
        if prod is None:
            prod = _Product(self.torch, self.table[:h, :w], self.device, self.dtype)
        self._products[(h, w)] = prod  # most recently used last
        while len(self._products) > BLOCKS_KEPT:
            del self._products[next(iter(self._products))]
        return prod

    # -- the iteration
    def _run(self, prod, pen, total, warm) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every pose's iteration from its starts: ``(p, dz, iterations)`` (numpy; ``dz``
        0 without totals)."""
        torch = self.torch
        held = total is not None
        s = self._rows(prod, pen, total, warm)
        B = pen.shape[0]
        p_out = torch.zeros((B, prod.n), device=self.device, dtype=self.dtype)
        it_out = torch.zeros((B, 1), device=self.device, dtype=torch.int32)
        fallback = torch.zeros((B, 1), device=self.device, dtype=torch.bool)
        pen_ok = s.pen
        limit = WARM_ITER + self.max_iter + 1  # the two starts' budgets: every pose is done
        for step in range(1, limit + 1):
            self._iterate(s, prod, held)
            if step % self.check_every and step < limit:
                continue
            if self.check_every > 1 and bool(s.failed.any()):
                self._restart(s, s.failed, held)
                s.failed = torch.zeros_like(s.failed)
            done = s.done.squeeze(1)
            n_live = int((~done).sum())
            if n_live == 0:
                break
            rows = done.numel()
            if self.check_every == 1 and n_live <= rows - max(1, rows // 8):
                size = n_live  # on the CPU, when an eighth of the rows are done
            elif self.check_every > 1 and 2 * n_live <= rows:
                size = 1 << (n_live - 1).bit_length()  # on a GPU, in powers of two
            else:
                continue
            if size < rows:
                self._store(s, p_out, it_out, fallback)
                s.keep(torch.argsort(done.to(torch.int8), stable=True)[:size])
        self.steps = step
        s.fallback |= ~s.done  # (none: each start has its budget)
        s.done[:] = True
        self._store(s, p_out, it_out, fallback)
        dz = np.zeros(B)
        if held:  # the pad's shift: the mean gap on the contact set (one product)
            dz = self._cg.mean_gaps(prod(p_out), pen_ok, p_out).squeeze(1).double().cpu().numpy()
        p = p_out.to(torch.float64).cpu().numpy()
        its = it_out.squeeze(1).cpu().numpy().astype(np.int64)
        for i in np.flatnonzero(fallback.squeeze(1).cpu().numpy()):
            p[i], dz[i], its[i] = self._last_start(prod, i, pen[i], total)
        return p, dz, its

    def _rows(self, prod, pen, total, warm) -> _Rows:
        """The batch's first state: each pose from its warm start where it has one in reach,
        else from the uniform start (``_cg_torch.starts``, on the device)."""
        torch, dev, dt = self.torch, self.device, self.dtype
        B = pen.shape[0]
        held = total is not None

        def column(value, dtype=dt):
            return torch.full((B, 1), value, device=dev, dtype=dtype)

        s = _Rows()
        s.total = torch.as_tensor(total, device=dev).to(dt).view(B, 1) if held else None
        s.ok, s.pen, s.flat, s.P, has_warm, s.gap_tol = self._cg.starts(
            torch.as_tensor(pen, device=dev).to(dt),
            torch.as_tensor(warm, device=dev).to(dt),
            s.total,
            prod.diag,
            held,
        )
        s.rows = torch.arange(B, device=dev)
        s.T, s.U, s.p_out = (torch.zeros_like(s.P) for _ in range(3))
        s.g_old, s.delta = column(1.0), column(0.0)
        s.scale = s.total.clone() if held else column(-1.0)
        s.stuck, s.it, s.it_out = (column(0, torch.int32) for _ in range(3))
        s.budget = torch.where(has_warm, min(WARM_ITER, self.max_iter), self.max_iter).int()
        s.start = torch.where(has_warm, 0, 1).int()
        s.stale = column(True, torch.bool)
        s.done, s.failed, s.fallback = (column(False, torch.bool) for _ in range(3))
        return s

    @staticmethod
    def _store(s: _Rows, p_out, it_out, fallback) -> None:
        """The answers of the rows that are done, into the batch's outputs."""
        done = s.done.squeeze(1)
        rows = s.rows[done]
        p_out.index_copy_(0, rows, s.p_out[done])
        it_out.index_copy_(0, rows, s.it_out[done])
        fallback.index_copy_(0, rows, s.fallback[done])

    def _last_start(self, prod, i, pen, total) -> tuple[np.ndarray, float, int]:
        """Pose ``i``'s last start, where the plain iteration cycled from the others: few
        nodes join at a time (:data:`~.spectral.JOIN_SHARE`), in the numpy solve;
        ``(p, dz, iterations)``."""
        t = None if total is None else float(total[i])
        ok = np.isfinite(pen)
        pen_ok = np.where(ok, pen, 0.0)
        flat = ok.astype(np.float64)
        if t is None:  # (as Spectral._starts)
            flat *= max(pen_ok[ok].max(), 0.0) / (prod.diag * ok.sum()) + 1e-300
        p, it, change = prod.ref._cg_numpy(flat, pen_ok, ok, t, self.max_iter, JOIN_SHARE)
        if p is None:
            raise PhysicsError(
                f"the spectral contact solve of pose {i} did not converge in {self.max_iter} "
                f"iterations ({int(ok.sum())} nodes within reach; last change {change:.3g})"
            )
        dz = 0.0 if t is None else _mean_gap(prod.ref.apply(p), pen, p > 0)
        return p, dz, it

    def _iterate(self, s: _Rows, prod: _Product, held: bool) -> None:
        """One iteration of every row (:meth:`~.spectral.Spectral._cg`'s body): the
        deflections taken again by FFT where they are stale, the direction, its product,
        the projection; then the verdicts and the restarts."""
        torch = self.torch
        s.it += 1
        need = (s.stale | (s.it % REFRESH_EVERY == 0)) & ~s.done
        self._refresh(s, prod, need)
        onf, c, g, G, t, s.g_old, umax = self._gradient(
            s.P, s.U, s.pen, s.T, s.delta, s.g_old, held
        )
        r = prod(t)
        P, s.U, s.T, s.delta, stale, conv, go, change, s.scale = self._project(
            s.P,
            s.U,
            g,
            t,
            r,
            onf,
            c,
            G,
            umax,
            s.ok,
            s.total,
            s.scale,
            s.gap_tol,
            (self.tol, self.rounding, prod.diag),
            held,
        )
        s.P = P
        s.stale = stale
        stuck = torch.where(change > CYCLE_CHANGE, s.stuck + 1, 0)
        s.stuck = torch.where(go & ~conv, stuck, s.stuck)
        new = conv & ~(s.done | s.failed)
        s.p_out = torch.where(new, P, s.p_out)
        s.it_out = torch.where(new, s.it, s.it_out)
        s.done = s.done | new
        fail = ~s.done & ((s.stuck >= CYCLE_ITER) | (s.it >= s.budget))
        if self.check_every == 1:
            if bool(fail.any()):
                self._restart(s, fail, held)
        else:  # on a GPU the host restarts them at its next look (they wait till then)
            s.failed = s.failed | fail

    def _refresh(self, s: _Rows, prod: _Product, need) -> None:
        """``U = C P`` on the rows ``need`` (one look of the host): those rows alone, on a
        GPU padded to a power of two of them (cuFFT keeps a plan per batch size)."""
        idx = need.squeeze(1).nonzero().squeeze(1)
        k, rows = idx.numel(), need.shape[0]
        if k == 0:
            return
        size = k if self.check_every == 1 else min(rows, 1 << (k - 1).bit_length())
        if size == rows:
            s.U = self.torch.where(need, prod(s.P), s.U)
        else:
            pad = idx[:1].expand(size - k)  # (rows done twice, kept once)
            u = prod(s.P.index_select(0, self.torch.cat([idx, pad])))
            s.U.index_copy_(0, idx, u[:k])
        s.stale = s.stale & ~need

    def _restart(self, s: _Rows, fail, held: bool) -> None:
        """The rows ``fail`` (their start cycled or ran out of iterations) from their next
        start: the uniform pressure after the warm one; after that, the numpy solve's last
        start (:meth:`_last_start`)."""
        torch = self.torch
        last = fail & (s.start >= 1)
        s.fallback = s.fallback | last
        s.done = s.done | last
        f = fail & ~last
        s.P = torch.where(f, s.flat, s.P)
        s.T = torch.where(f, 0.0, s.T)
        s.g_old = torch.where(f, 1.0, s.g_old)
        s.delta = torch.where(f, 0.0, s.delta)
        s.scale = torch.where(f, s.total if held else -1.0, s.scale)
        s.stuck = torch.where(f, 0, s.stuck)
        s.it = torch.where(f, 0, s.it)
        s.budget = torch.where(f, self.max_iter, s.budget)
        s.start = torch.where(f, 1, s.start)
        s.stale = s.stale | f
