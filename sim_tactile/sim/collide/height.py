"""The height-map colliders of the sampled plates: each skin node's depth below the plate's
surface at its centre, in one compiled loop.

- :class:`ProfileCollider`: a roughness plate, a profile z(x)
  (:func:`~sim_tactile.plates.roughness_profile`, linear between its samples) across its
  textured area, on its base. MuJoCo's height-field collider gave about four contacts per
  node there (26 160 for the iCub's 6231 nodes on rough-ra100), filled its contact buffer and
  stopped the slide, and it measured each sphere's distance to the nearest facet, where the
  skin model and the reference it is measured against take the height map's depth (see
  :mod:`~sim_tactile.sim.collide`, which chooses the collider).
- :class:`MapCollider`: a height-map plate (:class:`~sim_tactile.plates.HeightMap`: heights
  sampled on a grid over (at least) the textured area, bilinear between them, NaN where
  there is no material), on its base. MuJoCo's height-field collider had served it: several
  contacts a node, at most 50 a pair.

Both read the same surface as :func:`~sim_tactile.plates.height_at`, bit for bit (tested),
without its per-call set-up.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import njit


class _SurfaceCollider:
    """What the height-map colliders share: the skin's probe spheres (centres ``local`` in
    the bone's frame, ``radius``, ``margin``) against a plate's ``surface`` (the arrays the
    subclass's loop reads after the nodes'), bound to the finger's joints by
    :meth:`from_scene`. A node's depth is the surface height at its centre less its lowest
    point, reported (else -inf) within its margin, as MuJoCo reports a contact; where the
    surface is NaN (off the plate, no material) nothing is near."""

    #: the held step may run it in one compiled call (:class:`~sim_tactile.sim.step.held.CompiledHeldStep`,
    #: through :attr:`kernel` and :attr:`arrays`)
    compiled = True
    #: the texture kind (``plate.texture.kind``) whose plates it collides
    texture_kind = ""

    def __init__(self, local, radius, margin, plate=None, surface=None) -> None:
        self.local, self.radius, self.margin = local, radius, margin
        self.surface = self.surface_of(plate) if surface is None else surface
        self._x = np.empty(len(local))
        self._y = np.empty(len(local))
        self._z = np.empty(len(local))
        #: the arguments of :attr:`kernel` after the bone's position, in its order
        self.arrays = (local, radius, margin, *self.surface)

    @staticmethod
    def surface_of(plate) -> tuple:
        """The arrays of ``plate``'s surface that the loop reads."""
        raise NotImplementedError

    @property
    def kernel(self):
        """The compiled depth map: ``kernel(bone, *arrays, pen) -> near``."""
        raise NotImplementedError

    def loop(self):
        """The compiled depth map at the bone's position ``x0, y0, z0``:
        ``loop(x0, y0, z0, *arrays, pen) -> near``."""
        raise NotImplementedError

    def heights(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The plate's surface height [m] at (x, y) in numpy; NaN off the plate."""
        raise NotImplementedError

    def subset(self, nodes: np.ndarray):
        """The same collider for the nodes ``nodes`` only (their order)."""
        c = type(self)(
            self.local[nodes], self.radius[nodes], self.margin[nodes], None, self.surface
        )
        for k in ("bone0", "jx", "jz"):
            if hasattr(self, k):
                setattr(c, k, getattr(self, k))
        return c

    @classmethod
    def from_scene(cls, scene):
        """The collider of a scene whose plate has the collider's texture kind, bound to the
        finger's joints (as :meth:`~.primitive.PrimitiveCollider.from_scene`), or None."""
        if scene.plate.texture.kind != cls.texture_kind:
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
            scene.plate,
        )
        c.bone0 = np.array(m.body_pos[bone], dtype=np.float64)
        c.jx, c.jz = int(scene.jx), int(scene.jz)
        return c

    def depths_at(self, qpos: np.ndarray, pen: np.ndarray) -> bool:
        """Fill ``pen`` with each node's depth [m] for the joints at ``qpos``; whether any
        node is within its margin of the plate. One compiled loop, the same numbers as
        :meth:`depths_numpy` bit for bit (tested)."""
        return self.loop()(
            self.bone0[0] + qpos[self.jx],
            self.bone0[1],
            self.bone0[2] + qpos[self.jz],
            *self.arrays,
            pen,
        )

    def depths_numpy(self, qpos: np.ndarray, pen: np.ndarray) -> bool:
        """:meth:`depths_at` in numpy: the reference of the compiled loop."""
        np.add(self.bone0[0] + qpos[self.jx], self.local[:, 0], out=self._x)
        np.add(self.bone0[1], self.local[:, 1], out=self._y)
        np.add(self.bone0[2] + qpos[self.jz], self.local[:, 2], out=self._z)
        d = self.heights(self._x, self._y) - (self._z - self.radius)
        near = d >= -self.margin  # NaN (off the plate, no material) is not near
        pen[:] = np.where(near, d, -np.inf)
        return bool(near.any())

    def warnings(self) -> list[str]:
        return []


class ProfileCollider(_SurfaceCollider):
    """Depths of the skin's probe spheres below a roughness plate's height map: its profile
    z(x) (:func:`~sim_tactile.plates.roughness_profile`, linear between samples) over the
    textured area, the base (z = 0) elsewhere on the plate, nothing off it (see
    :class:`_SurfaceCollider`): what :func:`~sim_tactile.plates.height_at` gives, without
    its per-call set-up (tested equal)."""

    texture_kind = "roughness"

    def __init__(self, local, radius, margin, plate=None, profile=None) -> None:
        super().__init__(local, radius, margin, plate, profile)
        self.profile = self.surface
        self.px, self.pz = self.profile[0], self.profile[1]
        self.area, self.size = self.profile[2:4], self.profile[4:6]

    @staticmethod
    def surface_of(plate) -> tuple:
        """``(px, pz, ax, ay, sx, sy)``: the profile, the textured area's and the plate's
        half-extents."""
        from ...plates import roughness_profile

        px, pz = roughness_profile(plate)
        area = (plate.area_length_m / 2, plate.area_width_m / 2)
        size = (plate.length_m / 2, plate.width_m / 2)
        return (px, pz, *area, *size)

    @property
    def kernel(self):
        return profile_depths_kernel

    def loop(self):
        return _profile_depths

    def y_invariant(self, bone_y: float) -> bool:
        """Whether every node's depth is independent of its y for the bone at ``bone_y``:
        every node lies inside the textured area's y extent (the profile varies along x
        only), so nodes with equal x, z, radius and margin get bit-identical depths."""
        y = bone_y + self.local[:, 1]
        return bool(len(y)) and float(np.abs(y).max()) < min(self.area[1], self.size[1])

    def heights(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        inside = (np.abs(x) <= self.area[0]) & (np.abs(y) <= self.area[1])
        z = np.where(inside, np.interp(x, self.px, self.pz), 0.0)
        off = (np.abs(x) > self.size[0]) | (np.abs(y) > self.size[1])
        return np.where(off, np.nan, z)


class MapCollider(_SurfaceCollider):
    """Depths of the skin's probe spheres below a height-map plate's surface: its samples
    (:class:`~sim_tactile.plates.HeightMap`, bilinear between them as
    :func:`~sim_tactile.plates.features.map_height` has it, in its operation order) over the
    map's span, the base (z = 0) elsewhere on the plate, nothing off it or where the map holds
    no material (see :class:`_SurfaceCollider`): what :func:`~sim_tactile.plates.height_at`
    gives, bit for bit (tested)."""

    texture_kind = "heightmap"

    def __init__(self, local, radius, margin, plate=None, surface=None) -> None:
        super().__init__(local, radius, margin, plate, surface)
        self.z, self.pixel = self.surface[0], self.surface[1]
        self.span, self.size = self.surface[2:4], self.surface[4:6]

    @staticmethod
    def surface_of(plate) -> tuple:
        """``(z, pixel, ax, ay, sx, sy)``: the map (read-only, C order), its pixel, its own
        half-extents (its span, ``(samples - 1) pixel``, which covers the textured area) and
        the plate's, as :func:`~sim_tactile.plates.height_at` masks them."""
        t = plate.texture
        z = np.ascontiguousarray(t.z, dtype=np.float64)
        ex, ey = t.extent_m
        size = (plate.length_m / 2, plate.width_m / 2)
        return (z, float(t.pixel_m), ex / 2, ey / 2, *size)

    @property
    def kernel(self):
        return map_depths_kernel

    def loop(self):
        return _map_depths

    def y_invariant(self, bone_y: float) -> bool:
        """False: a map varies along y in general, and even where its rows are equal the
        bilinear blend of two equal rows, ``(1 - ty) a + ty a``, rounds differently at
        different y, so no two nodes are sure of bit-identical depths."""
        return False

    def heights(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        from ...plates.features import map_height

        inside = (np.abs(x) <= self.span[0]) & (np.abs(y) <= self.span[1])
        z = np.where(inside, map_height(x, y, self.z, self.pixel), 0.0)
        off = (np.abs(x) > self.size[0]) | (np.abs(y) > self.size[1])
        return np.where(off, np.nan, z)


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
def _profile_depths(x0, y0, z0, local, radius, margin, px, pz, ax, ay, sx, sy, pen):
    """:meth:`ProfileCollider.depths_numpy` in one loop: each node's height-map depth within
    its margin (the profile over the textured area ``|x| <= ax, |y| <= ay``, the base
    elsewhere on the plate, nothing beyond ``sx, sy``), else -inf; whether any is near."""
    near = False
    for i in range(local.shape[0]):
        x = x0 + local[i, 0]
        y = y0 + local[i, 1]
        z = z0 + local[i, 2]
        if abs(x) > sx or abs(y) > sy:
            pen[i] = -np.inf
            continue
        h = 0.0
        if abs(x) <= ax and abs(y) <= ay:
            h = interp_at(x, px, pz, pz[0], pz[pz.size - 1])
        near |= report_depth(pen, i, h - (z - radius[i]), margin[i])
    return near


@njit
def profile_depths_kernel(bone, local, radius, margin, px, pz, ax, ay, sx, sy, pen):
    """:func:`_profile_depths` for the bone at world position ``bone`` (3,): the depth kernel
    of :class:`ProfileCollider` in the compiled held step (the same sums, bit for bit)."""
    return _profile_depths(
        bone[0], bone[1], bone[2], local, radius, margin, px, pz, ax, ay, sx, sy, pen
    )


@njit
def map_height_at(x, y, z, pixel):
    """:func:`~sim_tactile.plates.features.map_height` at one point, in its operation order
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
    :func:`~sim_tactile.plates.height_at` gives it: the map over its span ``|x| <= ax, |y|
    <= ay`` (NaN where it holds no material), the base (0) elsewhere on the plate, NaN beyond
    ``sx, sy``."""
    if abs(x) > sx or abs(y) > sy:
        return np.nan
    if abs(x) <= ax and abs(y) <= ay:
        return map_height_at(x, y, z, pixel)
    return 0.0


@njit
def _map_depths(x0, y0, z0, local, radius, margin, z, pixel, ax, ay, sx, sy, pen):
    """:meth:`MapCollider.depths_numpy` in one loop: each node's depth below the plate's
    surface at its centre (:func:`map_surface_at`) within its margin, else -inf (and where the
    surface is NaN); whether any is near."""
    near = False
    for i in range(local.shape[0]):
        h = map_surface_at(x0 + local[i, 0], y0 + local[i, 1], z, pixel, ax, ay, sx, sy)
        near |= report_depth(pen, i, h - ((z0 + local[i, 2]) - radius[i]), margin[i])
    return near


@njit
def map_depths_kernel(bone, local, radius, margin, z, pixel, ax, ay, sx, sy, pen):
    """:func:`_map_depths` for the bone at world position ``bone`` (3,): the depth kernel of
    :class:`MapCollider` in the compiled held step (the same sums, bit for bit)."""
    return _map_depths(
        bone[0], bone[1], bone[2], local, radius, margin, z, pixel, ax, ay, sx, sy, pen
    )


@njit(inline="always")
def report_depth(pen, i, depth, margin):
    """Node ``i``'s depth into ``pen`` if it is within its margin (else -inf); whether it is.
    A NaN depth (no surface) is not within it."""
    if depth >= -margin:
        pen[i] = depth
        return True
    pen[i] = -np.inf
    return False
