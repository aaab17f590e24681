"""A node lattice anchored to the plate: every wall on a line, fine cells at the walls.

The pad's own lattice (:mod:`~sim_tactile.scene.nodes`) moves with the pad, so a rigid box's
wall runs through a different patch at every step. A patch is in contact or not by its
centre, and the pressure under a rigid flat top is singular at the wall (it grows as the
inverse square root of the distance, as at a flat punch's edge): both errors grow with the
pitch. Clipping the patches at the walls at each step (:mod:`~sim_tactile.sim.skin.clipped`)
removes them, at the price of a new compliance and factorisation every step.

Here the lattice is fixed to the plate instead, and the pad slides over it:

- **along the slide** its lines are the plate's walls across the slide, taken modulo the
  texture's period ``P`` (so a wall is on a line wherever the pattern repeats), and between
  two walls cells of ``wall_m`` at each wall, doubling away from it up to ``pitch_m``
  (:func:`period_lines`). The lattice repeats every ``P``;
- **across the slide** (the pad does not move across it) its lines are the uniform
  ``pitch_y_m`` lattice, the taxels' edges, and the walls along the slide
  (:func:`row_lines`). Graded cells beside those walls too cost more than they return: every
  row runs the whole length of the window, and on flat ground (where the pad's whole face
  touches) each column that joins the contact is a block update as tall as the rows.

The pad covers a window of whole periods of the lattice that moves one period at a time.
Inside a window the lattice moves rigidly under the pad, and a rigid motion changes neither
the cells' sizes nor their relative positions: the compliance between any two cells is
constant. Moving the window by a period maps each cell onto the cell one period further,
whose compliance entries are the same numbers (they are computed from the same differences,
:func:`lattice_compliance`). So the compliance is computed once for the slide, and the
contact set's inverse (:class:`~sim_tactile.sim.skin.contact.ActiveSet`'s block updates) carries
over a window move by renumbering its cells. A step costs what a whole-patch step costs: the
depths, the same-set check, a block update where cells join or leave.

A cell is in contact or not as a whole, by its centre, and no wall runs through one; the
taxels' edges across the slide move over the cells, and a taxel at the surface reads its
exact overlap with each cell (the cell's load spread over the cell). Against Tamaas on
finger7's ridges and bumps (grid3x3, 1 N, four offsets) the taxel loads of the 0.5 mm /
2 x 2 mm lattice (auto's there) are 2.9-9.7% from the reference, of the 0.25 mm / 2 x 1 mm
lattice 1.2-4.0% (``docs/physics.md``).

It serves the elastic half-space (L1) under the held force, plates of boxes (ridges, bumps,
gratings of bars), and taxels at the surface (a buried taxel's weights would move with the
phase; left to the pad's lattice).
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import blas_alone, njit
from ...cache import setup_memo
from ...errors import PhysicsError
from ...hashing import array_digest
from ...plates.define.spec import Plate
from ...plates.define.surface import surface_of
from ..plan.lattices import PAD_SHAPE_CODES, check_anchorable, period_lines, row_lines
from .clipped import rect_entry
from .contact import MAX_ITER, REFRESH, TOL_REL
from .contact.inverse import NO_K, NO_SUMS
from .contact.kernels import force_loop, force_same_set


@njit
def lattice_compliance(cxb, wxb, P, n_periods, cy, wy, e_star):
    """(n, n) deflection at cell i's centre per unit *load* on cell j [m/N] (Love's
    rectangle solution over the cell's area), cells numbered ``(k m + a) ny + j`` for period
    k, base column a (centres ``cxb``, widths ``wxb`` in a period) and row j (``cy``,
    ``wy``). The x offset of two cells is ``(cxb[a] - cxb[b]) + (k - l) P``, so cells one
    period apart see the same numbers bit for bit."""
    m, ny = cxb.size, cy.size
    n = m * n_periods * ny
    C = np.empty((n, n))
    kk = 1.0 / (math.pi * e_star)
    blk = np.empty((ny, ny))
    for a in range(m):
        for b in range(m):
            for dk in range(-(n_periods - 1), n_periods):
                dx = (cxb[a] - cxb[b]) + dk * P
                hx = 0.5 * wxb[b]
                for i in range(ny):
                    for j in range(ny):
                        blk[i, j] = (
                            kk * rect_entry(dx, cy[i] - cy[j], hx, 0.5 * wy[j]) / (wxb[b] * wy[j])
                        )
                for l_ in range(n_periods):
                    k = l_ + dk
                    if k < 0 or k >= n_periods:
                        continue
                    r0 = (k * m + a) * ny
                    c0 = (l_ * m + b) * ny
                    for i in range(ny):
                        for j in range(ny):
                            C[r0 + i, c0 + j] = blk[i, j]
    return C


@njit
def _surface(shape, x, y, hx, hy, r, R, rx, ry, rz):
    """:meth:`Finger.surface` at one point."""
    if shape == 0:
        ex = max(abs(x) - hx, 0.0)
        ey = max(abs(y) - hy, 0.0)
        if r <= 0.0:
            return 0.0
        e = min(math.hypot(ex, ey), r)
        return r - math.sqrt(max(r * r - e * e, 0.0))
    if shape == 1:
        return R - math.sqrt(max(R * R - x * x - y * y, 0.0))
    return rz * (1.0 - math.sqrt(max(1.0 - (x / rx) ** 2 - (y / ry) ** 2, 0.0)))


@njit
def depths(off, x_pad, z_low, y0, cxr, cy, boxes, plate_half, pad, pen):
    """Each cell's penetration [m] (``pen``, -inf where no skin lies over it or no plate
    under it) with the lattice's first column at ``off + cxr`` in the pad frame, the pad at
    ``x_pad`` (its centre's x on the plate), its lowest point ``z_low`` above the base.
    ``boxes`` rows: (x, half x, y, half y, height); ``pad``: (shape, half patch x, half
    patch y, half flat x, half flat y, edge radius, R, rx, ry, rz)."""
    nc, ny = cxr.size, cy.size
    shape = int(pad[0])
    ex, ey = pad[1], pad[2]
    nb = boxes.shape[0]
    near = np.empty(nb, np.int64)
    for c in range(nc):
        x = off + cxr[c]
        wx = x_pad + x
        if abs(x) > ex or abs(wx) > plate_half[0]:
            for j in range(ny):
                pen[c * ny + j] = -np.inf
            continue
        cnt = 0
        for b in range(nb):
            if abs(wx - boxes[b, 0]) < boxes[b, 1]:
                near[cnt] = b
                cnt += 1
        for j in range(ny):
            y = cy[j]
            wy = y0 + y
            if abs(y) > ey or abs(wy) > plate_half[1]:
                pen[c * ny + j] = -np.inf
                continue
            h = 0.0
            for q in range(cnt):
                b = near[q]
                if abs(wy - boxes[b, 2]) < boxes[b, 3] and boxes[b, 4] > h:
                    h = boxes[b, 4]
            s = _surface(shape, x, y, pad[3], pad[4], pad[5], pad[6], pad[7], pad[8], pad[9])
            pen[c * ny + j] = h - z_low - s


@njit
def read_surface(off, cxr, wxr, ny, taxel_x, taxel_hx, oy, f, out):
    """Surface taxels' loads [N] (``out``): each cell's load ``f`` spread over the cell, read
    over the taxel's area: the x overlap of the cells at ``off + cxr`` (widths ``wxr``) with
    each taxel, times ``oy`` (taxels x rows: the rows' overlap fractions)."""
    nt = taxel_x.size
    for t in range(nt):
        lo, hi = taxel_x[t] - taxel_hx[t], taxel_x[t] + taxel_hx[t]
        acc = 0.0
        for c in range(cxr.size):
            x = off + cxr[c]
            h = 0.5 * wxr[c]
            o = min(x + h, hi) - max(x - h, lo)
            if o <= 0.0:
                continue
            s = 0.0
            for j in range(ny):
                s += oy[t, j] * f[c * ny + j]
            acc += o / wxr[c] * s
        out[t] = acc


def _compliance(cxb, wxb, P, n_periods, cy, wy, e_star) -> np.ndarray:
    """:func:`lattice_compliance`, kept in this process by content
    (:func:`~sim_tactile.cache.setup_memo`): every slide of a scene at one offset has the
    same lattice, and building it took 80 ms of a finger7 slide's 100 (read-only: the
    solve never writes it)."""
    parts = {
        "lattice": [array_digest(np.asarray(a, dtype=np.float64)) for a in (cxb, wxb, cy, wy)],
        "period": [float(P), int(n_periods)],
        "e_star": float(e_star),
    }
    compute = lambda: (lattice_compliance(cxb, wxb, P, n_periods, cy, wy, e_star),)  # noqa: E731
    return setup_memo("anchored lattice compliance", parts, compute, (__name__,))[0]


class AnchoredLattice:
    """The lattice of a pad on a plate (see the module docstring) and its contact solve:
    ``pitch_m`` the largest cell along the slide, ``pitch_y_m`` across it, ``wall_m`` the
    cells at a wall, ``y0_m`` the pad centre's y on the plate."""

    def __init__(
        self, finger, layout, plate: Plate, y0_m: float, pitch_m: float, pitch_y_m, wall_m: float
    ):
        check_anchorable(plate, layout)
        self.anchor, self.P, base = period_lines(plate, wall_m, pitch_m)
        self.m = base.size
        ends = np.append(base, self.P)
        cxb, wxb = 0.5 * (ends[:-1] + ends[1:]), np.diff(ends)
        ex = finger.patch_m[0]
        self.half_x = ex / 2
        #: periods in the window: the pad's extent starts within the first one
        self.n_periods = 1 + math.ceil(ex / self.P - 1e-12)
        k = np.arange(self.n_periods)
        self.cxr = (cxb[None, :] + k[:, None] * self.P).ravel()  # from the window's start
        self.wxr = np.tile(wxb, self.n_periods)
        by = row_lines(finger, layout, plate, y0_m, pitch_y_m or pitch_m)
        self.cy, self.wy = 0.5 * (by[:-1] + by[1:]), np.diff(by)
        self.ny = self.cy.size
        self.n = self.cxr.size * self.ny
        self.C = _compliance(cxb, wxb, self.P, self.n_periods, self.cy, self.wy, finger.e_star_pa)
        self.boxes = surface_of(plate).boxes
        self.plate_half = np.array([plate.length_m / 2, plate.width_m / 2])
        self.pad = self.pad_of(finger)
        self.y0 = y0_m
        pos, size = layout.positions, layout.sizes
        self.taxel_x = np.ascontiguousarray(pos[:, 0])
        self.taxel_hx = np.ascontiguousarray(size[:, 0] / 2)
        lo, hi = by[:-1], by[1:]
        ty0, ty1 = pos[:, 1] - size[:, 1] / 2, pos[:, 1] + size[:, 1] / 2
        ov = np.minimum(hi[None, :], ty1[:, None]) - np.maximum(lo[None, :], ty0[:, None])
        self.oy = np.ascontiguousarray(np.clip(ov, 0.0, None) / self.wy[None, :])
        # the contact set's state (ActiveSet's, numbered in the current window)
        blas_alone()  # its kernels multiply matrices
        self.window = None
        self.M = np.zeros((0, 0))
        self.S = np.zeros(0, np.int64)
        self.in_set = np.zeros(self.n, bool)
        self.updates = 0
        self.pen = np.empty(self.n)
        self.f = np.zeros(self.n)
        self._rowsum, self._rowsum_of = np.zeros(0), None

    @staticmethod
    def pad_of(finger) -> np.ndarray:
        """The pad as :func:`depths` reads it: (shape, half patch x, half patch y, half flat
        x, half flat y, edge radius, R, rx, ry, rz)."""
        ex, ey = finger.patch_m
        return np.array(
            [
                PAD_SHAPE_CODES[finger.shape],
                ex / 2,
                ey / 2,
                finger.size_m[0] / 2,
                finger.size_m[1] / 2,
                finger.edge_radius_m,
                finger.radius_m,
                *finger.radii_m,
            ],
            dtype=np.float64,
        )

    def _move_window(self, k: int) -> None:
        """Renumber the contact set for the window starting at period ``k``."""
        if self.window is not None and self.S.size:
            shift = (k - self.window) * self.m * self.ny
            S = self.S - shift
            if (S >= 0).all() and (S < self.n).all():
                self.S = S
                self.in_set[:] = False
                self.in_set[S] = True
            else:  # a cell of the set left the window: start the set afresh
                self.S = np.zeros(0, np.int64)
                self.M = np.zeros((0, 0))
                self.in_set[:] = False
                self.updates = 0
        self.window = k

    def offset(self, x_pad: float) -> float:
        """The window's first column's start in the pad frame [m] for the pad at ``x_pad``
        (moving the window when the pad has crossed a period)."""
        k = math.floor((x_pad - self.half_x - self.anchor) / self.P)
        if k != self.window:
            self._move_window(k)
        return self.anchor + k * self.P - x_pad

    def solve(self, x_pad: float, z_low: float, force_n: float) -> tuple[float, float]:
        """The contact carrying ``force_n`` [N] with the pad at ``x_pad``, its lowest point
        first ``z_low`` [m] above the plate's base: ``(dz, off)``, how far the pad moved down
        [m] and the window's offset; the cells' loads [N] are in ``f``, their
        penetrations at the new height in ``pen``."""
        off = self.offset(x_pad)
        pen, f = self.pen, self.f
        depths(
            off,
            x_pad,
            z_low,
            self.y0,
            self.cxr,
            self.cy,
            self.boxes,
            self.plate_half,
            self.pad,
            pen,
        )
        dz = np.nan
        if self.S.size:
            if self._rowsum_of is not self.M:
                self._rowsum, self._rowsum_of = self.M.sum(axis=1), self.M
            dz = force_same_set(
                self.M, self.S, pen, self.C, self.in_set, TOL_REL, force_n, f, self._rowsum, 0.0
            )
        if dz != dz:
            st, dz, M, S, updates, _ = force_loop(
                self.M,
                self.S,
                self.in_set,
                self.C,
                NO_K,
                pen,
                TOL_REL,
                force_n,
                self.updates,
                REFRESH,
                MAX_ITER,
                f,
                False,
                0.0,
                False,
                NO_SUMS,  # the set is renumbered as the window moves: no running sums
            )
            if st == 2:
                raise PhysicsError("no cell of the anchored lattice lies over the plate")
            if st != 1:
                raise PhysicsError(
                    f"the anchored lattice's contact solve did not converge in {MAX_ITER} "
                    f"iterations (target {force_n:.4g} N)"
                )
            self.M, self.S, self.updates = M, S, updates
        pen += dz
        return float(dz), off

    def taxel_loads(self, off: float, out: np.ndarray) -> np.ndarray:
        """The surface taxels' loads [N] of the last solve."""
        read_surface(
            off, self.cxr, self.wxr, self.ny, self.taxel_x, self.taxel_hx, self.oy, self.f, out
        )
        return out
