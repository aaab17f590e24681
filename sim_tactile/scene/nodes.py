"""The skin's nodes: rectangular patches tiling a pad, each probing the plate.

:func:`skin_grid` discretises a :class:`~sim_tactile.sensors.pad.Finger`'s pad into nodes of
a given pitch; each node carries the load of its patch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _validate as v
from ..errors import ConfigError
from ..sensors.pad import Finger


@dataclass(frozen=True)
class SkinGrid:
    """Skin nodes: rectangular patches of ``pitch_m`` (x, the slide) by ``pitch_y_m`` (y;
    None: square) tiling the pad's patch.

    xy: (N, 2) node centres [m] in the pad frame; z: (N,) undeformed surface height [m].
    """

    pitch_m: float
    xy: np.ndarray
    z: np.ndarray
    pitch_y_m: float | None = None

    @property
    def n(self) -> int:
        return len(self.z)

    @property
    def pitch_xy(self) -> tuple[float, float]:
        return (self.pitch_m, self.pitch_y_m or self.pitch_m)

    @property
    def lattice(self) -> tuple[int, int]:
        """``(nx, ny)``: the nodes per row along x and the rows along y (node ``iy * nx +
        ix``)."""
        ny = int(np.count_nonzero(self.xy[:, 0] == self.xy[0, 0]))
        return self.n // ny, ny

    @property
    def area_m2(self) -> float:
        px, py = self.pitch_xy
        return px * py


def lattice_shape(finger: Finger, pitch_m: float, pitch_y_m: float | None = None):
    """``(nx, ny)``: the nodes :func:`skin_grid` lays along x and y on the finger's patch at
    these pitches (an odd count per side), without its range checks."""
    px, py = finger.patch_m
    nx = 2 * int(np.floor(px / pitch_m / 2)) + 1
    ny = 2 * int(np.floor(py / (pitch_y_m or pitch_m) / 2)) + 1
    return nx, ny


def skin_grid(finger: Finger, pitch_m: float, pitch_y_m: float | None = None) -> SkinGrid:
    """Nodes at ``pitch_m`` along x and ``pitch_y_m`` (default: the same) along y over the
    finger's patch (an odd count per side, so a node sits at the pad's centre)."""
    v.in_range("skin pitch_m", pitch_m, 20e-6, 5e-3, unit="m")
    if pitch_y_m is not None:
        v.in_range("skin pitch_y_m", pitch_y_m, 20e-6, 5e-3, unit="m")
    qy = pitch_y_m or pitch_m
    px, py = finger.patch_m
    nx, ny = lattice_shape(finger, pitch_m, pitch_y_m)
    if nx * ny > 20_000:
        raise ConfigError(
            f"skin pitch_m = {pitch_m:g} m (y {qy:g} m) gives {nx * ny} nodes; valid: at most "
            f"20000 (pitch_m >= {max(px, py) / 141:g} m for this pad)"
        )
    xs = (np.arange(nx) - (nx - 1) / 2) * pitch_m
    ys = (np.arange(ny) - (ny - 1) / 2) * qy
    X, Y = np.meshgrid(xs, ys, indexing="xy")
    xy = np.column_stack([X.ravel(), Y.ravel()])
    return SkinGrid(
        pitch_m,
        xy,
        finger.surface(xy[:, 0], xy[:, 1]),
        None if pitch_y_m is None or pitch_y_m == pitch_m else pitch_y_m,
    )
