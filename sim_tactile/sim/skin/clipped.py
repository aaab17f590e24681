"""Node patches clipped at the plate's walls and the taxels' edges.

A node of the lattice carries a uniform pressure over its rectangular patch and probes the
plate at the patch's centre. Where a rigid box's vertical wall or a taxel's edge runs through
a patch, that is wrong in two ways that grow with the pitch, not with the physics:

- the patch is in contact or not as a whole, by its centre, so the box's top is a whole
  number of patches wide and jumps by a patch as a wall crosses a centre;
- under a rigid flat top the pressure is singular at the wall (as at a flat punch's edge:
  it grows as the inverse square root of the distance), so the patch at the wall carries a
  large share of the load; where a taxel's edge cuts that patch, the taxel reads a share of
  it by area, but the load sits at the wall.

Here the patches are cut along every line where the plate's height or the taxel reading
jumps, so that no patch straddles either:

- **static lines** (in the pad's frame, for the whole slide): the lattice's own lines, the
  taxels' edges, and the walls of the plate's boxes that run along the slide (the pad does
  not move across it);
- **moving lines**: the walls of the plate's boxes across the slide, at the pad's position
  of the step.

The patches are the tensor product of the columns and rows these lines make. Each is in
contact or not by its centre, and is wholly inside a taxel or outside it. Their compliance is
Love's rectangle solution with each patch's own size (:func:`rect_compliance`), assembled at
each step for the patches that may touch, and the contact under force control is solved
exactly on them (:func:`hold_force`). A taxel reads a patch's load with the weights of the
static cell it lies in (their overlap at the surface, Boussinesq's stress below it).

Against Tamaas on ``finger7/bumps-4x4`` (grid3x3, 1 N, four offsets), the taxel loads of the
1 mm lattice move from 100% (whole patches) to a few per cent of the reference
(``docs/physics.md``). It serves the elastic half-space skin (L1); a layered stack or a
friction-coupled skin keeps whole patches.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import njit
from ...errors import PhysicsError
from ...plates.define.spec import Plate
from ...plates.define.surface import surface_of
from ...scene.elastic import subsurface_weights
from ...scene.nodes import SkinGrid
from ..plan.lattices import merge_lines, static_lines
from .contact import MAX_ITER, TOL_REL

#: The patches within this of the deepest one (or of touching) enter the solve; when the
#: pad then moves further, the reach grows and the solve runs again [m].
REACH_M = 2e-5
#: Times the reach may grow in one solve before it gives up (the pad falling through).
MAX_REACHES = 50
#: Factorisations kept between steps for the same patches (the sets one step visits).
MAX_FACTORS = 8


@njit
def _F(x, y):
    ax, ay = abs(x), abs(y)
    a = 0.0 if ax == 0.0 else x * math.asinh(y / ax)
    b = 0.0 if ay == 0.0 else y * math.asinh(x / ay)
    return a + b


@njit
def rect_entry(x, y, a, b):
    """The deflection at offset (x, y) from the centre of a rectangle of half-sides ``a``,
    ``b`` under unit pressure, times pi E* (Love 1929)."""
    return _F(x + a, y + b) - _F(x - a, y + b) - _F(x + a, y - b) + _F(x - a, y - b)


@njit
def assemble(cx, cy, hx, hy, cell, split, C_cells, e_star):
    """:func:`rect_compliance` of the patches, taking the entry between two patches that
    are whole static cells (``split`` False) from ``C_cells`` (the static cells'
    compliance) and computing the rest."""
    n = cx.size
    C = np.empty((n, n))
    k = 1.0 / (math.pi * e_star)
    for i in range(n):
        for j in range(n):
            if split[i] or split[j]:
                C[i, j] = k * rect_entry(cx[i] - cx[j], cy[i] - cy[j], hx[j], hy[j])
            else:
                C[i, j] = C_cells[cell[i], cell[j]]
    return C


@njit
def rect_compliance(cx, cy, hx, hy, e_star):
    """(n, n) surface compliance [m/Pa]: the deflection at patch i's centre per unit pressure
    on patch j, a rectangle of half-sides ``hx[j]``, ``hy[j]`` centred at (``cx[j]``,
    ``cy[j]``), on a half-space of plane-strain modulus ``e_star`` (Love 1929; the same
    closed form as :func:`~sim_tactile.scene.elastic.compliance_matrix`, per patch)."""
    n = cx.size
    C = np.empty((n, n))
    k = 1.0 / (math.pi * e_star)
    for i in range(n):
        for j in range(n):
            x = cx[i] - cx[j]
            y = cy[i] - cy[j]
            C[i, j] = k * rect_entry(x, y, hx[j], hy[j])
    return C


def hold_force(
    g: np.ndarray, area: np.ndarray, C: np.ndarray, force_n: float, start=None, factors=None
):
    """The exact frictionless contact of patches with gaps ``-g`` (``g`` > 0: penetration at
    the pad's present height) [m], areas ``area`` [m^2] and compliance ``C``, the pad moved by
    ``d`` so that the pressures carry ``force_n``: ``(p [Pa], d [m], in_contact)``.

    Active set on the augmented system ``C_SS p_S - d = g_S``, ``area_S . p_S = force_n``:
    patches pulled into tension leave it, patches that the deformed skin would penetrate
    join it, until neither happens. ``start``: the first set (a boolean mask). ``factors``: a
    dict in which the factorisations of the sets are kept for the next call with the same
    ``C`` (a pad on flat ground solves the same system every step)."""
    # scipy.linalg is loaded where a clipped problem is solved, not with the skins that import
    # this module (0.16 s of every command's start-up)
    from scipy.linalg import lu_factor, lu_solve

    n = g.size
    S = (
        np.flatnonzero(start)
        if start is not None and start.any()
        else np.array([int(np.argmax(g))])
    )
    tol = TOL_REL * max(float(np.abs(g).max()), 1e-9)
    for _ in range(MAX_ITER):
        m = S.size
        key = S.tobytes()
        lu = None if factors is None else factors.get(key)
        if lu is None:
            A = np.empty((m + 1, m + 1))
            A[:m, :m] = C[np.ix_(S, S)]
            A[:m, m] = -1.0
            A[m, :m] = area[S]
            A[m, m] = 0.0
            lu = lu_factor(A, check_finite=False)
            if factors is not None:
                if len(factors) >= MAX_FACTORS:
                    factors.clear()
                factors[key] = lu
        sol = lu_solve(lu, np.append(g[S], force_n), check_finite=False)
        pS, d = sol[:m], float(sol[m])
        if (pS < 0).any():
            S = S[pS >= 0] if (pS >= 0).any() else S[[int(np.argmax(pS))]]
            continue
        mask = np.zeros(n, bool)
        mask[S] = True
        rest = np.flatnonzero(~mask)
        if rest.size:
            over = g[rest] + d - C[np.ix_(rest, S)] @ pS
            add = rest[over > tol]
            if add.size:
                S = np.sort(np.concatenate([S, add]))
                continue
        p = np.zeros(n)
        p[S] = pS
        return p, d, mask
    raise PhysicsError(
        f"clipped contact solve did not converge in {MAX_ITER} iterations ({n} patches)"
    )


class ClippedPatches:
    """The static cells of a pad on a plate (see the module docstring) and the patches of any
    pad position: ``grid`` the lattice, ``layout`` the taxels (their edges cut it), ``y0_m``
    the pad centre's y on the plate [m]."""

    def __init__(self, grid: SkinGrid, finger, layout, plate: Plate, y0_m: float):
        self.sx, self.sy = static_lines(grid, layout, plate, y0_m)
        self.surface = surface_of(plate)
        self.walls_x, _ = self.surface.walls
        pos, size = layout.positions[:, :2], layout.sizes
        bx = self.sx
        self.lo, self.hi = bx[0], bx[-1]
        self.half_x = max(-bx[0], bx[-1])
        self.plate, self.finger, self.y0 = plate, finger, y0_m
        self.e_star = finger.e_star_pa
        # the static cells and the weights with which the taxels read them
        cx, cy = _centres(self.sx), _centres(self.sy)
        wx, wy = np.diff(self.sx), np.diff(self.sy)
        self.cy, self.wy = cy, wy
        ny, nx = cy.size, cx.size
        Wc = np.zeros((layout.n, ny * nx))
        # cells of the same size share one call
        CX, CY = np.meshgrid(cx, cy)
        WX, WY = np.meshgrid(wx, wy)
        sizes = np.round(np.column_stack([WX.ravel(), WY.ravel()]), 12)
        for s in np.unique(sizes, axis=0):
            sel = np.flatnonzero((sizes == s).all(axis=1))
            xy = np.column_stack([CX.ravel()[sel], CY.ravel()[sel]])
            Wc[:, sel] = subsurface_weights(
                xy, float(s[0]), pos, size, layout.depth_m, pitch_y_m=float(s[1])
            )
        self._last, self._C, self._factors = None, None, {}  # the last solve's patches
        self.deepest = -np.inf  # the last solve's deepest patch [m]
        self.W_cells = Wc  # (taxels, ny * nx): per unit load of the static cell
        self.nx_static = nx
        # the static cells' compliance: the entries between patches that are whole cells
        self.C_cells = rect_compliance(
            CX.ravel(), CY.ravel(), WX.ravel() / 2, WY.ravel() / 2, self.e_star
        )

    def columns(self, x_pad: float) -> tuple[np.ndarray, np.ndarray]:
        """The column lines with the cross walls at pad position ``x_pad`` (the pad centre's
        x on the plate) added, and each column's static column."""
        ex = merge_lines(self.sx, self.walls_x - x_pad, self.lo, self.hi)
        parent = np.searchsorted(self.sx, _centres(ex)) - 1
        return ex, parent

    def _split(self, ex: np.ndarray, parent: np.ndarray) -> np.ndarray:
        """Which columns are parts of their static column (a wall runs through it)."""
        return (ex[:-1] != self.sx[parent]) | (ex[1:] != self.sx[parent + 1])

    def patches(self, x_pad: float):
        """``(cx, cy, hx, hy, cell, split)``: every patch's centre [m] in the pad frame,
        half-sides [m], static cell, and whether it is a part of that cell, row-major over
        (rows, columns)."""
        ex, parent = self.columns(x_pad)
        split = self._split(ex, parent)
        cxs, hxs = _centres(ex), np.diff(ex) / 2
        ny, nx = self.cy.size, cxs.size
        cx = np.tile(cxs, ny)
        hx = np.tile(hxs, ny)
        cy = np.repeat(self.cy, nx)
        hy = np.repeat(self.wy / 2, nx)
        cell = (np.repeat(np.arange(ny), nx) * self.nx_static + np.tile(parent, ny)).astype(
            np.int64
        )
        return cx, cy, hx, hy, cell, np.tile(split, ny)

    def heights(self, x_pad: float, cx, cy) -> np.ndarray:
        """The plate's height above the base less the pad's undeformed surface, at the patch
        centres [m]: a patch's penetration with the pad's lowest point at z is this less z."""
        x, y = cx + x_pad, cy + self.y0
        # the surface near the pad (on a plate of features, the features within its reach)
        z = self.surface.height(x, y, near=(x_pad, self.half_x))
        return np.where(np.isfinite(z), z, -np.inf) - self.finger.surface(cx, cy)

    def solve(self, x_pad: float, z_low: float, force_n: float):
        """The contact carrying ``force_n`` [N] with the pad at ``x_pad`` (its centre's x on
        the plate), its lowest point first ``z_low`` [m] above the plate's base: ``(patches,
        cand, p, d)``: the patches (:meth:`patches`), the indices of those that may touch,
        their pressures [Pa], and how far the pad moved down [m]."""
        cx, cy, hx, hy, cell, split = pt = self.patches(x_pad)
        g = self.heights(x_pad, cx, cy) - z_low
        area = 4 * hx * hy
        reach = REACH_M
        for _ in range(MAX_REACHES):
            c = np.flatnonzero(g > min(-reach, float(g.max()) - reach))
            # the same patches as the last solve: the same compliance and factorisations
            key = (c.size, cx[c].tobytes(), cy[c].tobytes(), hx[c].tobytes(), hy[c].tobytes())
            if key != self._last:
                self._C = assemble(
                    cx[c], cy[c], hx[c], hy[c], cell[c], split[c], self.C_cells, self.e_star
                )
                self._last, self._factors = key, {}
            gc = g[c]
            p, d, _ = hold_force(gc, area[c], self._C, force_n, gc > 0, self._factors)
            out = np.ones(g.size, bool)
            out[c] = False
            if not (g[out] + d > 0).any():  # no patch left out would touch at the new height
                self.deepest = float(gc.max()) + d
                return pt, c, p, d
            reach = max(2 * reach, d + REACH_M)
        raise PhysicsError(f"clipped contact: no height of the pad carries {force_n:g} N")

    def taxel_loads(self, cell: np.ndarray, loads: np.ndarray, out=None) -> np.ndarray:
        """The taxel loads [N] of patch loads [N] in static cells ``cell``."""
        return np.matmul(self.W_cells[:, cell], loads, out=out)


def _centres(lines: np.ndarray) -> np.ndarray:
    return 0.5 * (lines[:-1] + lines[1:])
