"""A plate's surface: its raised features and its analytic height.

This is the plate's *definition*: the CAD solid, the MuJoCo collision geometry and the
preview are all generated from :func:`features` (and :func:`roughness_profile`), and the
tests check that each of them agrees with :func:`height_at`.
"""

from __future__ import annotations

import numpy as np

from ..cache import memoized
from ..errors import ConfigError
from .geometry import Feature
from .spec import Plate


def features(plate: Plate) -> list[Feature]:
    """The plate's raised features, in a fixed order (x-major). Raises ConfigError if they
    overlap or leave the textured area. Roughness plates have none (see
    :func:`roughness_profile`)."""
    return plate.texture.features(plate.area_length_m, plate.area_width_m)


@memoized("roughness profiles", maxsize=32)
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
    t = plate.texture
    if t.kind != "roughness":
        raise ConfigError(f"plate {plate.name or plate.hash} has no roughness texture")
    return _profile_cached(t.ra_m, t.corr_length_m, t.seed, t.resolution_m, plate.area_length_m)


def height_at(plate: Plate, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray:
    """Analytic top-surface height z(x, y) [m] of the plate; broadcasts ``x`` and ``y``.

    Outside the plate's footprint the result is NaN. The base top is z = 0.
    """
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    z = np.zeros(x.shape)
    inside = (np.abs(x) <= plate.area_length_m / 2) & (np.abs(y) <= plate.area_width_m / 2)
    if plate.texture.kind == "roughness":
        px, pz = roughness_profile(plate)
        z = np.where(inside, np.interp(x, px, pz), 0.0)
    elif plate.texture.kind == "heightmap":
        t = plate.texture
        ex, ey = t.extent_m
        on_map = (np.abs(x) <= ex / 2) & (np.abs(y) <= ey / 2)
        z = np.where(on_map, map_height(x, y, t.z, t.pixel_m), 0.0)
    else:
        for f in features(plate):
            np.maximum(z, f.height(x, y), out=z)
    off = (np.abs(x) > plate.length_m / 2) | (np.abs(y) > plate.width_m / 2)
    return np.where(off, np.nan, z)


def map_height(x: np.ndarray, y: np.ndarray, z: np.ndarray, pixel: float) -> np.ndarray:
    """Bilinear height of the map ``z`` (ny, nx) [m], sampled every ``pixel`` [m] and centred
    on the origin, at ``(x, y)`` (broadcast); NaN where a corner of the cell is NaN (no
    material). Points beyond the map take its edge cells' extrapolation: callers mask them.

    The arithmetic, in this order, is the compiled collider's (tested bit for bit): ``fx =
    (x + (nx - 1) pixel / 2) / pixel``, ``j = clip(floor(fx), 0, nx - 2)``, ``tx = fx - j``
    (so for y), then ``(1 - ty) ((1 - tx) z00 + tx z01) + ty ((1 - tx) z10 + tx z11)``.
    """
    ny, nx = z.shape
    fx = (x + (nx - 1) * pixel / 2) / pixel
    fy = (y + (ny - 1) * pixel / 2) / pixel
    j = np.clip(np.floor(fx), 0, nx - 2).astype(np.intp)
    i = np.clip(np.floor(fy), 0, ny - 2).astype(np.intp)
    tx, ty = fx - j, fy - i
    lower = (1 - tx) * z[i, j] + tx * z[i, j + 1]
    upper = (1 - tx) * z[i + 1, j] + tx * z[i + 1, j + 1]
    return (1 - ty) * lower + ty * upper
