"""Top-surface heights of a triangle mesh on a regular grid (a z-buffer), in numpy.

Used to read back the exported STL: an independent view of the plate against which the
analytic definition and MuJoCo's collider are compared. For every upward-facing triangle,
the grid nodes inside its xy-projection get the triangle's plane height; a node keeps the
highest value. Vectorised over (triangle, node) candidate pairs, no Python loop per triangle.
"""

from __future__ import annotations

import numpy as np

#: Barycentric slack so nodes on shared edges are not lost to round-off.
_EDGE_EPS = 1e-9
_CHUNK = 2_000_000


def zbuffer(
    vertices: np.ndarray,
    faces: np.ndarray,
    xs: np.ndarray,
    ys: np.ndarray,
    *,
    lowest: bool = False,
    edge_eps: float = _EDGE_EPS,
    reach: float = 1e-9,
) -> np.ndarray:
    """Highest surface z at every node of the grid ``xs`` x ``ys`` (the lowest with
    ``lowest``).

    vertices: (V, 3); faces: (F, 3) int; xs: (nx,) and ys: (ny,) increasing and evenly
    spaced. Returns (ny, nx), NaN where no triangle covers the node. ``edge_eps``: the
    barycentric slack (negative: only nodes strictly inside a triangle count); ``reach``: how
    far beyond a triangle's bounding box a node is tried [grid steps].
    """
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    tri = vertices[faces]  # (F, 3, 3)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    nz = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    tri = tri[np.abs(nz) > 1e-15 * np.abs(e1).max() * np.abs(e2).max()]  # drop vertical walls
    dx, dy = xs[1] - xs[0], ys[1] - ys[0]
    lo = tri[:, :, :2].min(axis=1)
    hi = tri[:, :, :2].max(axis=1)
    ix0 = np.clip(np.ceil((lo[:, 0] - xs[0]) / dx - reach).astype(np.int64), 0, len(xs))
    ix1 = np.clip(np.floor((hi[:, 0] - xs[0]) / dx + reach).astype(np.int64) + 1, 0, len(xs))
    iy0 = np.clip(np.ceil((lo[:, 1] - ys[0]) / dy - reach).astype(np.int64), 0, len(ys))
    iy1 = np.clip(np.floor((hi[:, 1] - ys[0]) / dy + reach).astype(np.int64) + 1, 0, len(ys))
    nxs, nys = np.maximum(ix1 - ix0, 0), np.maximum(iy1 - iy0, 0)
    counts = nxs * nys
    out = np.full(len(ys) * len(xs), np.inf if lowest else -np.inf)
    pick = np.minimum if lowest else np.maximum
    # process triangles in chunks so that the candidate pairs fit in memory
    bounds = np.searchsorted(np.cumsum(counts), np.arange(_CHUNK, counts.sum() + _CHUNK, _CHUNK))
    start = 0
    for stop in np.unique(np.append(bounds + 1, len(tri))):
        sel = slice(start, min(stop, len(tri)))
        start = min(stop, len(tri))
        c = counts[sel]
        if c.sum() == 0:
            continue
        t_idx = np.repeat(np.arange(sel.start, sel.stop), c)
        k = np.arange(c.sum()) - np.repeat(np.cumsum(c) - c, c)
        w = nxs[t_idx]
        gx = ix0[t_idx] + k % w
        gy = iy0[t_idx] + k // w
        px, py = xs[gx], ys[gy]
        a, b, cc = tri[t_idx, 0], tri[t_idx, 1], tri[t_idx, 2]
        det = (b[:, 0] - a[:, 0]) * (cc[:, 1] - a[:, 1]) - (cc[:, 0] - a[:, 0]) * (
            b[:, 1] - a[:, 1]
        )
        l1 = ((px - a[:, 0]) * (cc[:, 1] - a[:, 1]) - (cc[:, 0] - a[:, 0]) * (py - a[:, 1])) / det
        l2 = ((b[:, 0] - a[:, 0]) * (py - a[:, 1]) - (px - a[:, 0]) * (b[:, 1] - a[:, 1])) / det
        l0 = 1 - l1 - l2
        inside = (l0 >= -edge_eps) & (l1 >= -edge_eps) & (l2 >= -edge_eps)
        z = a[:, 2] + l1 * (b[:, 2] - a[:, 2]) + l2 * (cc[:, 2] - a[:, 2])  # exact on flat faces
        pick.at(out, (gy * len(xs) + gx)[inside], z[inside])
    out[np.isinf(out)] = np.nan
    return out.reshape(len(ys), len(xs))
