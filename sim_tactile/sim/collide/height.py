"""The collider of the sampled plates: each skin node's depth below the plate's surface at
its centre, in one compiled loop (:func:`surface_depths`) over the surface's arrays
(:attr:`~sim_tactile.plates.define.surface.Surface.arrays`), whose class says which surface it is:

- a rough plate (:class:`~sim_tactile.plates.define.surface.ProfileArrays`): a profile z(x)
  (linear between its samples) across its textured area, on its base. MuJoCo's height-field
  collider gave about four contacts per node there (26 160 for the iCub's 6231 nodes on
  rough-ra100), filled its contact buffer and stopped the slide, and it measured each
  sphere's distance to the nearest facet, where the skin model and the reference it is
  measured against take the height map's depth;
- a height map (:class:`~sim_tactile.plates.define.surface.MapArrays`): heights sampled on a grid
  over (at least) the textured area, bilinear between them, NaN where there is no material,
  on its base. MuJoCo's height-field collider had served it: several contacts a node, at
  most 50 a pair.

Each point's height (:func:`surface_in_row`, a rough plate's profile read once for each x a run
of nodes shares: :func:`surface_row`) is the surface's own numpy height
(:meth:`~sim_tactile.plates.define.surface.Surface.height`) bit for bit (tested): the one compiled
copy of it. :mod:`~sim_tactile.sim.collide.choose` chooses the collider.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from typing import NamedTuple

import numpy as np

from ..._jit import njit, when_numba
from ...cache import register_memo
from ...hashing import array_digest
from ...plates.define.surface import MapArrays, ProfileArrays, Surface, surface_of

#: What :meth:`SurfaceCollider.kept` keeps, by the surface (its id: each entry holds the
#: surface itself, so the id is not reused while it is kept) and the digest of the nodes:
#: ``(surface, {key: value})``, the most recently used last.
KEPT: OrderedDict[tuple, tuple] = OrderedDict()
#: Most surfaces and node sets :data:`KEPT` holds, and most values each holds (as a primitive
#: collider holds: :func:`kept_value`).
KEPT_MAX, KEPT_VALUES = 8, 16
register_memo("surface colliders' kept values", KEPT.clear)


def kept_value(values: dict, key, build):
    """``values[key]``, else ``build()``, kept there while ``values`` holds fewer than
    :data:`KEPT_VALUES` (what a collider keeps for the slides that share it)."""
    hit = values.get(key)
    if hit is None:
        hit = build()
        if len(values) < KEPT_VALUES:
            values[key] = hit
    return hit


class SurfaceProbe(NamedTuple):
    """What :func:`surface_depths` reads: the probe spheres' centres ``local`` (N, 3) in the
    bone's frame, their ``radius`` and ``margin`` (N,) [m], the surface's arrays, and the
    order in which the loop visits the probes (by their x: :func:`x_order`)."""

    local: np.ndarray
    radius: np.ndarray
    margin: np.ndarray
    surface: ProfileArrays | MapArrays
    order: np.ndarray


def x_order(local: np.ndarray) -> np.ndarray:
    """The probes' indices in the order of their x (stable: a run of one x keeps its order),
    so that :func:`surface_depths` meets each x in one run: a full grid lists its nodes row by
    row (the iCub's 6231 at 93 x values), the held step's columns come sorted already."""
    return np.argsort(local[:, 0], kind="stable").astype(np.int64)


class SurfaceCollider:
    """The skin's probe spheres (centres ``local`` in the bone's frame, ``radius``,
    ``margin``) against a sampled plate's ``surface`` (one with
    :attr:`~sim_tactile.plates.define.surface.Surface.arrays`), bound to the finger's joints
    (:meth:`bind`). A node's depth is the surface height at its centre less its lowest point,
    reported (else -inf) within its margin, as MuJoCo reports a contact; where the surface is
    NaN (off the plate, no material) nothing is near."""

    #: the held step may run it in one compiled call
    #: (:class:`~sim_tactile.sim.step.held.CompiledHeldStep`, through ``probe``)
    compiled = True

    def __init__(self, local, radius, margin, surf: Surface) -> None:
        self.local, self.radius, self.margin = local, radius, margin
        self.surface = surf
        #: the depth kernel's arguments after the bone's position
        self.probe = SurfaceProbe(local, radius, margin, surf.arrays, x_order(local))
        self._x = np.empty(len(local))
        self._y = np.empty(len(local))
        self._z = np.empty(len(local))

    @classmethod
    def from_scene(cls, scene) -> SurfaceCollider | None:
        """The collider of a scene whose plate's surface is sampled, bound to the finger's
        joints, or None (a plate of features; skin nodes rotated on the bone)."""
        surf = surface_of(scene.plate)
        if surf.arrays is None:
            return None
        m = scene.m_col
        bone = m.body("bone").id
        nodes = np.flatnonzero(scene.node_of_geom >= 0)
        nodes = nodes[np.argsort(scene.node_of_geom[nodes])]
        if not np.allclose(m.geom_quat[nodes], [1, 0, 0, 0]) or not np.allclose(
            m.body_quat[bone], [1, 0, 0, 0]
        ):
            return None
        c = cls(
            m.geom_pos[nodes].copy(),
            m.geom_size[nodes, 0].copy(),
            m.geom_margin[nodes].copy(),
            surf,
        )
        c.bind(m.body_pos[bone], scene.jx, scene.jz)
        return c

    def bind(self, bone0: np.ndarray, jx: int, jz: int) -> None:
        """Read the bone's world position as ``bone0 + (qpos[jx], 0, qpos[jz])``."""
        self.bone0 = np.array(bone0, dtype=np.float64)
        self.jx, self.jz = int(jx), int(jz)
        self._bone = self.bone0.copy()

    def kept(self, key, build):
        """``build()``, kept under ``key`` for every collider of this surface and these
        nodes (by their content: each slide's scene makes a collider of its own): what is
        computed from the nodes and the surface alone, never from a pose (a held step's
        reduced probes, 0.5 ms of each PVDF slide on a rough plate). ``key`` holds whatever
        else ``build`` reads."""
        ident = (id(self.surface), array_digest(self.local, self.radius, self.margin))
        entry = KEPT.get(ident)
        if entry is None or entry[0] is not self.surface:
            entry = KEPT[ident] = (self.surface, {})
            while len(KEPT) > KEPT_MAX:
                KEPT.popitem(last=False)
        else:
            KEPT.move_to_end(ident)
        return kept_value(entry[1], key, build)

    def subset(self, nodes: np.ndarray) -> SurfaceCollider:
        """The same collider for the nodes ``nodes`` only (their order), bound alike."""
        c = SurfaceCollider(self.local[nodes], self.radius[nodes], self.margin[nodes], self.surface)
        if hasattr(self, "bone0"):
            c.bind(self.bone0, self.jx, self.jz)
        return c

    def y_invariant(self, bone_y: float) -> bool:
        """Whether every node's depth is independent of its y for the bone at ``bone_y``
        (:meth:`~sim_tactile.plates.define.surface.Surface.y_invariant` at the nodes): then nodes
        with equal x, z, radius and margin get bit-identical depths."""
        return self.surface.y_invariant(bone_y + self.local[:, 1])

    def depths_at(self, qpos: np.ndarray, pen: np.ndarray) -> bool:
        """Fill ``pen`` with each node's depth [m] for the joints at ``qpos``; whether any
        node is within its margin of the plate. One compiled loop, the same numbers as
        :meth:`depths_numpy` bit for bit (tested)."""
        b = self._bone
        b[0] = self.bone0[0] + qpos[self.jx]
        b[2] = self.bone0[2] + qpos[self.jz]
        return surface_depths(b, *self.probe, pen)

    def depths_numpy(self, qpos: np.ndarray, pen: np.ndarray) -> bool:
        """:meth:`depths_at` in numpy, on the surface's own height: the reference of the
        compiled loop."""
        np.add(self.bone0[0] + qpos[self.jx], self.local[:, 0], out=self._x)
        np.add(self.bone0[1], self.local[:, 1], out=self._y)
        np.add(self.bone0[2] + qpos[self.jz], self.local[:, 2], out=self._z)
        d = self.surface.height(self._x, self._y) - (self._z - self.radius)
        near = d >= -self.margin  # NaN (off the plate, no material) is not near
        pen[:] = np.where(near, d, -np.inf)
        return bool(near.any())

    def warnings(self) -> list[str]:
        return []


@njit
def interp_at(q, xp, fp, left, right):
    """``np.interp(q, xp, fp, left, right)`` at one point, with numpy's arithmetic (the same
    number bit for bit, tested): the knot found by bisection, the slope between its
    neighbours, and numpy's care for exact knots and non-finite slopes."""
    n = xp.size
    if np.isnan(q):
        return q
    if q < xp[0]:
        return left
    if q > xp[n - 1]:
        return right
    j = np.searchsorted(xp, q, side="right") - 1
    if j == n - 1 or xp[j] == q:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    v = slope * (q - xp[j]) + fp[j]
    if np.isnan(v):
        v = slope * (q - xp[j + 1]) + fp[j + 1]
        if np.isnan(v) and fp[j] == fp[j + 1]:
            v = fp[j]
    return v


@njit
def map_height_at(x, y, z, pixel):
    """:func:`~sim_tactile.plates.define.surface.map_height` at one point, in its operation order
    (the same number bit for bit, tested): the cell by ``floor``, clipped to the map's edge
    cells, and the bilinear blend of its corners, along x first."""
    ny, nx = z.shape
    fx = (x + (nx - 1) * pixel / 2) / pixel
    fy = (y + (ny - 1) * pixel / 2) / pixel
    j = min(max(math.floor(fx), 0), nx - 2)
    i = min(max(math.floor(fy), 0), ny - 2)
    tx = fx - j
    ty = fy - i
    lower = (1 - tx) * z[i, j] + tx * z[i, j + 1]
    upper = (1 - tx) * z[i + 1, j] + tx * z[i + 1, j + 1]
    return (1 - ty) * lower + ty * upper


@njit
def map_surface_at(x, y, z, pixel, ax, ay, sx, sy):
    """A height-map plate's surface height at (x, y), as
    :meth:`MapSurface.height <sim_tactile.plates.define.surface.Surface.height>` gives it: the map
    over its span ``|x| <= ax, |y| <= ay`` (NaN where it holds no material), the base (0)
    elsewhere on the plate, NaN beyond ``sx, sy``."""
    if abs(x) > sx or abs(y) > sy:
        return np.nan
    if abs(x) <= ax and abs(y) <= ay:
        return map_height_at(x, y, z, pixel)
    return 0.0


def surface_row(x, s):
    """What the height at x shares along y (compiled code only): a rough plate's profile
    value at ``x`` (:func:`interp_at`: linear between its samples), which
    :func:`profile_in_row` reads across the textured area; nothing for a height map (0.0,
    unread)."""
    raise NotImplementedError("surface_row runs in compiled code only")


def surface_in_row(x, y, row, s):
    """The surface's height at (x, y), as
    :meth:`~sim_tactile.plates.define.surface.Surface.height` gives it, given
    :func:`surface_row`'s ``row`` at ``x`` (compiled code only; its implementation is chosen
    by the class of ``s``)."""
    raise NotImplementedError("surface_in_row runs in compiled code only")


@njit
def profile_in_row(x, y, row, ax, ay, sx, sy):
    """A rough plate's surface height at (x, y), as
    :meth:`ProfileSurface.height <sim_tactile.plates.define.surface.Surface.height>` gives it,
    given its profile's value at ``x`` (``row``): the profile over the textured area
    ``|x| <= ax, |y| <= ay``, the base (0) elsewhere on the plate, NaN beyond ``sx, sy``."""
    if abs(x) > sx or abs(y) > sy:
        return np.nan
    if abs(x) <= ax and abs(y) <= ay:
        return row
    return 0.0


def _surface_row(x, s):
    kind = getattr(s, "instance_class", None)
    if kind is ProfileArrays:
        return lambda x, s: interp_at(x, s.px, s.pz, s.pz[0], s.pz[s.pz.size - 1])
    if kind is MapArrays:
        return lambda x, s: 0.0
    return None


def _surface_in_row(x, y, row, s):
    kind = getattr(s, "instance_class", None)
    if kind is ProfileArrays:
        return lambda x, y, row, s: profile_in_row(x, y, row, s.ax, s.ay, s.sx, s.sy)
    if kind is MapArrays:
        return lambda x, y, row, s: map_surface_at(x, y, s.z, s.pixel, s.ax, s.ay, s.sx, s.sy)
    return None


@when_numba
def _register(numba) -> None:
    """The compiled implementations of :func:`surface_row` and :func:`surface_in_row`."""
    from numba.extending import overload

    overload(surface_row)(_surface_row)
    overload(surface_in_row)(_surface_in_row)


@njit
def surface_depths(bone, local, radius, margin, arrays, order, pen):
    """:meth:`SurfaceCollider.depths_numpy` in one loop for the bone at world position
    ``bone`` (3,): each node's depth below the surface (its ``arrays``) at its centre within
    its margin, else -inf (and where the surface is NaN); whether any is near. The nodes are
    visited in ``order`` (by x, :func:`x_order`), and a rough plate's profile is read once
    for each run of nodes at one x (:func:`surface_row`): its search was half of a
    ``pvdf2`` held step (27 x values among 378 probes), a tenth of an iCub step on a rough
    strip (93 among 6231 nodes)."""
    near = False
    last_x = np.nan  # no x equals it: the first node reads its row
    row = 0.0
    for k in range(order.shape[0]):
        i = order[k]
        x = bone[0] + local[i, 0]
        if x != last_x:
            row = surface_row(x, arrays)
            last_x = x
        h = surface_in_row(x, bone[1] + local[i, 1], row, arrays)
        near |= report_depth(pen, i, h - ((bone[2] + local[i, 2]) - radius[i]), margin[i])
    return near


@njit(inline="always")
def report_depth(pen, i, depth, margin):
    """Node ``i``'s depth into ``pen`` if it is within its margin (else -inf); whether it is.
    A NaN depth (no surface) is not within it."""
    if depth >= -margin:
        pen[i] = depth
        return True
    pen[i] = -np.inf
    return False
