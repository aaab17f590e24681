"""Per-step readout kernels (numba): MuJoCo contacts -> the skin's penetration-depth map.

Tested for equality against a plain numpy version (``np.maximum.at``) in the tests.
"""

from __future__ import annotations

import numba
import numpy as np


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
    pen = np.full(n_nodes, -np.inf)
    node = node_of_geom[geom[:, 0]]
    node = np.where(node >= 0, node, node_of_geom[geom[:, 1]])
    keep = node >= 0
    np.maximum.at(pen, node[keep], -dist[keep])
    return pen
