"""Colliders: the penetration-depth map of the skin's probe spheres against the plate.

A collider answers one question, :meth:`depths_at`: with the finger's joints at ``qpos``, how
deep is each skin node in the plate (``-inf`` where no plate geom lies within the node's
margin), and is any node that close. :func:`make_collider` chooses one, in one place:

- :class:`PrimitiveCollider`: a compiled narrow phase for plates made of boxes and spheres.
  MuJoCo's collider (``mj_kinematics`` + ``mj_collision``) costs about 60 us a step for a
  few hundred skin nodes, a third of a whole L1 step, although the plate never moves and
  every node is a sphere on the one bone; this computes the same map in one numba loop (the
  signed distance of each probe sphere to each plate box, in the box's frame, and sphere; the
  deepest per node). Over an upright box's footprint a node's depth is the depth below the
  box's top face, as the plate's height map (and the skin model, and the reference it is
  measured against) has it: MuJoCo measures a node inside a box to its nearest face, so a
  node that a slide carries into a box's side, deeper than half the box is wide, reads a
  depth that falls as the pad sinks, and the held force then let the pad pass through the
  box onto the base (finger7/bumps-4x4 at 0.5 mm nodes read as flat). Tested equal to
  MuJoCo's map everywhere else, on every plate it accepts, at random poses.
- :class:`ProfileCollider`: a roughness plate (a profile z(x) across the textured area, on
  its base): each node's depth below the plate's height map at its centre, in one numba
  loop (numpy's interpolation, bit for bit).
  MuJoCo's height-field collider returned about four contacts per node (26 160 for the iCub's
  6231 nodes on rough-ra100) and filled its contact buffer there, which stopped the slide;
  and it measured each sphere's distance to the nearest facet, where the skin model and the
  reference it is measured against take the height map's depth.
- :class:`MujocoCollider`: MuJoCo's own collider on the scene's collision model, for any
  geometry (meshes of drafted ridges, cylinders, height fields): the reference.
"""

from __future__ import annotations

import math

import mujoco
import numba
import numpy as np

from ..plates import features

_BOX = int(mujoco.mjtGeom.mjGEOM_BOX)
_SPHERE = int(mujoco.mjtGeom.mjGEOM_SPHERE)


@numba.njit(cache=True)
def penetration_map(
    geom: np.ndarray, dist: np.ndarray, node_of_geom: np.ndarray, pen: np.ndarray
) -> None:
    """pen[node] = max over the node's contacts of -dist (else -inf). geom: (n, 2) int32."""
    pen[:] = -np.inf
    for k in range(dist.shape[0]):
        i = node_of_geom[geom[k, 0]]
        if i < 0:
            i = node_of_geom[geom[k, 1]]
        if i >= 0 and -dist[k] > pen[i]:
            pen[i] = -dist[k]


def penetration_map_reference(geom, dist, node_of_geom, n_nodes: int) -> np.ndarray:
    """:func:`penetration_map` in plain numpy (``np.maximum.at``)."""
    pen = np.full(n_nodes, -np.inf)
    node = node_of_geom[geom[:, 0]]
    node = np.where(node >= 0, node, node_of_geom[geom[:, 1]])
    keep = node >= 0
    np.maximum.at(pen, node[keep], -dist[keep])
    return pen


class MujocoCollider:
    """MuJoCo's collider on the scene's collision model (contacts enabled, nothing stepped):
    each node's deepest contact distance, read by :func:`penetration_map`."""

    compiled = False

    def __init__(self, scene) -> None:
        self.m = scene.m_col
        self.d = mujoco.MjData(self.m)
        self.node_of_geom = scene.node_of_geom

    def depths_at(self, qpos: np.ndarray, pen: np.ndarray) -> bool:
        """Fill ``pen`` with each node's depth [m] for the joints at ``qpos``; whether any
        node is within its margin of the plate."""
        d = self.d
        d.qpos[:] = qpos
        mujoco.mj_kinematics(self.m, d)
        mujoco.mj_collision(self.m, d)
        if d.ncon:
            con = d.contact
            penetration_map(con.geom, con.dist, self.node_of_geom, pen)
            return True
        pen[:] = -np.inf
        return False

    def warnings(self) -> list[str]:
        """Names of the warnings MuJoCo raised while colliding (e.g. a full contact buffer)."""
        d = self.d
        if not d.warning.number.any():
            return []
        return [mujoco.mjtWarning(i).name for i, w in enumerate(d.warning) if w.number]


#: Collider margin [m] of the skin nodes when the pad is held at a force: nodes this far above
#: the plate are reported, so they can join the contact when the pad sinks; a step that would
#: move the pad further than this is re-collided at the new height.
QS_MARGIN_M = 0.5e-3
#: The margin where MuJoCo's collider serves (meshes, cylinders) and on roughness plates: each
#: node within it is a contact MuJoCo must generate, which on a height field filled the
#: contact buffer at 0.5 mm; a step that sinks further is re-collided. The roughness plates
#: keep it under the profile collider (their slides unchanged but for the depths).
QS_MARGIN_MUJOCO_M = 0.1e-3


def node_margin_m(plate) -> float:
    """The skin nodes' collider margin for a held force on ``plate``: wide where the compiled
    collider serves (boxes and spherical caps; it costs nothing there), narrow where MuJoCo
    collides."""
    if plate.texture.kind == "roughness":
        return QS_MARGIN_MUJOCO_M
    if all(f.kind in ("box", "cap") for f in features(plate)):
        return QS_MARGIN_M
    return QS_MARGIN_MUJOCO_M


def make_collider(scene, primitive: bool = True):
    """The compiled collider where the plate allows it, the profile collider on a roughness
    plate (both where ``primitive`` is set), else MuJoCo's. The bone must be at its starting
    pose (its world position is read here)."""
    if primitive:
        c = PrimitiveCollider.from_scene(scene)
        if c is None:
            c = ProfileCollider.from_scene(scene)
        if c is not None:
            return c
    return MujocoCollider(scene)


class ProfileCollider:
    """Depths of the skin's probe spheres below a roughness plate's height map: its profile
    z(x) (:func:`~sim_tactile.plates.roughness_profile`, linear between samples) over the
    textured area, the base (z = 0) elsewhere on the plate, nothing off it. A node's depth is
    the surface height at its centre less its lowest point, and it is reported (else -inf)
    within its margin, as MuJoCo reports a contact: what
    :func:`~sim_tactile.plates.height_at` gives, without its per-call set-up (tested equal)."""

    compiled = False

    def __init__(self, local, radius, margin, plate) -> None:
        from ..plates import roughness_profile

        self.local, self.radius, self.margin = local, radius, margin
        self.px, self.pz = roughness_profile(plate)
        self.area = (plate.area_length_m / 2, plate.area_width_m / 2)
        self.size = (plate.length_m / 2, plate.width_m / 2)
        self._x = np.empty(len(local))
        self._y = np.empty(len(local))
        self._z = np.empty(len(local))

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
            self.local,
            self.radius,
            self.margin,
            self.px,
            self.pz,
            self.area[0],
            self.area[1],
            self.size[0],
            self.size[1],
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
        d = h - (z - radius[i])
        if d >= -margin[i]:
            pen[i] = d
            near = True
        else:
            pen[i] = -np.inf
    return near


class PrimitiveCollider:
    """Penetration depths of the skin's probe spheres against a static plate of boxes and
    spheres. Built once per scene from the compiled collision model."""

    compiled = True

    def __init__(self, local, radius, margin, kind, pos, mat, size):
        self.local = local  # (N, 3) node centres in the bone's frame
        self.radius = radius  # (N,)
        self.margin = margin  # (N,) node geom margins
        self.kind, self.pos, self.mat, self.size = kind, pos, mat, size
        # broad phase: a grid of x-y cells, each listing the geoms whose footprint (grown by
        # the largest probe's reach) overlaps it
        reach = float((radius + margin).max()) if len(radius) else 0.0
        half = _half_extents(kind, mat, size)
        lo = pos[:, :2] - half[:, :2] - reach
        hi = pos[:, :2] + half[:, :2] + reach
        self.cell = max(float(np.median(hi - lo)) / 2 if len(kind) else 1.0, 1e-4)
        self.origin = lo.min(axis=0) if len(kind) else np.zeros(2)
        n = np.maximum(np.ceil((hi.max(axis=0) - self.origin) / self.cell).astype(np.int64), 1)
        self.shape = n
        buckets: list[list[int]] = [[] for _ in range(int(n[0] * n[1]))]
        for g in range(len(kind)):
            i0, j0 = np.floor((lo[g] - self.origin) / self.cell).astype(int)
            i1, j1 = np.floor((hi[g] - self.origin) / self.cell).astype(int)
            for i in range(max(i0, 0), min(i1, n[0] - 1) + 1):
                for j in range(max(j0, 0), min(j1, n[1] - 1) + 1):
                    buckets[i * n[1] + j].append(g)
        self.start = np.zeros(len(buckets) + 1, dtype=np.int64)
        self.start[1:] = np.cumsum([len(b) for b in buckets])
        self.items = np.array([g for b in buckets for g in b], dtype=np.int64)
        #: the arguments of the depth kernel after the bone's position, in its order
        self.arrays = (
            self.local,
            self.radius,
            self.margin,
            self.kind,
            self.pos,
            self.mat,
            self.size,
            self.origin,
            self.cell,
            self.shape,
            self.start,
            self.items,
        )

    @classmethod
    def from_model(
        cls, m: mujoco.MjModel, node_of_geom: np.ndarray, bone_body: int
    ) -> PrimitiveCollider | None:
        """The collider for ``m``'s plate, or None if the plate has a geom that is not a box
        or sphere, or the skin nodes are not spheres fixed on an unrotated bone."""
        nodes = np.flatnonzero(node_of_geom >= 0)
        order = np.argsort(node_of_geom[nodes])
        nodes = nodes[order]
        if (
            not (m.geom_type[nodes] == _SPHERE).all()
            or not (m.geom_bodyid[nodes] == bone_body).all()
        ):
            return None
        if not np.allclose(m.geom_quat[nodes], [1, 0, 0, 0]) or not np.allclose(
            m.body_quat[bone_body], [1, 0, 0, 0]
        ):
            return None
        node_bits = int(np.bitwise_or.reduce(m.geom_contype[nodes]))
        plate = [
            g
            for g in range(m.ngeom)
            if node_of_geom[g] < 0
            and m.geom_bodyid[g] != bone_body
            and (int(m.geom_conaffinity[g]) & node_bits)
        ]
        if any(m.geom_type[g] not in (_BOX, _SPHERE) for g in plate):
            return None
        if any(
            m.body_mocapid[m.geom_bodyid[g]] >= 0 or m.body_dofnum[m.geom_bodyid[g]] for g in plate
        ):
            return None  # the plate must be static
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        idx = np.array(plate, dtype=np.int64)
        return cls(
            local=m.geom_pos[nodes].copy(),
            radius=m.geom_size[nodes, 0].copy(),
            margin=m.geom_margin[nodes].copy(),
            kind=m.geom_type[idx].astype(np.int64),
            pos=d.geom_xpos[idx].copy(),
            mat=d.geom_xmat[idx].reshape(-1, 3, 3).copy(),
            size=m.geom_size[idx].copy(),
        )

    @classmethod
    def from_scene(cls, scene) -> PrimitiveCollider | None:
        """:meth:`from_model` for a scene's plate and skin, bound to its finger's joints so
        that :meth:`depths_at` reads the bone's pose from ``qpos``."""
        m = scene.m_col
        bone = m.body("bone").id
        c = cls.from_model(m, scene.node_of_geom, bone)
        if c is not None:
            c.bind(m.body_pos[bone], scene.jx, scene.jz)
        return c

    def bind(self, bone0: np.ndarray, jx: int, jz: int) -> None:
        """Read the bone's world position as ``bone0 + (qpos[jx], 0, qpos[jz])``."""
        self.bone0 = np.array(bone0, dtype=np.float64)
        self.jx, self.jz = int(jx), int(jz)
        self._bone = self.bone0.copy()

    def depths_at(self, qpos: np.ndarray, pen: np.ndarray) -> bool:
        """:meth:`depths` with the bone at its pose for the joints ``qpos`` (see :meth:`bind`)."""
        b = self._bone
        b[0] = self.bone0[0] + qpos[self.jx]
        b[2] = self.bone0[2] + qpos[self.jz]
        return depths_kernel(b, *self.arrays, pen)

    def warnings(self) -> list[str]:
        return []

    def y_invariant(self, bone_y: float) -> bool:
        """Whether every node's depth is independent of its y for the bone at ``bone_y``: all
        plate geoms are unrotated boxes that reach past every node in y by more than their
        smaller half-extent in x or z. Then a node's signed distance to each box does not
        involve its y at all (the y-term is neither the largest inside nor nonzero outside),
        so nodes with equal x, z, radius and margin get bit-identical depths."""
        if not len(self.kind) or not (self.kind == _BOX).all():
            return False
        if not (self.mat == np.eye(3)).all():
            return False
        y = bone_y + self.local[:, 1]
        for g in range(len(self.kind)):
            hx, hy, hz = self.size[g]
            if np.abs(y - self.pos[g, 1]).max() >= hy - min(hx, hz):
                return False
        return True

    def subset(self, nodes: np.ndarray) -> PrimitiveCollider:
        """The same collider for the nodes ``nodes`` only (their order)."""
        return PrimitiveCollider(
            self.local[nodes],
            self.radius[nodes],
            self.margin[nodes],
            self.kind,
            self.pos,
            self.mat,
            self.size,
        )

    def depths(self, bone_pos: np.ndarray, pen: np.ndarray) -> bool:
        """Fill ``pen`` (N,) with each node's deepest penetration [m] for the bone at world
        position ``bone_pos`` (3,); ``-inf`` where no plate geom is within the node's margin.
        Returns whether any node is within it."""
        return depths_kernel(bone_pos, *self.arrays, pen)


def _half_extents(kind: np.ndarray, mat: np.ndarray, size: np.ndarray) -> np.ndarray:
    """World half extents (G, 3) of each geom's bounding box."""
    out = np.empty((len(kind), 3))
    for g in range(len(kind)):
        if kind[g] == _SPHERE:
            out[g] = size[g, 0]
        else:
            out[g] = np.abs(mat[g]) @ size[g]
    return out


@numba.njit(cache=True)
def depths_kernel(
    bone, local, radius, margin, kind, pos, mat, size, origin, cell, shape, start, items, pen
):
    n = local.shape[0]
    near = False
    for i in range(n):
        cx = bone[0] + local[i, 0]
        cy = bone[1] + local[i, 1]
        cz = bone[2] + local[i, 2]
        r = radius[i]
        best = -np.inf
        bi = int(math.floor((cx - origin[0]) / cell))
        bj = int(math.floor((cy - origin[1]) / cell))
        if bi < 0 or bj < 0 or bi >= shape[0] or bj >= shape[1]:
            pen[i] = -np.inf
            continue
        b = bi * shape[1] + bj
        for k in range(start[b], start[b + 1]):
            g = items[k]
            dx = cx - pos[g, 0]
            dy = cy - pos[g, 1]
            dz = cz - pos[g, 2]
            if kind[g] == _SPHERE:
                dist = math.sqrt(dx * dx + dy * dy + dz * dz) - size[g, 0] - r
            else:  # box: the centre in the box's frame, then the box's signed distance
                lz = mat[g, 0, 2] * dx + mat[g, 1, 2] * dy + mat[g, 2, 2] * dz
                qx = abs(mat[g, 0, 0] * dx + mat[g, 1, 0] * dy + mat[g, 2, 0] * dz) - size[g, 0]
                qy = abs(mat[g, 0, 1] * dx + mat[g, 1, 1] * dy + mat[g, 2, 1] * dz) - size[g, 1]
                qz = abs(lz) - size[g, 2]
                if qx <= 0.0 and qy <= 0.0 and abs(mat[g, 2, 2] - 1.0) < 1e-12:
                    # over an upright box's footprint: the depth below its top face, as the
                    # plate's height map has it (a node inside the box is not measured to a
                    # nearer side or bottom face, as MuJoCo's collider would)
                    dist = (lz - size[g, 2]) - r
                else:
                    ox = qx if qx > 0.0 else 0.0
                    oy = qy if qy > 0.0 else 0.0
                    oz = qz if qz > 0.0 else 0.0
                    inside = qx
                    if qy > inside:
                        inside = qy
                    if qz > inside:
                        inside = qz
                    if inside > 0.0:
                        dist = math.sqrt(ox * ox + oy * oy + oz * oz) - r
                    else:
                        dist = inside - r
            if -dist > best:
                best = -dist
        if best >= -margin[i]:
            pen[i] = best
            near = True
        else:
            pen[i] = -np.inf
    return near
