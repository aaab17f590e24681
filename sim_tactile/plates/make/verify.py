"""Compare three independent views of a plate: the analytic definition, the exported STL
(z-buffered) and MuJoCo's collider (probed, see :mod:`.probe`).

:func:`compare_views` returns the figures the tests assert on and the manual's plates
reference quotes: feature
counts (connected regions above half the peak height), peak heights, and the largest height
differences between views away from walls; for roughness plates, Ra from each view.
"""

from __future__ import annotations

import io
from dataclasses import asdict, dataclass

import numpy as np
from scipy import ndimage

from ...cache import ArtefactCache
from ..define.spec import Plate
from ..define.surface import surface_of
from ..parts.zbuffer import zbuffer
from .build import build
from .probe import ColliderProbe

MM = 1e-3
#: "Away from walls": farther than this from any jump or slope steeper than 60 degrees [m].
#: Tessellation error on a steep flank grows as 1/cos(slope); walls are discontinuities.
WALL_CLEARANCE_M = 0.15 * MM
STEEP_SLOPE = float(np.tan(np.radians(60)))
FINE_STEP_M = 0.1 * MM  # analytic and STL grid
PROBE_STEP_M = 0.5 * MM  # collider grid (a probe costs tens of microseconds)


@dataclass
class ViewReport:
    """Agreement between the views of one plate (heights in m)."""

    name: str
    counts: dict[str, int]
    peak_m: dict[str, float]
    max_diff_m: dict[str, float]
    checked_fraction: float
    ra_m: dict[str, float] | None = None

    def to_json(self) -> dict:
        return asdict(self)


def away_from_walls(plate: Plate, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """True where the analytic surface has no jump or steep slope within the clearance."""
    height = surface_of(plate).height
    z0 = height(X, Y)
    ok = np.ones(X.shape, bool)
    for ang in np.linspace(0, 2 * np.pi, 16, endpoint=False):
        for r in (WALL_CLEARANCE_M / 3, WALL_CLEARANCE_M):
            z = height(X + r * np.cos(ang), Y + r * np.sin(ang))
            ok &= np.abs(z - z0) <= STEEP_SLOPE * r
    return ok


def count_features(z: np.ndarray, peak_m: float) -> int:
    """Connected regions (4-neighbour) above half of ``peak_m``."""
    return int(ndimage.label(z > peak_m / 2)[1]) if peak_m > 0 else 0


def stl_heights(stl_bytes: bytes, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Z-buffer of an STL written in mm, on the grid xs x ys [m]; (ny, nx) [m]."""
    import trimesh

    mesh = trimesh.load(io.BytesIO(stl_bytes), file_type="stl")
    return zbuffer(mesh.vertices * 1e-3, mesh.faces, xs, ys)


def _ra(z: np.ndarray) -> float:
    return float(np.mean(np.abs(z - z.mean())))


def compare_views(plate: Plate, *, cache: ArtefactCache | None = None) -> ViewReport:
    res = build(plate, kinds=("stl", "mjcf"), cache=cache)
    stl = res.files["stl"].read_bytes()
    probe = ColliderProbe(res.files["mjcf"].read_text())
    surface = surface_of(plate)
    if surface.profile is not None:
        return _compare_roughness(plate, stl, probe)
    hx, hy = plate.area_length_m / 2 + 1 * MM, plate.area_width_m / 2 - 0.1 * MM
    xs = np.arange(-hx, hx, FINE_STEP_M) + 1.3e-6  # offsets keep nodes off feature edges
    ys = np.arange(-hy, hy, FINE_STEP_M) + 1.7e-6
    X, Y = np.meshgrid(xs, ys)
    z_an = surface.height(X, Y)
    z_stl = stl_heights(stl, xs, ys)
    xc = np.arange(-hx, hx, PROBE_STEP_M) + 2.3e-6
    yc = np.arange(-hy, hy, PROBE_STEP_M) + 3.1e-6
    Xc, Yc = np.meshgrid(xc, yc)
    z_col = probe.heights(Xc, Yc)
    z_stl_c = stl_heights(stl, xc, yc)
    z_an_c = surface.height(Xc, Yc)
    peak = float(np.nanmax(z_an))
    top = np.unravel_index(np.argmax(z_an), z_an.shape)  # where the definition peaks
    ok = away_from_walls(plate, X, Y)
    okc = away_from_walls(plate, Xc, Yc)

    def worst(a, b, mask) -> float:
        d = np.abs(a - b)[mask]
        return float(np.nanmax(d)) if np.isfinite(d).all() else float("inf")

    return ViewReport(
        name=plate.name or plate.hash,
        counts={
            "analytic": count_features(z_an, peak),
            "stl": count_features(z_stl, peak),
            "collider": count_features(z_col, peak),
        },
        peak_m={
            "analytic": peak,
            "stl": float(np.nanmax(z_stl)),
            "collider": probe.height(X[top], Y[top]),
        },
        max_diff_m={
            "stl_vs_analytic": worst(z_stl, z_an, ok),
            "collider_vs_analytic": worst(z_col, z_an_c, okc),
            "collider_vs_stl": worst(z_col, z_stl_c, okc),
        },
        checked_fraction=float(min(ok.mean(), okc.mean())),
    )


def _compare_roughness(plate: Plate, stl: bytes, probe: ColliderProbe) -> ViewReport:
    surface = surface_of(plate)
    half = plate.area_length_m / 2 - WALL_CLEARANCE_M
    xs = np.linspace(-half, half, 20001)
    ys = np.array([-5 * MM, 0.0, 7 * MM])
    z_an = surface.height(xs[None, :], ys[:, None])
    z_stl = stl_heights(stl, xs, ys)
    xc = np.linspace(-half, half, 1501)
    z_col = probe.heights(xc, 0.0)
    z_an_c = surface.height(xc, 0.0)
    return ViewReport(
        name=plate.name or plate.hash,
        counts={},
        peak_m={
            "analytic": float(z_an.max()),
            "stl": float(np.nanmax(z_stl)),
            "collider": float(np.nanmax(z_col)),
        },
        max_diff_m={
            "stl_vs_analytic": float(np.max(np.abs(z_stl - z_an))),
            "collider_vs_analytic": float(np.max(np.abs(z_col - z_an_c))),
        },
        checked_fraction=1.0,
        ra_m={
            "target": surface.ra_m,
            "analytic": max(_ra(r) for r in z_an),
            "analytic_min": min(_ra(r) for r in z_an),
            "stl": max(_ra(r) for r in z_stl),
            "stl_min": min(_ra(r) for r in z_stl),
            "collider": _ra(z_col),
        },
    )
