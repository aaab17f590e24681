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
from scipy.linalg import lu_factor, lu_solve

from .._jit import njit
from ..errors import ConfigError, PhysicsError
from ..plates import Plate, features, height_at
from ..scene.elastic import subsurface_weights
from ..scene.nodes import SkinGrid

#: Lines closer than this to one already there are not added [m]: a patch thinner than it
#: carries nothing a taxel could tell apart.
MERGE_M = 1e-7
#: A patch joins the contact when the deformed skin would penetrate it by more than this,
#: relative to the largest gap (the whole-patch solver's tolerance).
TOL_REL = 1e-9
#: Active-set iterations one force-holding solve may take.
MAX_ITER = 200
#: The patches within this of the deepest one (or of touching) enter the solve; when the
#: pad then moves further, the reach grows and the solve runs again [m].
REACH_M = 2e-5
#: Times the reach may grow in one solve before it gives up (the pad falling through).
MAX_REACHES = 50
#: Factorisations kept between steps for the same patches (the sets one step visits).
MAX_FACTORS = 8


def wall_lines(plate: Plate) -> tuple[np.ndarray, np.ndarray]:
    """The plate frame's x positions of the vertical walls across the slide, and y positions
    of those along it [m]: the faces of its boxes (ridges, bumps, grating bars)."""
    xs, ys = set(), set()
    for f in features(plate):  # none on a rough plate or a height map
        if f.kind == "box":
            xs.update((round(f.x - f.hx, 12), round(f.x + f.hx, 12)))
            ys.update((round(f.y - f.hy, 12), round(f.y + f.hy, 12)))
    return np.array(sorted(xs)), np.array(sorted(ys))


def has_walls(plate: Plate) -> bool:
    """Whether the plate has box walls that clipping would follow."""
    xs, _ = wall_lines(plate)
    return xs.size > 0


def static_lines(grid: SkinGrid, layout, plate: Plate, y0_m: float):
    """The static column and row lines [m] in the pad's frame: the lattice's own, the taxels'
    edges, and (rows) the walls along the slide with the pad centred at ``y0_m`` on the
    plate."""
    px, py = grid.pitch_xy
    xs, ys = np.unique(grid.xy[:, 0]), np.unique(grid.xy[:, 1])
    bx = np.append(xs - px / 2, xs[-1] + px / 2)
    by = np.append(ys - py / 2, ys[-1] + py / 2)
    pos, size = layout.positions[:, :2], layout.sizes
    tx = np.concatenate([pos[:, 0] - size[:, 0] / 2, pos[:, 0] + size[:, 0] / 2])
    ty = np.concatenate([pos[:, 1] - size[:, 1] / 2, pos[:, 1] + size[:, 1] / 2])
    _, walls_y = wall_lines(plate)
    return _merge(bx, tx, bx[0], bx[-1]), _merge(
        by, np.concatenate([ty, walls_y - y0_m]), by[0], by[-1]
    )


def static_cells(grid: SkinGrid, layout, plate: Plate, y0_m: float) -> int:
    """How many static cells the clipped grid has (:func:`static_lines`)."""
    sx, sy = static_lines(grid, layout, plate, y0_m)
    return (sx.size - 1) * (sy.size - 1)


def _merge(base: np.ndarray, extra, lo: float, hi: float) -> np.ndarray:
    """``base`` (sorted) with the lines of ``extra`` strictly inside (lo, hi) that are not
    within :data:`MERGE_M` of a line already there."""
    out = list(base)
    for e in sorted(extra):
        if not lo + MERGE_M < e < hi - MERGE_M:
            continue
        i = np.searchsorted(out, e)
        if (i < len(out) and out[i] - e < MERGE_M) or (i > 0 and e - out[i - 1] < MERGE_M):
            continue
        out.insert(i, e)
    return np.array(out)


@njit
def _F(x, y):
    ax, ay = abs(x), abs(y)
    a = 0.0 if ax == 0.0 else x * math.asinh(y / ax)
    b = 0.0 if ay == 0.0 else y * math.asinh(x / ay)
    return a + b


@njit
def _entry(x, y, a, b):
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
                C[i, j] = k * _entry(cx[i] - cx[j], cy[i] - cy[j], hx[j], hy[j])
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
            C[i, j] = k * _entry(x, y, hx[j], hy[j])
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
        self.walls_x, _ = wall_lines(plate)
        pos, size = layout.positions[:, :2], layout.sizes
        bx = self.sx
        self.lo, self.hi = bx[0], bx[-1]
        self.half_x = max(-bx[0], bx[-1])
        sampled = plate.texture.kind in ("roughness", "heightmap")  # no features: its samples
        fs = None if sampled else features(plate)
        self._feats = fs
        self._fx = None if fs is None else np.array([f.x for f in fs])
        self._fhx = None if fs is None else np.array([f.hx for f in fs])
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
        ex = _merge(self.sx, self.walls_x - x_pad, self.lo, self.hi)
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
        if self._feats is None:  # rough, a height map: the plate's own function
            z = height_at(self.plate, x, y)
        else:  # the features within the pad's reach (height_at over all of them, faster)
            z = np.zeros(x.shape)
            near = np.abs(self._fx - x_pad) <= self._fhx + self.half_x
            for k in np.flatnonzero(near):
                np.maximum(z, self._feats[k].height(x, y), out=z)
            p = self.plate
            z[(np.abs(x) > p.length_m / 2) | (np.abs(y) > p.width_m / 2)] = -np.inf
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


class PlateHeldStep:
    """The frame of a held step (``step(qpos, jz, total, taxel_out) -> (force, deepest)``, as
    :class:`~sim_tactile.sim.held.HeldStep`) that solves on cells of the plate's own: the
    pad's position on the plate is ``x0 + qpos[jx]``, its lowest point ``z0 + qpos[jz]``
    above the base; ``c`` the cells' solver, ``area`` the pad lattice's node area (the
    total it is given is a pressure summed over those nodes)."""

    def __init__(self, cells, base_area_m2: float, x0: float, z0: float, jx: int):
        self.c = cells
        self.area = base_area_m2
        self.x0, self.z0, self.jx = x0, z0, jx

    def pose(self, qpos, jz) -> tuple[float, float]:
        """``(x_pad, z_low)``: the pad centre's x on the plate and its lowest point's height
        above the base [m]."""
        return self.x0 + float(qpos[self.jx]), self.z0 + float(qpos[jz])


class ClippedHeldStep(PlateHeldStep):
    """The held step on clipped patches (:class:`ClippedPatches`)."""

    def describe(self) -> str:
        return (
            f"patches clipped at the walls and taxel edges ({self.c.sy.size - 1} rows, "
            f"{self.c.sx.size - 1} static columns)"
        )

    def step(self, qpos, jz, total, taxel_out) -> tuple[float, float]:
        x_pad, z_low = self.pose(qpos, jz)
        (cx, cy, hx, hy, cell, _), cand, p, d = self.c.solve(x_pad, z_low, total * self.area)
        qpos[jz] -= d
        loads = p * (4 * hx[cand] * hy[cand])
        self.c.taxel_loads(cell[cand], loads, out=taxel_out)
        return float(loads.sum()), self.c.deepest


def skin_refusals(level: str, finger=None, quasi_static: bool = True) -> list[str]:
    """What keeps a held step on the plate's own cells (clipped patches, the anchored lattice)
    from serving this skin: a level other than L1, a layered stack, friction coupled into the
    normal problem, dynamic force control. Empty when it serves it; ``finger`` None skips the
    finger's checks."""
    why = []
    if level != "L1":
        why.append(f"level {level!r} (valid: 'L1')")
    if finger is not None and finger.stack is not None:
        why.append("a layered stack")
    if finger is not None and finger.skin_tractions and finger.friction > 0:
        why.append("the skin's sliding tractions (skin_tractions)")
    if not quasi_static:
        why.append("dynamic force control (valid: 'quasi-static')")
    return why


def check_clippable(level: str, finger, quasi_static: bool = True) -> None:
    """Raise unless clipped patches serve this skin: the elastic half-space of L1, without a
    layered stack or friction coupled into the normal problem, under quasi-static force
    control (the held step)."""
    why = skin_refusals(level, finger, quasi_static)
    if why:
        raise ConfigError(
            "clipped patches serve the half-space skin of L1 under quasi-static force control; "
            "got " + ", ".join(why)
        )
