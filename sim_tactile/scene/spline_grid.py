"""A periodic cubic spline read on a tensor grid of points: what
:func:`scipy.ndimage.map_coordinates` gives there (``order=3, mode="grid-wrap",
prefilter=False``), in two passes of four taps (one along each axis) instead of sixteen taps
a point. The layered skin's kept stress tables are read so at the rig's node lattice."""

from __future__ import annotations

import numpy as np


def tensor_grid(node_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """``(xs, ys)`` when the nodes are the rows of a tensor grid (``x`` fastest: node ``j nx
    + i`` at ``(xs[i], ys[j])``), else None."""
    n = len(node_xy)
    if n < 2:
        return None
    y0 = node_xy[0, 1]
    nx = int(np.argmax(node_xy[:, 1] != y0)) or n
    if n % nx:
        return None
    xy = node_xy.reshape(n // nx, nx, 2)
    xs, ys = xy[0, :, 0], xy[:, 0, 1]
    if not (
        np.array_equal(xy[:, :, 0], np.broadcast_to(xs, xy.shape[:2]))
        and np.array_equal(xy[:, :, 1], np.broadcast_to(ys[:, None], xy.shape[:2]))
    ):
        return None
    return xs, ys


def cubic_taps(c: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The periodic cubic B-spline's four taps at coordinates ``c``: indices (len(c), 4)
    (wrapped into ``n``) and weights (len(c), 4)."""
    f = np.floor(c)
    t = c - f
    idx = (f.astype(np.int64)[:, None] + np.arange(-1, 3)) % n
    t2, t3 = t * t, t * t * t
    w = np.column_stack(
        [(1 - t) ** 3 / 6, (3 * t3 - 6 * t2 + 4) / 6, (-3 * t3 + 3 * t2 + 3 * t + 1) / 6, t3 / 6]
    )
    return idx, w


def spline_on_grid(coef: np.ndarray, cx: np.ndarray, cy: np.ndarray) -> np.ndarray:
    """(len(cy), len(cx)): the periodic cubic spline of coefficients ``coef`` (axis 0 along
    x) at every ``(cx[i], cy[j])``, in grid units: what :func:`scipy.ndimage.map_coordinates`
    (``order=3, mode="grid-wrap", prefilter=False``) gives at those points (to round-off,
    tested), in two passes of four taps over the columns the points reach instead of sixteen
    taps a point."""
    ix, wx = cubic_taps(np.asarray(cx, float), coef.shape[0])
    iy, wy = cubic_taps(np.asarray(cy, float), coef.shape[1])
    cols, inv = np.unique(iy, return_inverse=True)
    part = coef[:, cols]  # only the columns any point reaches
    along_x = np.einsum("ia,iac->ic", wx, part[ix])  # (len(cx), len(cols))
    return np.einsum("jb,ijb->ji", wy, along_x[:, inv.reshape(iy.shape)])
