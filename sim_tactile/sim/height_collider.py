"""The height-map collider of the rough plates: each skin node's depth below the plate's
surface at its centre, in one compiled loop.

A roughness plate is a profile z(x) (:func:`~sim_tactile.plates.roughness_profile`, linear
between its samples) across its textured area, on its base. MuJoCo's height-field collider
gave about four contacts per node there (26 160 for the iCub's 6231 nodes on rough-ra100),
filled its contact buffer and stopped the slide, and it measured each sphere's distance to the
nearest facet, where the skin model and the reference it is measured against take the height
map's depth (see :mod:`.collide`, which chooses the collider).
"""

from __future__ import annotations

import numba
import numpy as np


class ProfileCollider:
    """Depths of the skin's probe spheres below a roughness plate's height map: its profile
    z(x) (:func:`~sim_tactile.plates.roughness_profile`, linear between samples) over the
    textured area, the base (z = 0) elsewhere on the plate, nothing off it. A node's depth is
    the surface height at its centre less its lowest point, and it is reported (else -inf)
    within its margin, as MuJoCo reports a contact: what
    :func:`~sim_tactile.plates.height_at` gives, without its per-call set-up (tested equal)."""

    #: the held step may run it in one compiled call (:class:`~.held.CompiledHeldStep`,
    #: through :attr:`kernel` and :attr:`arrays`)
    compiled = True

    def __init__(self, local, radius, margin, plate=None, profile=None) -> None:
        self.local, self.radius, self.margin = local, radius, margin
        if profile is None:
            from ..plates import roughness_profile

            px, pz = roughness_profile(plate)
            area = (plate.area_length_m / 2, plate.area_width_m / 2)
            size = (plate.length_m / 2, plate.width_m / 2)
            profile = (px, pz, *area, *size)
        self.profile = profile
        self.px, self.pz = profile[0], profile[1]
        self.area, self.size = profile[2:4], profile[4:6]
        self._x = np.empty(len(local))
        self._y = np.empty(len(local))
        self._z = np.empty(len(local))
        #: the arguments of :attr:`kernel` after the bone's position, in its order
        self.arrays = (local, radius, margin, *profile)

    @property
    def kernel(self):
        """The compiled depth map: ``kernel(bone, *arrays, pen) -> near``."""
        return profile_depths_kernel

    def subset(self, nodes: np.ndarray) -> ProfileCollider:
        """The same collider for the nodes ``nodes`` only (their order)."""
        c = ProfileCollider(
            self.local[nodes], self.radius[nodes], self.margin[nodes], profile=self.profile
        )
        for k in ("bone0", "jx", "jz"):
            if hasattr(self, k):
                setattr(c, k, getattr(self, k))
        return c

    def y_invariant(self, bone_y: float) -> bool:
        """Whether every node's depth is independent of its y for the bone at ``bone_y``:
        every node lies inside the textured area's y extent (the profile varies along x
        only), so nodes with equal x, z, radius and margin get bit-identical depths."""
        y = bone_y + self.local[:, 1]
        return bool(len(y)) and float(np.abs(y).max()) < min(self.area[1], self.size[1])

    @classmethod
    def from_scene(cls, scene) -> ProfileCollider | None:
        """The collider of a scene whose plate is a roughness plate, bound to the finger's
        joints (as :meth:`PrimitiveCollider.from_scene`), or None."""
        if scene.plate.texture.kind != "roughness":
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

    def heights(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The plate's surface height [m] at (x, y); NaN off the plate."""
        inside = (np.abs(x) <= self.area[0]) & (np.abs(y) <= self.area[1])
        z = np.where(inside, np.interp(x, self.px, self.pz), 0.0)
        off = (np.abs(x) > self.size[0]) | (np.abs(y) > self.size[1])
        return np.where(off, np.nan, z)

    def depths_at(self, qpos: np.ndarray, pen: np.ndarray) -> bool:
        """Fill ``pen`` with each node's depth [m] for the joints at ``qpos``; whether any
        node is within its margin of the plate. One compiled loop, the same numbers as
        :meth:`depths_numpy` bit for bit (tested)."""
        return _profile_depths(
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
        near = d >= -self.margin  # NaN (off the plate) is not near
        pen[:] = np.where(near, d, -np.inf)
        return bool(near.any())

    def warnings(self) -> list[str]:
        return []


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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


@numba.njit(cache=True)
def profile_depths_kernel(bone, local, radius, margin, px, pz, ax, ay, sx, sy, pen):
    """:func:`_profile_depths` for the bone at world position ``bone`` (3,): the depth kernel
    of :class:`ProfileCollider` in the compiled held step (the same sums, bit for bit)."""
    return _profile_depths(
        bone[0], bone[1], bone[2], local, radius, margin, px, pz, ax, ay, sx, sy, pen
    )


@numba.njit(cache=True, inline="always")
def report_depth(pen, i, depth, margin):
    """Node ``i``'s depth into ``pen`` if it is within its margin (else -inf); whether it is."""
    if depth >= -margin:
        pen[i] = depth
        return True
    pen[i] = -np.inf
    return False
