"""CadQuery solids of the plates and their STEP and STL exports.

CadQuery takes about 5 s to import, so this module imports it only inside functions and the
rest of the package never imports this module on a cache hit. The CAD model is built in
millimetres (the unit of STEP headers, slicers and CAD tools); the STL is written in mm too.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ...errors import GeometryError
from ..define.geometry import Feature
from ..define.spec import Plate
from ..define.surface import surface_of
from ..parts.cad_run import STL_ANGULAR_TOLERANCE_RAD, STL_TOLERANCE_MM

M_TO_MM = 1000.0


def _cq():
    import cadquery as cq  # noqa: PLC0415  (slow import, only when building)

    return cq


def _feature_solid(f: Feature):
    cq = _cq()
    s = M_TO_MM
    x, y, h = f.x * s, f.y * s, f.height_m * s
    if f.kind == "box":
        return (
            cq.Workplane("XY")
            .box(2 * f.hx * s, 2 * f.hy * s, h, centered=(True, True, False))
            .translate((x, y, 0))
            .val()
        )
    if f.kind == "prism":
        hx, tx, hy = f.hx * s, f.top_hx * s, f.hy * s
        pts = [(-hx, 0.0), (hx, 0.0), (tx, h), (-tx, h)]
        return (
            cq.Workplane("XZ")
            .polyline(pts)
            .close()
            .extrude(hy, both=True)
            .translate((x, y, 0))
            .val()
        )
    if f.kind == "cylinder":
        return cq.Workplane("XY").circle(f.hx * s).extrude(h).translate((x, y, 0)).val()
    if f.kind == "cap":
        r = f.sphere_radius_m * s
        sphere = cq.Workplane("XY").sphere(r).translate((x, y, f.sphere_z_m * s))
        above = (
            cq.Workplane("XY")
            .box(2 * r + 1, 2 * r + 1, h + 1, centered=(True, True, False))
            .translate((x, y, 0))
        )
        return sphere.intersect(above).val()
    raise ValueError(f.kind)  # pragma: no cover


def build_solid(plate: Plate):
    """The plate as one CadQuery solid, in mm."""
    cq = _cq()
    s = M_TO_MM
    L, W, T = plate.length_m * s, plate.width_m * s, plate.thickness_m * s
    base = cq.Workplane("XY").box(L, W, T, centered=(True, True, False)).translate((0, 0, -T))
    surface = surface_of(plate)
    if surface.profile is not None:
        return _roughness_solid(plate, surface.profile, base)
    feats = surface.features
    if not feats:
        return base.val()
    comp = cq.Compound.makeCompound([_feature_solid(f) for f in feats])
    return base.union(cq.Workplane("XY").add(comp)).val().clean()


def _profile_prism(px_mm, pz_mm, floor_mm: float, x_ends_mm: tuple[float, float], half_w_mm: float):
    """A prism along y whose cross-section (in xz) is the piecewise-linear profile over a
    flat floor. Built with OCP's polygon maker: CadQuery's polyline assembles the wire edge by
    edge and took 45 s for a 5700-point profile; this takes 0.3 s."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.gp import gp_Pnt, gp_Vec

    cq = _cq()
    x0, x1 = x_ends_mm
    pts = [(x0, floor_mm), (x1, floor_mm)]
    if x1 > px_mm[-1]:  # flat margin at z = 0, then a vertical step onto the profile
        pts += [(x1, 0.0), (float(px_mm[-1]), 0.0)]
    pts += list(zip(px_mm[::-1].tolist(), pz_mm[::-1].tolist(), strict=True))
    if x0 < px_mm[0]:
        pts += [(float(px_mm[0]), 0.0), (x0, 0.0)]
    poly = BRepBuilderAPI_MakePolygon()
    for x, z in pts:
        poly.Add(gp_Pnt(x, -half_w_mm, z))
    poly.Close()
    face = BRepBuilderAPI_MakeFace(poly.Wire()).Face()
    return cq.Shape.cast(BRepPrimAPI_MakePrism(face, gp_Vec(0, 2 * half_w_mm, 0)).Shape())


def _roughness_solid(plate: Plate, profile: tuple[np.ndarray, np.ndarray], base):
    """One prism when the textured area spans the plate's width (the presets); otherwise the
    base with a pocket under the textured area, filled by the profile prism ``(x, z)`` [m]."""
    cq = _cq()
    s = M_TO_MM
    px, pz = profile
    px_mm, pz_mm = px * s, pz * s
    L, T = plate.length_m * s / 2, plate.thickness_m * s
    if plate.area_width_m >= plate.width_m:
        return _profile_prism(px_mm, pz_mm, -T, (-L, L), plate.width_m * s / 2)
    ax, ay = plate.area_length_m * s / 2, plate.area_width_m * s / 2
    floor = float(pz_mm.min()) - 0.1  # pocket floor 0.1 mm below the deepest valley
    pocket = cq.Workplane("XY").box(2 * ax, 2 * ay, -floor + 1.0, centered=(True, True, False))
    prism = _profile_prism(px_mm, pz_mm, floor, (-ax, ax), ay)
    return base.cut(pocket.translate((0, 0, floor))).union(cq.Workplane("XY").add(prism)).val()


def step_bytes(shape) -> bytes:
    """STEP AP214 of a solid (mm). Differs between runs only in the header's timestamp."""
    cq = _cq()
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "plate.step"
        cq.exporters.export(shape, str(path), exportType="STEP")
        return path.read_bytes()


def stl_bytes(shape) -> bytes:
    """Binary STL (mm) of a solid: OCC's tessellation, vertices merged and degenerate
    triangles (OCC leaves one at a sphere's pole) dropped; raises GeometryError unless the
    mesh is watertight. Deterministic for the same solid."""
    import trimesh

    verts, tris = shape.tessellate(STL_TOLERANCE_MM, STL_ANGULAR_TOLERANCE_RAD)
    v = np.array([(p.x, p.y, p.z) for p in verts], dtype=np.float64)
    mesh = trimesh.Trimesh(v, np.asarray(tris, dtype=np.int64), process=True, validate=True)
    if not mesh.is_watertight:
        raise GeometryError(f"the STL tessellation is not watertight ({len(mesh.faces)} faces)")
    return trimesh.exchange.stl.export_stl(mesh)
