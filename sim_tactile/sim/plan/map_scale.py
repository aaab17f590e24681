"""The lateral scales of a height map (:class:`~sim_tactile.plates.HeightMap`) that
:mod:`.fidelity` plans a node grid and a time step by, as it does by a plate's features:
the smallest feature width or gap, and the texture's period along the slide.

A map has no features to list, so they are read off its samples: where each row (along x) and
each column (along y) crosses the map's mid-level, halfway between its lowest and highest
sample (a sample without material lies below it). A run of samples above that level is a
feature, one below it a gap; only runs with a crossing at both ends count (those at the map's
edges are cut off). The feature scale is the smaller of the median feature run and the median
gap run, so one odd run (noise at a crossing, a scratch) does not set the grid; on a grating
of ridges 1 mm wide and 1 mm apart it is 1 mm, as :func:`~.fidelity.feature_scale_m` gives a
grating of features. The period is the median distance between successive rising crossings
along x.
"""

from __future__ import annotations

import numpy as np

from ...cache import register_memo

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
