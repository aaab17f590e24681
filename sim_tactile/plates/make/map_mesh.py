"""The solid of a height-map plate (:class:`~.spec.HeightMap`), for its STL and STEP.

The solid is the map's top surface (two triangles a cell) with the plate's base around it
(at z = 0, on the map's grid, so its edge lies within half a sample of the plate's), vertical
walls down its border and a flat bottom ``thickness_m`` under the base, in mm as the other
plates' CAD is. Samples
without material (NaN) lie on the bottom: the part's outline is kept, the solid stays
closed. The STL takes every ``k``-th sample, ``k`` the smallest that keeps it within
:data:`MAX_STL_CELLS` cells (the rows and columns of the border always), so its height error
is at most the map's change over ``k`` samples; the STEP, a faceted B-rep sewn by OpenCASCADE,
within :data:`MAX_STEP_CELLS`. The collider reads the samples themselves, never these files.
"""

from __future__ import annotations

import math

import numpy as np

from ..define.spec import Plate

M_TO_MM = 1000.0
MAX_STL_CELLS = 250_000
MAX_STEP_CELLS = 2_500


def stride(shape: tuple[int, int], max_cells: int) -> int:
    """The smallest sample stride that keeps the map within ``max_cells`` cells."""
    ny, nx = shape
    return max(1, math.ceil(math.sqrt((ny - 1) * (nx - 1) / max_cells)))


def _take(n: int, k: int) -> np.ndarray:
    return np.unique(np.append(np.arange(0, n, k), n - 1))


def map_solid(plate: Plate, max_cells: int = MAX_STL_CELLS) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices, faces)`` of the plate's closed solid [mm], outward-wound."""
    t = plate.texture
    p = t.pixel_m
    # the base around the map, at z = 0, on the map's grid (its edge within half a sample)
    px = round((plate.length_m - t.extent_m[0]) / 2 / p)
    py = round((plate.width_m - t.extent_m[1]) / 2 / p)
    full = np.pad(t.z, ((py, py), (px, px)), constant_values=0.0)
    k = stride(full.shape, max_cells)
    rows, cols = _take(full.shape[0], k), _take(full.shape[1], k)
    xs = (np.arange(full.shape[1]) - (full.shape[1] - 1) / 2) * p
    ys = (np.arange(full.shape[0]) - (full.shape[0] - 1) / 2) * p
    bottom = -plate.thickness_m
    z = np.nan_to_num(full[np.ix_(rows, cols)], nan=bottom)
    X, Y = np.meshgrid(xs[cols], ys[rows])
    ny, nx = z.shape
    top = np.column_stack([X.ravel(), Y.ravel(), z.ravel()])
    idx = np.arange(ny * nx).reshape(ny, nx)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    faces = [np.column_stack([a, b, c]), np.column_stack([a, c, d])]  # up, seen from above
    # the border, counter-clockwise seen from above, and the bottom under it
    ring = np.concatenate([idx[0, :-1], idx[:-1, -1], idx[-1, :0:-1], idx[:0:-1, 0]])
    n_top = len(top)
    under = top[ring] * [1, 1, 0] + [0, 0, bottom]
    centre = np.array([[0.0, 0.0, bottom]])
    verts = np.vstack([top, under, centre])
    m = len(ring)
    t0, t1 = ring, np.roll(ring, -1)
    b0 = n_top + np.arange(m)
    b1 = np.roll(b0, -1)
    faces += [np.column_stack([t0, b0, b1]), np.column_stack([t0, b1, t1])]
    faces.append(np.column_stack([b1, b0, np.full(m, len(verts) - 1)]))
    return verts * M_TO_MM, np.vstack(faces).astype(np.int64)


def stl_bytes(plate: Plate) -> bytes:
    """Binary STL of :func:`map_solid` [mm]; checked closed."""
    import trimesh

    from ...errors import GeometryError

    v, f = map_solid(plate)
    mesh = trimesh.Trimesh(v, f, process=True, validate=True)
    if not mesh.is_watertight:
        raise GeometryError(f"the height map's solid is not watertight ({len(f)} faces)")
    if mesh.volume < 0:
        mesh.invert()
    return trimesh.exchange.stl.export_stl(mesh)


def step_bytes(plate: Plate) -> bytes:
    """STEP AP214 of a faceted solid of the map within :data:`MAX_STEP_CELLS` cells [mm]."""
    import cadquery as cq  # noqa: I001  (slow import, only when building)
    from OCP.BRepBuilderAPI import (
        BRepBuilderAPI_MakeFace,
        BRepBuilderAPI_MakePolygon,
        BRepBuilderAPI_MakeSolid,
        BRepBuilderAPI_Sewing,
    )
    from OCP.gp import gp_Pnt
    from OCP.TopoDS import TopoDS

    from .cad import step_bytes as _step

    v, f = map_solid(plate, MAX_STEP_CELLS)
    sewing = BRepBuilderAPI_Sewing(1e-6)
    pts = [gp_Pnt(*map(float, p)) for p in v]
    for tri in f:
        if len({tuple(v[i]) for i in tri}) < 3:
            continue
        poly = BRepBuilderAPI_MakePolygon(pts[tri[0]], pts[tri[1]], pts[tri[2]], True)
        face = BRepBuilderAPI_MakeFace(poly.Wire(), True)
        if face.IsDone():
            sewing.Add(face.Face())
    sewing.Perform()
    shell = TopoDS.Shell_s(sewing.SewedShape())
    solid = cq.Shape.cast(BRepBuilderAPI_MakeSolid(shell).Solid())
    return _step(solid)
