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
    hardware's sampling rate; channel names; grid_shape ``(rows, cols)`` when the taxels form
    a grid in channel order (row-major; the LSTM's convolutional front reads it), else None."""

    name: str
    positions: np.ndarray
    sizes: np.ndarray
    layer: np.ndarray
    rate_hz: float = 100.0
    names: tuple[str, ...] = field(default=())
    grid_shape: tuple[int, int] | None = None

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
        if len(self.names) != n:
            raise ConfigError(
                f"layout {self.name!r}: {len(self.names)} channel names for {n} taxels"
            )
        if self.grid_shape is not None:
            rows, cols = (int(x) for x in self.grid_shape)
            if rows * cols != n:
                raise ConfigError(
                    f"layout {self.name!r}: grid_shape {self.grid_shape} holds {rows * cols} "
                    f"taxels, the layout {n}; valid: rows * cols = {n}"
                )
            object.__setattr__(self, "grid_shape", (rows, cols))

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
            "names": list(self.names),
            "grid_shape": None if self.grid_shape is None else list(self.grid_shape),
        }


#: How far two taxels' footprints may reach into each other and still count as touching [m]
#: (a nanometre: a grid whose taxels are as wide as its pitch touches within rounding).
TOUCH_TOL_M = 1e-9


def overlapping_taxels(layout: Layout) -> tuple[int, int] | None:
    """The first pair ``(i, j)``, ``i < j``, of taxels of one layer whose footprints
    (``sizes`` centred on ``positions`` in x and y) overlap by more than
    :data:`TOUCH_TOL_M` in both directions; None where none do (footprints may touch)."""
    xy, half = layout.positions[:, :2], layout.sizes / 2
    for lay in np.unique(layout.layer):
        idx = np.flatnonzero(layout.layer == lay)
        for start in range(0, len(idx), 256):  # 256 x N pairs at a time (N <= 4096)
            a = idx[start : start + 256]
            gap = np.abs(xy[a, None] - xy[None, idx]) - (half[a, None] + half[None, idx])
            over = (gap < -TOUCH_TOL_M).all(axis=-1) & (idx[None, :] > a[:, None])
            hit = np.argwhere(over)
            if len(hit):
                return int(a[hit[0, 0]]), int(idx[hit[0, 1]])
    return None


def overlap_text(layout: Layout, i: int, j: int) -> str:
    """Where taxels ``i`` and ``j`` overlap, in words (for an error)."""
    (xi, yi), (xj, yj) = layout.positions[i, :2] * 1e3, layout.positions[j, :2] * 1e3
    (si, ti), (sj, tj) = layout.sizes[i] * 1e3, layout.sizes[j] * 1e3
    wx = min(xi + si / 2, xj + sj / 2) - max(xi - si / 2, xj - sj / 2)
    wy = min(yi + ti / 2, yj + tj / 2) - max(yi - ti / 2, yj - tj / 2)
    return (
        f"taxels {i} ({layout.names[i]}, {si:.4g} x {ti:.4g} mm at x = {xi:.4g}, y = {yi:.4g} "
        f"mm) and {j} ({layout.names[j]}, {sj:.4g} x {tj:.4g} mm at x = {xj:.4g}, y = "
        f"{yj:.4g} mm) of layer {int(layout.layer[i])} overlap by {wx:.4g} x {wy:.4g} mm"
    )


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
    sizes = np.full((X.size, 2), size_m)
    return Layout(name, pos, sizes, np.zeros(X.size, int), rate_hz, names, (ny, nx))


def dense_layout(
    pitch_m: float, extent_m: tuple[float, float], *, rate_hz: float = 100.0, depth_m: float = 0.0
) -> Layout:
    """A dense grid of contiguous taxels of side ``pitch_m`` covering +-extent, at the
    surface or ``depth_m`` under it."""
    nx = 2 * int(np.floor(extent_m[0] / pitch_m)) + 1
    ny = 2 * int(np.floor(extent_m[1] / pitch_m)) + 1
    if nx * ny > 40_000:
        raise ConfigError(
            f"a dense grid of pitch {pitch_m:g} m has {nx * ny} taxels; valid: at most 40000"
        )
    return grid_layout(
        f"dense-{pitch_m * 1e3:g}mm", nx, ny, pitch_m, pitch_m, rate_hz=rate_hz, depth_m=depth_m
    )


def multilayer_layout() -> Layout:
    """multilayer3x3x2 (seed 003): two 3x3 layers of 3 x 3 mm elements at 5 mm pitch; the top
    layer (0) 0.5 mm under the surface, the bottom layer (1) 2 mm under it; 100 Hz."""
    top = grid_layout("top", 3, 3, 5e-3, 3e-3, depth_m=0.5e-3)
    bot = grid_layout("bottom", 3, 3, 5e-3, 3e-3, depth_m=2.0e-3)
    names = tuple(f"top_{n}" for n in top.names) + tuple(f"bottom_{n}" for n in bot.names)
    return Layout(
        "multilayer3x3x2",
        np.vstack([top.positions, bot.positions]),
        np.vstack([top.sizes, bot.sizes]),
        np.r_[np.zeros(9, int), np.ones(9, int)],
        100.0,
        names,
    )  # no grid_shape: two layers


def biotac_layout() -> Layout:
    """biotac19 (seed 000): 19 impedance electrodes on the BioTac's core, under about 2.5 mm
    of fluid and skin, as five staggered columns (3, 4, 5, 4, 3) over 16 x 10 mm; 100 Hz.
    An approximation of the real electrode map, which is curved around the core."""
    pos = []
    for col, n in zip((-2, -1, 0, 1, 2), (3, 4, 5, 4, 3), strict=True):
        for k in range(n):
            pos.append((col * 3.5e-3 * 0.866 * 1.3, (k - (n - 1) / 2) * 2.6e-3, -2.5e-3))
    pos = np.array(pos)
    return Layout(
        "biotac19",
        pos,
        np.full((19, 2), 1.5e-3),
        np.zeros(19, int),
        100.0,
        tuple(f"ele{i + 1}" for i in range(19)),
    )


def icub_layout() -> Layout:
    """icub60 (seed 000): six triangular modules of ten taxels (rows of 1, 2, 3, 4 at 2.6 mm),
    2 mm taxels 0.5 mm under a foam cover, modules alternately pointing up and down in a 3 x 2
    arrangement over about 28 x 16 mm; 50 Hz."""
    s = 2.6e-3
    tri = np.array(
        [((k - j / 2) * s, (j - 1.5) * s * 0.866) for j in range(4) for k in range(j + 1)]
    )
    tri[:, 1] -= tri[:, 1].mean()
    pos = []
    for m in range(6):
        cx, cy = (m % 3 - 1) * 9.5e-3, (m // 3 - 0.5) * 9e-3
        flip = -1.0 if (m % 3 + m // 3) % 2 else 1.0
        pos += [(cx + x, cy + flip * y, -0.5e-3) for x, y in tri]
    pos = np.array(pos)
    names = tuple(f"m{m}t{k}" for m in range(6) for k in range(10))
    return Layout(
        "icub60", pos, np.full((60, 2), 2e-3), np.repeat(np.arange(6), 10), 50.0, names, (6, 10)
    )


def pvdf_layout() -> Layout:
    """pvdf2 (seed 001): two PVDF films 1 mm under the surface of a fingertip, film 1 across
    the slide (1 x 8 mm), film 2 along it (8 x 1 mm); 1 kHz."""
    pos = np.array([(0.0, -2.0e-3, -1e-3), (0.0, 2.5e-3, -1e-3)])
    sizes = np.array([(1e-3, 8e-3), (8e-3, 1e-3)])
    return Layout("pvdf2", pos, sizes, np.array([0, 1]), 1000.0, ("film1_across", "film2_along"))


#: grid3x3: the soft-finger paper's fabric array, 2 x 2 mm taxels at 2.5 mm, 100 Hz (seed 002).
_LAYOUTS = {
    "grid3x3": lambda: grid_layout("grid3x3", 3, 3, 2.5e-3, 2.0e-3, rate_hz=100.0),
    "multilayer3x3x2": multilayer_layout,
    "biotac19": biotac_layout,
    "icub60": icub_layout,
    "pvdf2": pvdf_layout,
}


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
