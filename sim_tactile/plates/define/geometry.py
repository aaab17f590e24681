"""The raised features of a plate: their shapes, heights and layouts, in SI units.

A :class:`Feature` is one raised shape on top of the plate's base (z from 0 to its height);
the layout helpers expand a texture's parameters into features over a textured area of a
given size, checking that they fit and do not overlap. Nothing here knows about plates: the
texture classes of :mod:`.spec` call these helpers with their own numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ...errors import ConfigError

#: Slack when checking that a feature stays inside the textured area [m].
FIT_TOL_M = 1e-9


@dataclass(frozen=True)
class Feature:
    """One raised feature on top of the base (z from 0 to ``height_m``).

    kind ``box``: footprint ``2 hx`` by ``2 hy``; ``prism``: a drafted ridge along y, bottom
    half-width ``hx``, top half-width ``top_hx``, half-length ``hy``; ``cylinder``: radius
    ``hx``; ``cap``: a spherical cap of footprint radius ``hx`` (a hemisphere when
    ``height_m == hx``), i.e. a sphere of radius :attr:`sphere_radius_m` centred at
    z = :attr:`sphere_z_m`.
    """

    kind: Literal["box", "prism", "cylinder", "cap"]
    x: float
    y: float
    hx: float
    hy: float
    height_m: float
    top_hx: float = 0.0

    @property
    def sphere_radius_m(self) -> float:
        return (self.hx**2 + self.height_m**2) / (2 * self.height_m)

    @property
    def sphere_z_m(self) -> float:
        return self.height_m - self.sphere_radius_m

    def height(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Height of this feature's top above z = 0 at (x, y) [m]; 0 outside its footprint."""
        dx = np.abs(x - self.x)
        dy = np.abs(y - self.y)
        h = self.height_m
        if self.kind == "box":
            return np.where((dx <= self.hx) & (dy <= self.hy), h, 0.0)
        if self.kind == "prism":
            slope_run = self.hx - self.top_hx
            z = (
                np.clip((self.hx - dx) / slope_run * h, 0.0, h)
                if slope_run > 0
                else np.full_like(dx, h)
            )
            return np.where((dx <= self.hx) & (dy <= self.hy), z, 0.0)
        rho2 = dx**2 + dy**2
        if self.kind == "cylinder":
            return np.where(rho2 <= self.hx**2, h, 0.0)
        r = self.sphere_radius_m
        z = self.sphere_z_m + np.sqrt(np.maximum(r * r - rho2, 0.0))
        return np.where(rho2 <= self.hx**2, np.maximum(z, 0.0), 0.0)


def ridge_features(
    area_length_m: float,
    area_width_m: float,
    count: int,
    width: float,
    height: float,
    draft_deg: float,
    length: float | None,
    label: str,
) -> list[Feature]:
    """``count`` ridges along y spread evenly over the area's length (pitch ``Lx / count``)."""
    pitch = area_length_m / count
    if count > 1 and pitch <= width:
        raise ConfigError(
            f"{label}: {count} ridges of width {width:g} m on {area_length_m:g} m overlap "
            f"(pitch {pitch:g} m); valid: count < {area_length_m / width:g} or a smaller width"
        )
    if width > area_length_m + FIT_TOL_M:
        raise ConfigError(
            f"{label}.width_m = {width:g} m leaves the textured area; valid: (0, {area_length_m:g}] m"
        )
    length = area_width_m if length is None else length
    if length > area_width_m + FIT_TOL_M:
        raise ConfigError(
            f"{label}.length_m = {length:g} m leaves the textured area; valid: (0, {area_width_m:g}] m"
        )
    top = width - 2 * height * math.tan(math.radians(draft_deg))
    kind = "prism" if draft_deg > 0 else "box"
    x0 = -area_length_m / 2
    return [
        Feature(kind, x0 + (i + 0.5) * pitch, 0.0, width / 2, length / 2, height, top / 2)
        for i in range(count)
    ]


def grating_features(
    area_length_m: float,
    area_width_m: float,
    period: float,
    width: float,
    height: float,
    draft_deg: float,
) -> list[Feature]:
    """``floor(Lx / period)`` ridges along y at exactly ``period``, centred on the area."""
    count = math.floor(area_length_m / period + 1e-9)
    if count < 1:
        raise ConfigError(
            f"grating.period_m = {period:g} m is longer than the textured area; "
            f"valid: (0, {area_length_m:g}] m"
        )
    # a grating's pitch is its period: centre `count` periods on the area
    span = count * period
    x0 = -span / 2
    top = width - 2 * height * math.tan(math.radians(draft_deg))
    kind = "prism" if draft_deg > 0 else "box"
    hy = area_width_m / 2
    return [
        Feature(kind, x0 + (i + 0.5) * period, 0.0, width / 2, hy, height, top / 2)
        for i in range(count)
    ]


def bump_features(
    area_length_m: float,
    area_width_m: float,
    rows: int,
    cols: int,
    shape: str,
    size: float,
    height: float,
    spacing: float | None,
) -> list[Feature]:
    """A ``rows`` (y) by ``cols`` (x) grid of bumps centred on the origin (x-major order)."""
    spacing = spacing or min(area_length_m / cols, area_width_m / rows)
    if (rows > 1 or cols > 1) and spacing <= size:
        raise ConfigError(
            f"bumps: spacing {spacing:g} m makes bumps of size_m = {size:g} m overlap; "
            f"valid: spacing_m > {size:g} m or fewer rows/cols"
        )
    ext_x = (cols - 1) * spacing + size
    ext_y = (rows - 1) * spacing + size
    if ext_x > area_length_m + FIT_TOL_M or ext_y > area_width_m + FIT_TOL_M:
        raise ConfigError(
            f"bumps: a {rows}x{cols} grid at spacing {spacing:g} m spans {ext_x:g} x "
            f"{ext_y:g} m and leaves the textured area {area_length_m:g} x "
            f"{area_width_m:g} m; valid: (cols-1)*spacing_m + size_m <= area_length_m"
        )
    kind = {"box": "box", "cylinder": "cylinder", "hemisphere": "cap"}[shape]
    r = size / 2
    out = []
    for i in range(cols):
        for j in range(rows):
            x = (i - (cols - 1) / 2) * spacing
            y = (j - (rows - 1) / 2) * spacing
            out.append(Feature(kind, x, y, r, r, float(height)))
    return out
