"""Expand a plate into its features and evaluate its analytic surface height.

This is the plate's *definition*: the CAD solid, the MuJoCo collision geometry and the
preview are all generated from :func:`features` (and :func:`roughness_profile`), and the
tests check that each of them agrees with :func:`height_at`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Literal

import numpy as np

from ..errors import ConfigError

if TYPE_CHECKING:
    from .spec import Plate

#: Slack when checking that a feature stays inside the textured area [m].
_FIT_TOL_M = 1e-9


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


def _ridge_features(
    plate: Plate,
    count: int,
    width: float,
    height: float,
    draft_deg: float,
    length: float | None,
    label: str,
) -> list[Feature]:
    pitch = plate.area_length_m / count
    if count > 1 and pitch <= width:
        raise ConfigError(
            f"{label}: {count} ridges of width {width:g} m on {plate.area_length_m:g} m overlap "
            f"(pitch {pitch:g} m); valid: count < {plate.area_length_m / width:g} or a smaller width"
        )
    if width > plate.area_length_m + _FIT_TOL_M:
        raise ConfigError(
            f"{label}.width_m = {width:g} m leaves the textured area; valid: (0, {plate.area_length_m:g}] m"
        )
    length = plate.area_width_m if length is None else length
    if length > plate.area_width_m + _FIT_TOL_M:
        raise ConfigError(
            f"{label}.length_m = {length:g} m leaves the textured area; valid: (0, {plate.area_width_m:g}] m"
        )
    top = width - 2 * height * math.tan(math.radians(draft_deg))
    kind = "prism" if draft_deg > 0 else "box"
    x0 = -plate.area_length_m / 2
    return [
        Feature(kind, x0 + (i + 0.5) * pitch, 0.0, width / 2, length / 2, height, top / 2)
        for i in range(count)
    ]


def features(plate: Plate) -> list[Feature]:
    """The plate's raised features, in a fixed order (x-major). Raises ConfigError if they
    overlap or leave the textured area. Roughness plates have none (see
    :func:`roughness_profile`)."""
    from .spec import Bumps, Flat, Grating, Ridges, Roughness

    t = plate.texture
    if isinstance(t, Flat | Roughness):
        return []
    if isinstance(t, Ridges):
        return _ridge_features(
            plate, t.count, t.width_m, t.height_m, t.draft_deg, t.length_m, "ridges"
        )
    if isinstance(t, Grating):
        count = math.floor(plate.area_length_m / t.period_m + 1e-9)
        if count < 1:
            raise ConfigError(
                f"grating.period_m = {t.period_m:g} m is longer than the textured area; "
                f"valid: (0, {plate.area_length_m:g}] m"
            )
        width = t.ridge_width_m
        # a grating's pitch is its period: centre `count` periods on the area
        span = count * t.period_m
        x0 = -span / 2
        top = width - 2 * t.height_m * math.tan(math.radians(t.draft_deg))
        kind = "prism" if t.draft_deg > 0 else "box"
        hy = plate.area_width_m / 2
        return [
            Feature(kind, x0 + (i + 0.5) * t.period_m, 0.0, width / 2, hy, t.height_m, top / 2)
            for i in range(count)
        ]
    if isinstance(t, Bumps):
        spacing = t.spacing_m or min(plate.area_length_m / t.cols, plate.area_width_m / t.rows)
        if (t.rows > 1 or t.cols > 1) and spacing <= t.size_m:
            raise ConfigError(
                f"bumps: spacing {spacing:g} m makes bumps of size_m = {t.size_m:g} m overlap; "
                f"valid: spacing_m > {t.size_m:g} m or fewer rows/cols"
            )
        ext_x = (t.cols - 1) * spacing + t.size_m
        ext_y = (t.rows - 1) * spacing + t.size_m
        if ext_x > plate.area_length_m + _FIT_TOL_M or ext_y > plate.area_width_m + _FIT_TOL_M:
            raise ConfigError(
                f"bumps: a {t.rows}x{t.cols} grid at spacing {spacing:g} m spans {ext_x:g} x "
                f"{ext_y:g} m and leaves the textured area {plate.area_length_m:g} x "
                f"{plate.area_width_m:g} m; valid: (cols-1)*spacing_m + size_m <= area_length_m"
            )
        kind = {"box": "box", "cylinder": "cylinder", "hemisphere": "cap"}[t.shape]
        r = t.size_m / 2
        out = []
        for i in range(t.cols):
            for j in range(t.rows):
                x = (i - (t.cols - 1) / 2) * spacing
                y = (j - (t.rows - 1) / 2) * spacing
                out.append(Feature(kind, x, y, r, r, float(t.height_m)))
        return out
    raise ConfigError(f"unknown texture {t!r}")  # pragma: no cover


@lru_cache(maxsize=32)
def _profile_cached(
    ra: float, lc: float, seed: int, dx: float, length: float
) -> tuple[np.ndarray, np.ndarray]:
    n = round(length / dx) + 1
    x = np.linspace(-length / 2, length / 2, n)
    dx = x[1] - x[0]
    # White noise filtered by the square root of a Gaussian spectrum, on a grid twice as long
    # so that the circular FFT does not join the two ends of the profile.
    m = 2 * n
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal(m)
    k = 2 * np.pi * np.fft.rfftfreq(m, d=dx)
    # autocorrelation exp(-(x/lc)^2)  <->  PSD proportional to exp(-(k lc)^2 / 4)
    z = np.fft.irfft(np.fft.rfft(noise) * np.exp(-((k * lc) ** 2) / 8), n=m)[:n]
    z -= z.mean()
    z *= ra / np.mean(np.abs(z))
    x.setflags(write=False)
    z.setflags(write=False)
    return x, z


def roughness_profile(plate: Plate) -> tuple[np.ndarray, np.ndarray]:
    """The sampled roughness profile ``(x, z)`` [m], shape (n,) each, read-only.

    Deterministic: the same parameters give the same bytes in any process (numpy's PCG64
    and pocketfft are deterministic on one platform).
    """
    from .spec import Roughness

    t = plate.texture
    if not isinstance(t, Roughness):
        raise ConfigError(f"plate {plate.name or plate.hash} has no roughness texture")
    return _profile_cached(t.ra_m, t.corr_length_m, t.seed, t.resolution_m, plate.area_length_m)


def height_at(plate: Plate, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray:
    """Analytic top-surface height z(x, y) [m] of the plate; broadcasts ``x`` and ``y``.

    Outside the plate's footprint the result is NaN. The base top is z = 0.
    """
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    z = np.zeros(x.shape)
    from .spec import Roughness

    if isinstance(plate.texture, Roughness):
        px, pz = roughness_profile(plate)
        inside = (np.abs(x) <= plate.area_length_m / 2) & (np.abs(y) <= plate.area_width_m / 2)
        z = np.where(inside, np.interp(x, px, pz), 0.0)
    else:
        for f in features(plate):
            np.maximum(z, f.height(x, y), out=z)
    off = (np.abs(x) > plate.length_m / 2) | (np.abs(y) > plate.width_m / 2)
    return np.where(off, np.nan, z)
