"""A narrow phase for the skin's probe spheres against plates made of boxes and spheres.

MuJoCo's collider (``mj_kinematics`` + ``mj_collision``) costs about 60 us a step for a few
hundred skin nodes, a third of a whole L1 step, although the plate never moves and every node
is a sphere on the one bone. :class:`PrimitiveCollider` computes the same penetration-depth map
in one numba loop: the signed distance of each probe sphere to each plate box (in the box's
frame) and sphere, the deepest per node, ``-inf`` where no geom lies within the node's margin,
exactly as :func:`sim_tactile.sim._readout.penetration_map` reads MuJoCo's contacts. It is
tested equal to MuJoCo's map on every plate it accepts, at random pad poses.

Plates with other geoms (meshes of drafted ridges, cylinders, height fields) return ``None``
from :meth:`PrimitiveCollider.from_model`; they keep MuJoCo's collider.
"""

from __future__ import annotations

import math

import mujoco
import numba
import numpy as np

_BOX = int(mujoco.mjtGeom.mjGEOM_BOX)
_SPHERE = int(mujoco.mjtGeom.mjGEOM_SPHERE)


class PrimitiveCollider:
    """Penetration depths of the skin's probe spheres against a static plate of boxes and
    spheres. Built once per scene from the compiled collision model."""

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
        return _depths(bone_pos, *self.arrays, pen)


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
def _depths(
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
                qx = abs(mat[g, 0, 0] * dx + mat[g, 1, 0] * dy + mat[g, 2, 0] * dz) - size[g, 0]
                qy = abs(mat[g, 0, 1] * dx + mat[g, 1, 1] * dy + mat[g, 2, 1] * dz) - size[g, 1]
                qz = abs(mat[g, 0, 2] * dx + mat[g, 1, 2] * dy + mat[g, 2, 2] * dz) - size[g, 2]
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
