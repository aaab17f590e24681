"""MuJoCo's own collider on the scene's collision model, for any geometry: the reference the
compiled colliders are tested against, and the collider of a plate none of them takes (a mesh
that is not a drafted ridge of the plate's features, a rotated plate). No preset plate steps
it."""

from __future__ import annotations

import mujoco
import numpy as np

from ..._jit import njit


@njit
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
