"""A user's part, a closed triangle mesh, as a plate's height map: checked, placed, sampled.

The steps, each of which refuses bad input with an error that names the file:

1. **Closed**: the mesh must bound a solid (every edge shared by exactly two triangles, the
   winding consistent); an open mesh (a surface, a scan with holes) is refused.
2. **Placed**: the part is brought into the plate frame (:class:`Placement`: its units, which
   of its axes points up, a turn about z, a scale).
3. **Size**: its footprint must lie within the plate range (1 mm to 0.5 m a side) and its
   relief within the features' (10 mm), before anything is sampled.
4. **A height map**: a vertical line through the part must meet it in one interval, so that
   its top surface is a height map. Where a second upward-facing surface lies under the top
   (an overhang, a mushroom, a cavity), the part is refused, or with ``fill_overhangs`` the
   space under the top surface is filled and the filling reported.
5. **Sampled**: the top surface is z-buffered every ``pixel_m`` on a grid centred on the
   textured area (the samples more than 1 um above the lowest point of the top surface; the
   whole part if none is); that lowest point becomes z = 0.
6. **Outlined**: the part has material wherever its footprint does. A sample on the part's
   outline that round-off puts outside it takes the height of the nearest triangle's plane
   (:data:`OUTLINE_EPS`). Samples that no triangle covers and that reach the grid's border (beyond the part's outline: the grid, centred on
   the texture, extends past an off-centre part on one side, and a sample on the part's edge
   may fall just outside it) are the plate's flat base, z = 0, as the plate's base around
   the map is; the plate's notes say so where the grid reaches more than a sample beyond the
   part. Samples without material enclosed by the part (a through-hole) are refused, or with
   ``holes`` kept as holes (NaN: no material) and reported.
7. **Resolved**: every raised feature (above half the relief) must be at least three samples
   across, so that the collider, which interpolates the samples bilinearly, holds it (the
   slivers the part's outline cuts from features are not held to it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ...errors import ConfigError
from ..define.spec import MAX_FEATURE_HEIGHT_M, MAX_HEIGHTMAP_SAMPLES
from .zbuffer import zbuffer

#: A user plate's footprint, each side [m].
PLATE_SIDE_RANGE_M = (1e-3, 0.5)
#: Default sample spacing of a CAD part's height map [m].
DEFAULT_PIXEL_M = 5e-5
#: Heights within this of the top surface's lowest point are the base [m].
TEXTURE_TOL_M = 1e-6
#: Two upward-facing surfaces farther apart than this along a vertical line overhang [m].
OVERHANG_TOL_M = 1e-6
#: Samples a raised feature must span to be resolved.
RESOLVE_SAMPLES = 3
#: Barycentric slack within which a sample that no triangle covers takes the plane of the
#: nearest, and how far beyond a triangle's bounding box it is looked for [samples]: a
#: sample on the part's outline may fall outside it by the STL's float32 round-off (6e-8 of
#: a coordinate: 3 nm at 50 mm), 3e-5 of a 0.1 mm triangle and 6e-5 of a 50 um sample.
OUTLINE_EPS = 1e-3
UNITS_M = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "in": 0.0254}
UPS = ("+z", "-z", "+x", "-x", "+y", "-y")


@dataclass(frozen=True)
class Placement:
    """How a part drawn in another frame comes into the plate frame: its coordinates are in
    ``units``; its axis ``up`` becomes +z; it turns by ``rotate_deg`` about z (counter-
    clockwise seen from above, after ``up``); it is scaled by ``scale`` about its centre."""

    units: str = "mm"
    up: str = "+z"
    rotate_deg: float = 0.0
    scale: float = 1.0

    def __post_init__(self) -> None:
        if self.units not in UNITS_M:
            raise ConfigError(f"units = {self.units!r} is not valid; valid: {', '.join(UNITS_M)}")
        if self.up not in UPS:
            raise ConfigError(f"up = {self.up!r} is not valid; valid: {', '.join(UPS)}")
        if not math.isfinite(self.rotate_deg) or abs(self.rotate_deg) > 360:
            raise ConfigError(f"rotate_deg = {self.rotate_deg!r} is not valid; valid: [-360, 360]")
        if not (math.isfinite(self.scale) and 1e-3 <= self.scale <= 1e3):
            raise ConfigError(f"scale = {self.scale!r} is not valid; valid: [0.001, 1000]")

    def matrix(self) -> np.ndarray:
        """The 3 x 3 map from the part's coordinates to the plate frame's [m]."""
        axis = "xyz".index(self.up[1])
        sign = 1.0 if self.up[0] == "+" else -1.0
        # a proper rotation taking the part's `up` axis to +z: its rows are the new axes
        r = np.zeros((3, 3))
        r[2, axis] = sign
        r[0, 1 if axis == 0 else 0] = 1.0
        r[1] = np.cross(r[2], r[0])
        a = math.radians(self.rotate_deg)
        turn = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
        return UNITS_M[self.units] * self.scale * (turn @ r)


@dataclass
class SampledPart:
    """A part's top surface as samples (:func:`sample_part`)."""

    z: np.ndarray
    pixel_m: float
    thickness_m: float
    #: the textured area's size (x, y) [m], centred on the map (the whole part if flat)
    area_m: tuple[float, float]
    notes: list[str] = field(default_factory=list)


def closed_mesh(vertices: np.ndarray, faces: np.ndarray, where: str):
    """The mesh with its duplicate vertices merged and its normals outward; raises
    ConfigError unless it bounds a solid."""
    import trimesh

    if len(faces) < 4:
        raise ConfigError(f"{where}: {len(faces)} triangles bound no solid; valid: a closed solid")
    mesh = trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces), process=True)
    if not mesh.is_watertight:
        open_edges = len(trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1))
        raise ConfigError(
            f"{where}: the mesh is not a closed solid: {open_edges} edges belong to one triangle "
            "only (a hole, or a surface without thickness); valid: a closed (watertight) solid"
        )
    if not mesh.is_winding_consistent:
        raise ConfigError(
            f"{where}: the mesh's triangles are not consistently wound (inside and outside "
            "cannot be told apart); valid: a closed solid with consistent winding"
        )
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _check_size(lo: np.ndarray, hi: np.ndarray, where: str, units: str) -> None:
    lo_m, hi_m = PLATE_SIDE_RANGE_M
    for axis, side in zip("xy", hi[:2] - lo[:2], strict=True):
        if not lo_m <= side <= hi_m:
            hint = " (is the file in other units? pass units=...)" if side > hi_m else ""
            raise ConfigError(
                f"{where}: the part is {side:.4g} m along {axis} in the plate frame (read in "
                f"{units}){hint}; valid: [{lo_m:g}, {hi_m:g}] m"
            )


def _grid(centre: float, lo: float, hi: float, pixel: float) -> np.ndarray:
    half = max(centre - lo, hi - centre)
    n = 2 * math.ceil(half / pixel - 1e-9) + 1
    return centre + (np.arange(n) - (n - 1) / 2) * pixel


def sample_part(
    mesh,
    placement: Placement,
    pixel_m: float,
    where: str,
    *,
    fill_overhangs: bool = False,
    holes: bool = False,
) -> SampledPart:
    """The top surface of a closed mesh (:func:`closed_mesh`) as a centred height map; see
    the module for the checks."""
    v = mesh.vertices @ placement.matrix().T
    lo, hi = v.min(axis=0), v.max(axis=0)
    _check_size(lo, hi, where, placement.units)
    n_est = (math.ceil((hi[0] - lo[0]) / pixel_m) + 3) * (math.ceil((hi[1] - lo[1]) / pixel_m) + 3)
    if n_est > MAX_HEIGHTMAP_SAMPLES:
        raise ConfigError(
            f"{where}: pixel_m = {pixel_m:g} m gives about {n_est} samples over the part's "
            f"{hi[0] - lo[0]:.4g} x {hi[1] - lo[1]:.4g} m; valid: at most {MAX_HEIGHTMAP_SAMPLES} "
            "(a coarser pixel_m)"
        )
    a, b, c = (v[mesh.faces[:, k]] for k in range(3))
    normal_z = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    is_up = normal_z > 0
    up = mesh.faces[is_up]
    # the top's rim: upward faces beside others (walls), the only ones a sample on the
    # outline can be near
    pairs = mesh.face_adjacency
    beside = pairs[is_up[pairs[:, 0]] != is_up[pairs[:, 1]]].ravel()
    rim = mesh.faces[beside[is_up[beside]]]
    # first pass: where the texture lies
    xs = lo[0] + np.arange(math.ceil((hi[0] - lo[0]) / pixel_m) + 1) * pixel_m
    ys = lo[1] + np.arange(math.ceil((hi[1] - lo[1]) / pixel_m) + 1) * pixel_m
    top = _top(v, up, rim, xs, ys)
    base = float(np.nanmin(top))
    relief = float(np.nanmax(top)) - base
    if relief > MAX_FEATURE_HEIGHT_M:
        raise ConfigError(
            f"{where}: the top surface spans {relief:.4g} m in height; valid: at most "
            f"{MAX_FEATURE_HEIGHT_M:g} m of relief (is the part upright? pass up=...)"
        )
    raised = top > base + TEXTURE_TOL_M
    notes = []
    if raised.any():
        iy, ix = np.nonzero(raised)
        x0, x1, y0, y1 = xs[ix.min()], xs[ix.max()], ys[iy.min()], ys[iy.max()]
        # the texture's edges lie within a sample outside its outermost raised samples
        area = (
            min(x1 - x0 + 2 * pixel_m, hi[0] - lo[0]),
            min(y1 - y0 + 2 * pixel_m, hi[1] - lo[1]),
        )
    else:
        x0, x1, y0, y1 = lo[0], hi[0], lo[1], hi[1]
        area = (hi[0] - lo[0], hi[1] - lo[1])
        notes.append("the part's top is flat: the plate has no texture")
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    # second pass: a grid centred on the texture
    xs, ys = _grid(cx, lo[0], hi[0], pixel_m), _grid(cy, lo[1], hi[1], pixel_m)
    top = _top(v, up, rim, xs, ys)
    _check_overhangs(v, up, xs, ys, pixel_m, where, fill_overhangs, notes)
    z = top - float(np.nanmin(top))  # this grid's lowest point (the first's, to round-off)
    _check_resolved(z, pixel_m, where)
    z = _outline(z, pixel_m, where, holes, notes)
    beyond = {
        "-x": lo[0] - xs[0],
        "+x": xs[-1] - hi[0],
        "-y": lo[1] - ys[0],
        "+y": ys[-1] - hi[1],
    }
    side = max(beyond, key=beyond.get)
    if beyond[side] > pixel_m:
        notes.append(
            f"the map, centred on the texture, reaches {beyond[side] * 1e3:.4g} mm beyond the "
            f"part on its {side} side: the plate's flat base (z = 0) is the surface there"
        )
    span = ((z.shape[1] - 1) * pixel_m, (z.shape[0] - 1) * pixel_m)
    area = (min(area[0], span[0]), min(area[1], span[1]))
    return SampledPart(z, pixel_m, base - float(lo[2]), area, notes)


def _top(v, up, rim, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """The top surface's heights on the grid (:func:`.zbuffer.zbuffer` of the upward faces
    ``up``); a sample on the part's outline that round-off puts outside it takes the plane of
    the nearest face of the top's ``rim``."""
    top = zbuffer(v, up, xs, ys)
    if np.isnan(top).any() and len(rim):
        near = zbuffer(v, rim, xs, ys, edge_eps=OUTLINE_EPS, reach=OUTLINE_EPS)
        top = np.where(np.isnan(top), near, top)
    return top


def nan_regions(z: np.ndarray, pixel: float) -> tuple[int, int, float, float]:
    """Where a map ``z`` (ny, nx) sampled every ``pixel`` [m] has no material (NaN): the
    number of such samples, the largest 4-connected region's, and its centre (x, y) [m] in the
    plate frame (the map centred on the origin)."""
    from scipy import ndimage

    nan = np.isnan(z)
    labels, n = ndimage.label(nan)
    if n == 0:
        return 0, 0, 0.0, 0.0
    sizes = np.bincount(labels.ravel())[1:]
    k = int(np.argmax(sizes)) + 1
    iy, ix = ndimage.center_of_mass(nan, labels, k)
    ny, nx = z.shape
    return (
        int(nan.sum()),
        int(sizes[k - 1]),
        (ix - (nx - 1) / 2) * pixel,
        (iy - (ny - 1) / 2) * pixel,
    )


def describe_nan(z: np.ndarray, pixel: float) -> str:
    """What :func:`nan_regions` finds, in words (mm)."""
    n, big, x, y = nan_regions(z, pixel)
    return (
        f"{n} samples without material (NaN); the largest region, {big} samples, around "
        f"x = {round(x * 1e3, 3) + 0.0:.3f} mm, y = {round(y * 1e3, 3) + 0.0:.3f} mm"
    )


def _outline(z: np.ndarray, pixel: float, where: str, holes: bool, notes: list) -> np.ndarray:
    """``z`` with its samples beyond the part's outline (those without material that reach
    the grid's border) on the base, z = 0; samples without material inside the outline (a
    through-hole) refused, or with ``holes`` kept (NaN) and reported."""
    from scipy import ndimage

    nan = np.isnan(z)
    if not nan.any():
        return z
    labels, _ = ndimage.label(nan)
    border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    z = np.where(np.isin(labels, border[border > 0]), 0.0, z)
    if not np.isnan(z).any():
        return z
    what = f"the part has holes through it: {describe_nan(z, pixel)}"
    if not holes:
        raise ConfigError(
            f"{where}: {what}; valid: material at every sample inside the part's outline, or "
            "pass holes=true if the holes are intended (no material: the pad meets nothing there)"
        )
    notes.append(f"{what}; kept as holes (holes=true)")
    return z


def _check_overhangs(v, up, xs, ys, pixel, where, fill, notes) -> None:
    """Refuse (or report, with ``fill``) a second upward-facing surface under the top one.
    Sampled a fraction of a pixel off the grid and strictly inside triangles, so that the
    edges of adjacent faces (and the rims of vertical walls) are not counted twice."""
    dx, dy = 0.3719 * pixel, 0.2843 * pixel
    high = zbuffer(v, up, xs + dx, ys + dy, edge_eps=-1e-9)
    low = zbuffer(v, up, xs + dx, ys + dy, lowest=True, edge_eps=-1e-9)
    gap = high - low
    bad = np.nan_to_num(gap) > OVERHANG_TOL_M
    if not bad.any():
        return
    iy, ix = np.unravel_index(np.argmax(np.nan_to_num(gap)), gap.shape)
    what = (
        f"the part overhangs along z at {int(bad.sum())} of {int(np.isfinite(gap).sum())} "
        f"samples: a second upward-facing surface lies up to {float(np.nanmax(gap)) * 1e3:.4g} mm "
        f"under the top (deepest at x = {xs[ix] * 1e3:.4g} mm, y = {ys[iy] * 1e3:.4g} mm)"
    )
    if not fill:
        raise ConfigError(
            f"{where}: {what}; valid: a top surface that is a height map, or pass "
            "fill_overhangs=true to fill the space under the top surface"
        )
    notes.append(f"{what}; filled under the top surface")


def _check_resolved(z: np.ndarray, pixel: float, where: str) -> None:
    from scipy import ndimage  # 0.13 s to import: only when a part is sampled

    relief = float(np.nanmax(z))
    if relief <= TEXTURE_TOL_M:
        return
    raised = np.nan_to_num(z, nan=-1.0) > relief / 2
    labels, n = ndimage.label(raised)
    if n == 0:
        return
    depth = ndimage.distance_transform_edt(raised)
    widest = ndimage.maximum(depth, labels, index=np.arange(1, n + 1))
    # features the part's outline cuts (touching its edge or a place without material) are
    # slivers of features, not features: they are not held to the rule
    edge = np.zeros(z.shape, bool)
    edge[[0, -1], :] = edge[:, [0, -1]] = True
    edge |= ndimage.binary_dilation(np.isnan(z))
    cut = np.unique(labels[edge & raised])
    widest[cut[cut > 0] - 1] = np.inf
    k = int(np.argmin(widest))
    across = 2 * float(widest[k])
    if across < RESOLVE_SAMPLES:
        iy, ix = np.argwhere(labels == k + 1)[0]
        ny, nx = z.shape
        raise ConfigError(
            f"{where}: a feature (near x = {(ix - (nx - 1) / 2) * pixel * 1e3:.4g} mm, y = "
            f"{(iy - (ny - 1) / 2) * pixel * 1e3:.4g} mm) is about {across * pixel * 1e3:.3g} mm "
            f"across, {across:.3g} samples of pixel_m = {pixel:g} m; valid: at least "
            f"{RESOLVE_SAMPLES} samples (pass pixel_m <= {across * pixel / RESOLVE_SAMPLES:.3g})"
        )
