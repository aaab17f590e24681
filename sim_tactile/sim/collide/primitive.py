"""The compiled collider of a plate of features: boxes, spherical caps, upright cylinders
and drafted ridges (which MuJoCo holds as convex meshes), in one numba loop.

MuJoCo's collider (``mj_kinematics`` + ``mj_collision``) costs about 60 us a step for a few
hundred skin nodes, a third of a whole L1 step, although the plate never moves and every node
is a sphere on the one bone; :func:`depths_kernel` computes the same map in one loop (the
signed distance of each probe sphere to each plate geom in its frame; the deepest per node).
Over an upright geom's footprint, below its top surface, a node's depth is the depth below
that surface, as the plate's height map (and the skin model, and the reference it is
measured against) has it: MuJoCo measures a node inside a solid to its nearest face, so a
node that a slide carries into a box's side, deeper than half the box is wide, reads a depth
that falls as the pad sinks, and the held force then let the pad pass through the box onto
the base (finger7/bumps-4x4 at 0.5 mm nodes read as flat). Elsewhere tested equal to MuJoCo's
map at random poses on every plate kind: bit for bit on boxes and caps, within 1e-15 m on
cylinders, and within 1e-6 m on drafted ridges, where MuJoCo's mesh penetration is the
approximate one (measured 4.5e-7 m off; ours equals a brute-force distance).
"""

from __future__ import annotations

import copy
import math
from collections import OrderedDict
from typing import NamedTuple

import mujoco
import numpy as np

from ..._jit import njit
from ...cache import register_memo
from ...plates import surface_of
from .height import kept_value, report_depth
from .shapes import cylinder_distance, ridge_distance

_BOX = int(mujoco.mjtGeom.mjGEOM_BOX)
_SPHERE = int(mujoco.mjtGeom.mjGEOM_SPHERE)
_CYLINDER = int(mujoco.mjtGeom.mjGEOM_CYLINDER)
#: a drafted ridge (MuJoCo holds it as a convex mesh): a box whose x-walls slope in from
#: ``size[0]`` at its bottom to ``top[g]`` at its top
_PRISM = int(mujoco.mjtGeom.mjGEOM_MESH)


class PrimitiveProbe(NamedTuple):
    """What :func:`depths_kernel` reads after the bone's position: the probe spheres
    (``local`` (N, 3) in the bone's frame, ``radius``, ``margin``), the plate's geoms
    (``kind``, ``pos``, ``mat``, ``size``, a drafted ridge's ``top``) and the broad phase's
    grid of cells (``origin``, ``cell``, ``shape``, ``start``, ``items``, ``cell_top``)."""

    local: np.ndarray
    radius: np.ndarray
    margin: np.ndarray
    kind: np.ndarray
    pos: np.ndarray
    mat: np.ndarray
    size: np.ndarray
    top: np.ndarray
    origin: np.ndarray
    cell: float
    shape: np.ndarray
    start: np.ndarray
    items: np.ndarray
    cell_top: np.ndarray


def grid_buckets(lo, hi, tops, origin, cell: float, shape):
    """The broad phase's cells: ``(start, items, cell_top)``, the geoms whose footprint
    ``[lo, hi]`` (G, 2) overlaps each cell of the ``shape`` grid of side ``cell`` from
    ``origin``, listed cell by cell (row-major) in ascending geom order (cell ``c`` holds
    ``items[start[c]:start[c + 1]]``), and each cell's highest geom top (``tops``; -inf in
    an empty cell)."""
    n0, n1 = int(shape[0]), int(shape[1])
    first = np.floor((lo - origin) / cell).astype(int)
    last = np.floor((hi - origin) / cell).astype(int)
    ia, ib = np.maximum(first[:, 0], 0), np.minimum(last[:, 0], n0 - 1)
    ja, jb = np.maximum(first[:, 1], 0), np.minimum(last[:, 1], n1 - 1)
    ni, nj = np.maximum(ib - ia + 1, 0), np.maximum(jb - ja + 1, 0)
    count = ni * nj
    geom = np.repeat(np.arange(len(count)), count)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    cells = (ia[geom] + k // nj[geom]) * n1 + (ja[geom] + k % nj[geom])
    order = np.lexsort((geom, cells))
    start = np.zeros(n0 * n1 + 1, dtype=np.int64)
    start[1:] = np.cumsum(np.bincount(cells, minlength=n0 * n1))
    cell_top = np.full(n0 * n1, -np.inf)
    np.maximum.at(cell_top, cells, np.asarray(tops, dtype=np.float64)[geom])
    return start, geom[order].astype(np.int64), cell_top


#: The unbound colliders of the kept scene models, by their content key
#: (:data:`~sim_tactile.scene.model.SCENES`): None where a model's plate is not primitive.
KEPT: OrderedDict[str, PrimitiveCollider | None] = OrderedDict()
#: Most colliders :data:`KEPT` holds (the kept scene models' number).
KEPT_MAX = 8
register_memo("primitive colliders of kept scene models", KEPT.clear)


class PrimitiveCollider:
    """Penetration depths of the skin's probe spheres against a static plate of boxes,
    spheres, upright cylinders and drafted ridges. Built once per scene from the compiled
    collision model (and the plate's features, for the ridges MuJoCo holds as meshes).

    A node's depth is its sphere's signed distance to the nearest plate geom, exact (tested
    against MuJoCo's collider), but where its centre lies over an upright geom's footprint and
    below that geom's top surface: there it is the depth below the top surface at the centre,
    as the plate's height map has it (:meth:`~sim_tactile.plates.Surface.height`), which the skin
    model and the references it is measured against take."""

    compiled = True

    def __init__(self, local, radius, margin, kind, pos, mat, size, top=None):
        self.local = local  # (N, 3) node centres in the bone's frame
        self.radius = radius  # (N,)
        self.margin = margin  # (N,) node geom margins
        self.kind, self.pos, self.mat, self.size = kind, pos, mat, size
        # a drafted ridge's top half-width (its kind _PRISM); unused by the other kinds
        self.top = np.zeros(len(kind)) if top is None else np.asarray(top, dtype=np.float64)
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
        self.start, self.items, self.cell_top = grid_buckets(
            lo, hi, pos[:, 2] + half[:, 2], self.origin, self.cell, n
        )
        #: the depth kernel's arguments after the bone's position
        self.probe = PrimitiveProbe(
            self.local,
            self.radius,
            self.margin,
            self.kind,
            self.pos,
            self.mat,
            self.size,
            self.top,
            self.origin,
            self.cell,
            self.shape,
            self.start,
            self.items,
            self.cell_top,
        )
        #: values computed from the nodes and geoms alone (:meth:`kept`), shared by the
        #: copies that the scenes placed from one kept model take (:meth:`from_scene`)
        self._kept: dict = {}

    def kept(self, key, build):
        """``build()``, kept under ``key`` on this collider and every copy of it: the scenes
        placed from one kept model share what is computed from the collider's nodes and
        geoms alone, never from a pose (a held step's reduced probes: their broad phase and
        column grouping took 0.5-0.9 ms of each L0 slide). ``key`` holds whatever else
        ``build`` reads."""
        return kept_value(self._kept, key, build)

    @classmethod
    def from_model(
        cls, m: mujoco.MjModel, node_of_geom: np.ndarray, bone_body: int, plate=None
    ) -> PrimitiveCollider | None:
        """The collider for ``m``'s plate, or None if the plate has a geom that is not a box,
        sphere or cylinder (or, given the ``plate`` whose features the model was built from, a
        mesh that is one of its drafted ridges), or the skin nodes are not spheres fixed on an
        unrotated bone."""
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
        plate_geoms = [
            g
            for g in range(m.ngeom)
            if node_of_geom[g] < 0
            and m.geom_bodyid[g] != bone_body
            and (int(m.geom_conaffinity[g]) & node_bits)
        ]
        if any(
            m.body_mocapid[m.geom_bodyid[g]] >= 0 or m.body_dofnum[m.geom_bodyid[g]]
            for g in plate_geoms
        ):
            return None  # the plate must be static
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        n = len(plate_geoms)
        kind = np.empty(n, dtype=np.int64)
        pos, mat = np.empty((n, 3)), np.empty((n, 3, 3))
        size, top = np.empty((n, 3)), np.zeros(n)
        fs = None  # the plate's features, where a mesh must be found among them
        for k, g in enumerate(plate_geoms):
            t = int(m.geom_type[g])
            if t in (_BOX, _SPHERE, _CYLINDER):
                kind[k], pos[k], size[k] = t, d.geom_xpos[g], m.geom_size[g]
                mat[k] = d.geom_xmat[g].reshape(3, 3)
                continue
            if t == _PRISM and fs is None and plate is not None:
                fs = surface_of(plate).features  # once, for every mesh geom
            ridge = _drafted_ridge(m, d, g, fs) if t == _PRISM else None
            if ridge is None:
                return None
            kind[k], top[k] = _PRISM, ridge[3]
            pos[k], mat[k], size[k] = ridge[0], ridge[1], ridge[2]
        return cls(
            local=m.geom_pos[nodes].copy(),
            radius=m.geom_size[nodes, 0].copy(),
            margin=m.geom_margin[nodes].copy(),
            kind=kind,
            pos=pos,
            mat=mat,
            size=size,
            top=top,
        )

    @classmethod
    def from_scene(cls, scene) -> PrimitiveCollider | None:
        """:meth:`from_model` for a scene's plate and skin, bound to its finger's joints so
        that :meth:`depths_at` reads the bone's pose from ``qpos``. What :meth:`from_model`
        reads does not move with the scene's placement (the plate is static, the nodes sit
        in the bone's frame), so the scenes placed from one kept model (``scene.model_key``)
        share it (:data:`KEPT`), each binding a copy of its own."""
        m = scene.m_col
        bone = m.body("bone").id
        key = scene.model_key
        if key and key in KEPT:
            KEPT.move_to_end(key)
            kept = KEPT[key]
        else:
            kept = cls.from_model(m, scene.node_of_geom, bone, scene.plate)
            if key:
                KEPT[key] = kept
                while len(KEPT) > KEPT_MAX:
                    KEPT.popitem(last=False)
        if kept is None:
            return None
        c = copy.copy(kept)  # its arrays are read only; bind sets the copy's own pose
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
        return depths_kernel(b, *self.probe, pen)

    def warnings(self) -> list[str]:
        return []

    def y_invariant(self, bone_y: float) -> bool:
        """Whether every node's depth is independent of its y for the bone at ``bone_y``: all
        plate geoms are unrotated boxes or drafted ridges that reach past every node in y by
        more than their smaller half-extent in x or z. Then a node's signed distance to each
        does not involve its y at all (the y-term is neither the largest inside nor nonzero
        outside), so nodes with equal x, z, radius and margin get bit-identical depths."""
        if not len(self.kind) or not np.isin(self.kind, (_BOX, _PRISM)).all():
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
            self.top,
        )

    def depths(self, bone_pos: np.ndarray, pen: np.ndarray) -> bool:
        """Fill ``pen`` (N,) with each node's deepest penetration [m] for the bone at world
        position ``bone_pos`` (3,); ``-inf`` where no plate geom is within the node's margin.
        Returns whether any node is within it."""
        return depths_kernel(bone_pos, *self.probe, pen)


def _half_extents(kind: np.ndarray, mat: np.ndarray, size: np.ndarray) -> np.ndarray:
    """World half extents (G, 3) of each geom's bounding box."""
    out = np.empty((len(kind), 3))
    for g in range(len(kind)):
        if kind[g] == _SPHERE:
            out[g] = size[g, 0]
        elif kind[g] == _CYLINDER:
            r, hz = size[g, 0], size[g, 1]
            out[g] = np.abs(mat[g]) @ np.array([r, r, hz])
        else:
            out[g] = np.abs(mat[g]) @ size[g]
    return out


def _drafted_ridge(m: mujoco.MjModel, d: mujoco.MjData, g: int, fs):
    """A mesh geom that is one of the plate's drafted ridges (its features ``fs``; by the
    geom's name ``fNNNN``, as :func:`~sim_tactile.plates.make.mjcf.plate_spec` names it) as ``(pos,
    mat, size, top)``: its mid-height centre in the world, the plate body's frame (unrotated),
    its bottom half-widths and half-height, its top half-width. None if it is not one, or the
    plate is rotated."""
    name = m.geom(g).name
    if fs is None or not (len(name) == 5 and name[0] == "f" and name[1:].isdigit()):
        return None
    i = int(name[1:])
    if i >= len(fs) or fs[i].kind != "prism":
        return None
    body = int(m.geom_bodyid[g])
    xmat = d.xmat[body].reshape(3, 3)
    if not (xmat == np.eye(3)).all():
        return None
    f = fs[i]
    pos = d.xpos[body] + np.array([f.x, f.y, f.height_m / 2])
    return pos, xmat.copy(), np.array([f.hx, f.hy, f.height_m / 2]), float(f.top_hx)


@njit
def depths_kernel(
    bone,
    local,
    radius,
    margin,
    kind,
    pos,
    mat,
    size,
    top,
    origin,
    cell,
    shape,
    start,
    items,
    cell_top,
    pen,
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
        if cz - r - cell_top[b] > margin[i]:  # above every geom of the cell by its margin
            pen[i] = -np.inf
            continue
        for k in range(start[b], start[b + 1]):
            g = items[k]
            dx = cx - pos[g, 0]
            dy = cy - pos[g, 1]
            dz = cz - pos[g, 2]
            if kind[g] == _SPHERE:
                dist = math.sqrt(dx * dx + dy * dy + dz * dz) - size[g, 0] - r
            elif kind[g] == _CYLINDER or kind[g] == _PRISM:
                lx = mat[g, 0, 0] * dx + mat[g, 1, 0] * dy + mat[g, 2, 0] * dz
                ly = mat[g, 0, 1] * dx + mat[g, 1, 1] * dy + mat[g, 2, 1] * dz
                lz = mat[g, 0, 2] * dx + mat[g, 1, 2] * dy + mat[g, 2, 2] * dz
                if kind[g] == _PRISM:
                    dist = ridge_distance(lx, ly, lz, size[g, 0], size[g, 1], size[g, 2], top[g])
                else:
                    upright = abs(mat[g, 2, 2] - 1.0) < 1e-12
                    dist = cylinder_distance(lx, ly, lz, size[g, 0], size[g, 1], upright)
                dist -= r
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
        near |= report_depth(pen, i, best, margin[i])
    return near
