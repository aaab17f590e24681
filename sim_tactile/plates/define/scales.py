"""A plate's lateral scales, one formula each: the smallest feature width or gap (what the
node grid must resolve), the texture's period along the slide (what the taxels alias and the
anchored lattice repeats over), and the walls of its boxes (what the clipped and anchored
grids follow). A plate of features reads them off its features; a height map, which has no
features to list, off its samples (:func:`map_scales`). :class:`~.surface.Surface` asks
here, and the simulator asks the surface.

A height map's scales: where each row (along x) and each column (along y) crosses the map's
mid-level, halfway between its lowest and highest sample (a sample without material lies
below it). A run of samples above that level is a feature, one below it a gap; only runs
with a crossing at both ends count (those at the map's edges are cut off). The feature scale
is the smaller of the median feature run and the median gap run, so one odd run (noise at a
crossing, a scratch) does not set the grid; on a grating of ridges 1 mm wide and 1 mm apart
it is 1 mm, as :func:`feature_scale_m` gives a grating of features. The period is the median
distance between successive rising crossings along x.
"""

from __future__ import annotations

import numpy as np

from ...cache import register_memo
from .geometry import Feature

#: The scales of the maps seen in this process, by their samples' SHA-256 and pixel.
_SEEN: dict[tuple[str, float], tuple[float | None, float | None]] = {}
register_memo("height-map scales", _SEEN.clear)


def _crossings(above: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Along each row of ``above`` (bool): the interior runs' lengths [samples], whether each
    is a run above the level, and the distances [samples] between successive rising
    crossings of one row."""
    r, c = np.nonzero(above[:, 1:] != above[:, :-1])  # a crossing between c and c + 1
    rising = above[r, c + 1]
    same = r[1:] == r[:-1]
    runs, high = np.diff(c)[same], rising[:-1][same]
    rr, rc = r[rising], c[rising]
    periods = np.diff(rc)[rr[1:] == rr[:-1]]
    return runs, high, periods


def map_scales(texture) -> tuple[float | None, float | None]:
    """``(feature scale [m], period along x [m])`` of a height map (see the module
    docstring); None where the map has no interior run (or no two rising crossings in a
    row). Kept per process by the samples' hash."""
    key = (texture.sha256, float(texture.pixel_m))
    if key not in _SEEN:
        z = texture.z
        lo, hi = float(np.nanmin(z)), float(np.nanmax(z))
        above = np.nan_to_num(z, nan=-np.inf) > (lo + hi) / 2
        runs_x, high_x, periods = _crossings(above)
        runs_y, high_y, _ = _crossings(above.T)
        runs = np.concatenate([runs_x, runs_y])
        high = np.concatenate([high_x, high_y])
        medians = [float(np.median(runs[k])) for k in (high, ~high) if k.any()]
        p = texture.pixel_m
        scale = min(medians) * p if medians else None
        period = float(np.median(periods)) * p if periods.size else None
        _SEEN[key] = (scale, period)
    return _SEEN[key]


def feature_scale_m(fs: list[Feature]) -> float | None:
    """The smallest feature width or gap [m] of features ``fs`` (widths along x and y, gaps
    between feature columns and rows; at least 1 um); None without features."""
    if not fs:
        return None
    widths = [2 * f.hx for f in fs] + [2 * f.hy for f in fs]
    xs = sorted({round(f.x, 9) for f in fs})
    gaps = [b - a - 2 * fs[0].hx for a, b in zip(xs, xs[1:], strict=False)]
    ys = sorted({round(f.y, 9) for f in fs})
    if len(ys) > 1:
        gaps += [b - a - 2 * fs[0].hy for a, b in zip(ys, ys[1:], strict=False)]
    return max(min(widths + [g for g in gaps if g > 0]), 1e-6)


def feature_period_m(fs: list[Feature]) -> float | None:
    """The texture's period along the slide [m]: the smallest spacing of the feature columns'
    x (to the nanometre); None for fewer than two columns."""
    xs = sorted({round(f.x, 9) for f in fs})
    if len(xs) < 2:
        return None
    return min(b - a for a, b in zip(xs, xs[1:], strict=False))


def box_walls(fs: list[Feature]) -> tuple[np.ndarray, np.ndarray]:
    """The x positions of the boxes' vertical walls across the slide and the y positions of
    those along it [m], sorted (each to the picometre): the faces of ridges, bumps and
    grating bars. Empty where no feature is a box."""
    xs, ys = set(), set()
    for f in fs:
        if f.kind == "box":
            xs.update((round(f.x - f.hx, 12), round(f.x + f.hx, 12)))
            ys.update((round(f.y - f.hy, 12), round(f.y + f.hy, 12)))
    return np.array(sorted(xs)), np.array(sorted(ys))
