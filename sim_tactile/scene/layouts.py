"""Taxel layouts: where the taxels sit in the pad frame, how large and how deep.

A layout is data (positions, sizes, depths, layers), so users add their own with
:func:`grid_layout` or by constructing :class:`Layout`. Positions are (x along the slide,
y across, z out of the skin); a taxel at depth d has z = -d.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import _validate as v
from ..errors import ConfigError, UnknownNameError


@dataclass(frozen=True)
class Layout:
    """name; positions (N, 3) [m]; sizes (N, 2) [m] (x, y); layer (N,) int; rate_hz the
    hardware's sampling rate; channel names."""

    name: str
    positions: np.ndarray
    sizes: np.ndarray
    layer: np.ndarray
    rate_hz: float = 100.0
    names: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        pos = np.asarray(self.positions, float)
        sizes = np.asarray(self.sizes, float)
        layer = np.asarray(self.layer, int)
        n = len(pos)
        if pos.shape != (n, 3) or sizes.shape != (n, 2) or layer.shape != (n,) or n == 0:
            raise ConfigError(
                f"layout {self.name!r}: positions (N, 3), sizes (N, 2) and layer (N,) "
                f"must agree, got {pos.shape}, {sizes.shape}, {layer.shape}"
            )
        if (sizes <= 0).any():
            raise ConfigError(f"layout {self.name!r}: taxel sizes must be > 0")
        if (pos[:, 2] > 1e-12).any():
            raise ConfigError(
                f"layout {self.name!r}: taxels must sit at or under the surface (z <= 0)"
            )
        v.positive("layout.rate_hz", self.rate_hz, unit="Hz")
        object.__setattr__(self, "positions", pos)
        object.__setattr__(self, "sizes", sizes)
        object.__setattr__(self, "layer", layer)
        if not self.names:
            object.__setattr__(self, "names", tuple(f"t{i}" for i in range(n)))

    @property
    def n(self) -> int:
        return len(self.positions)

    @property
    def depth_m(self) -> np.ndarray:
        return -self.positions[:, 2]

    @property
    def extent_m(self) -> tuple[float, float]:
        """Half-extents (x, y) of the taxels' footprint [m]."""
        lo = (self.positions[:, :2] - self.sizes / 2).min(axis=0)
        hi = (self.positions[:, :2] + self.sizes / 2).max(axis=0)
        return float(max(-lo[0], hi[0])), float(max(-lo[1], hi[1]))

    @property
    def min_pitch_m(self) -> float:
        """Smallest centre-to-centre distance between taxels of one layer [m]."""
        best = np.inf
        for lay in np.unique(self.layer):
            p = self.positions[self.layer == lay, :2]
            if len(p) > 1:
                d = np.linalg.norm(p[:, None] - p[None], axis=-1)
                best = min(best, float(d[d > 0].min()))
        return best if np.isfinite(best) else float(self.sizes.min())

    def to_json(self) -> dict:
        return {
            "name": self.name,
            "n": self.n,
            "rate_hz": self.rate_hz,
            "positions_m": self.positions.tolist(),
            "sizes_m": self.sizes.tolist(),
            "layer": self.layer.tolist(),
        }


def grid_layout(
    name: str,
    nx: int,
    ny: int,
    pitch_m: float,
    size_m: float,
    *,
    depth_m: float = 0.0,
    rate_hz: float = 100.0,
) -> Layout:
    """An nx (along x) by ny grid of square taxels centred on the pad."""
    v.integer("nx", nx, 1, 1000)
    v.integer("ny", ny, 1, 1000)
    v.positive("pitch_m", pitch_m, unit="m")
    v.in_range("size_m", size_m, 0.0, None, lo_open=True, unit="m")
    v.non_negative("depth_m", depth_m, unit="m")
    xs = (np.arange(nx) - (nx - 1) / 2) * pitch_m
    ys = (np.arange(ny) - (ny - 1) / 2) * pitch_m
    X, Y = np.meshgrid(xs, ys, indexing="xy")  # row-major: y rows, x columns
    pos = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, -depth_m)])
    names = tuple(f"r{j}c{i}" for j in range(ny) for i in range(nx))
    return Layout(name, pos, np.full((X.size, 2), size_m), np.zeros(X.size, int), rate_hz, names)


def dense_layout(
    pitch_m: float, extent_m: tuple[float, float], *, rate_hz: float = 100.0
) -> Layout:
    """A dense grid of contiguous surface taxels of side ``pitch_m`` covering +-extent."""
    nx = 2 * int(np.floor(extent_m[0] / pitch_m)) + 1
    ny = 2 * int(np.floor(extent_m[1] / pitch_m)) + 1
    if nx * ny > 40_000:
        raise ConfigError(
            f"a dense grid of pitch {pitch_m:g} m has {nx * ny} taxels; valid: at most 40000"
        )
    return grid_layout(f"dense-{pitch_m * 1e3:g}mm", nx, ny, pitch_m, pitch_m, rate_hz=rate_hz)


#: grid3x3: the soft-finger paper's fabric array, 2 x 2 mm taxels at 2.5 mm, 100 Hz (seed 002).
_LAYOUTS = {
    "grid3x3": lambda: grid_layout("grid3x3", 3, 3, 2.5e-3, 2.0e-3, rate_hz=100.0),
}


def layout_names() -> list[str]:
    return list(_LAYOUTS)


def get_layout(name: str) -> Layout:
    """A named layout, or ``dense-<pitch in mm>mm`` for a dense grid of that pitch over 12 mm."""
    if name in _LAYOUTS:
        return _LAYOUTS[name]()
    if name.startswith("dense-") and name.endswith("mm"):
        try:
            pitch = float(name[6:-2]) * 1e-3
        except ValueError:
            pitch = -1.0
        if pitch > 0:
            return dense_layout(pitch, (6e-3, 6e-3))
    raise UnknownNameError(
        f"sensor layout {name!r} is not known; valid: {', '.join(_LAYOUTS)}, or dense-<pitch>mm (e.g. dense-0.25mm)"
    )
