"""MuJoCo collision geometry of a plate, built with ``mujoco.MjSpec``.

docs/physics.md: a mesh collides as its convex hull, so a whole textured plate as one mesh is a
box to the solver. Here every feature is its own geom: a primitive where one is exact (box
ridges and bumps, cylinders, spherical caps as spheres half buried in the base) and a convex
mesh otherwise (drafted ridges: a trapezoidal prism, checked convex). A random roughness is
not a set of convex features and becomes an ``hfield`` over the textured area; its lay along
y makes the field two rows deep, so there is no row-order ambiguity.

Everything lives in a body named ``plate`` whose frame is the plate frame (top surface at
z = 0). Geoms belong to the default class ``plate``.
"""

from __future__ import annotations

import mujoco
import numpy as np

from ...errors import GeometryError
from ..define.geometry import Feature
from ..define.spec import HeightMap, Plate
from ..define.surface import Surface, surface_of

#: Largest height error allowed when the height field is made coarser than the profile: a
#: fifth of the 0.01 mm agreement demanded between collider and CAD [m], and at most a tenth
#: of the plate's Ra (so the collider's Ra stays within a few percent of the target).
HFIELD_MAX_ERROR_M = 2e-6
HFIELD_MAX_ERROR_RA = 0.1
#: Depth of the height field's own base below its lowest sample [m].
HFIELD_BASE_M = 1e-3
#: Gap between the base box under a height field and the field's lowest sample [m].
HFIELD_FLOOR_GAP_M = 1e-4
_RGBA = (0.62, 0.64, 0.70, 1.0)

_T = mujoco.mjtGeom


def _prism_vertices(f: Feature) -> np.ndarray:
    """The 8 vertices of a drafted ridge, relative to its bottom centre, shape (8, 3) [m]."""
    hx, tx, hy, h = f.hx, f.top_hx, f.hy, f.height_m
    xz = [(-hx, 0.0), (hx, 0.0), (tx, h), (-tx, h)]
    return np.array([(x, y, z) for y in (-hy, hy) for x, z in xz], dtype=float)


def check_convex(vertices: np.ndarray, *, rtol: float = 1e-9) -> None:
    """Raise GeometryError unless every vertex is a vertex of the convex hull (so MuJoCo's
    collider, which uses the hull, sees exactly this shape)."""
    from scipy.spatial import ConvexHull, QhullError  # only a drafted ridge's check needs it

    try:
        hull = ConvexHull(vertices)
    except QhullError as exc:
        raise GeometryError(
            f"mesh is degenerate (flat or too few vertices): {str(exc).splitlines()[0]}"
        ) from None
    on_hull = set(hull.vertices.tolist())
    if len(on_hull) != len(vertices):
        missing = sorted(set(range(len(vertices))) - on_hull)
        raise GeometryError(f"mesh is not convex: vertices {missing} lie inside its hull")
    if hull.volume <= rtol * np.ptp(vertices, axis=0).prod():
        raise GeometryError("mesh is degenerate (zero volume)")


def _add_box(body, cls, name: str, lo: tuple, hi: tuple) -> None:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    body.add_geom(cls, name=name, type=_T.mjGEOM_BOX, size=(hi - lo) / 2, pos=(hi + lo) / 2)


def plate_spec(plate: Plate) -> mujoco.MjSpec:
    """A standalone MjSpec holding the plate's collision geometry in body ``plate``."""
    spec = mujoco.MjSpec()
    spec.modelname = f"plate {plate.name or plate.hash}"
    cls = spec.add_default("plate", spec.default)
    cls.geom.rgba = _RGBA
    body = spec.worldbody.add_body(name="plate")
    L, W, T = plate.length_m / 2, plate.width_m / 2, plate.thickness_m
    surface = surface_of(plate)
    if surface.profile is not None:
        _add_roughness(spec, body, cls, plate, surface)
    elif surface.height_map is not None:
        _add_heightmap(spec, body, cls, plate, surface.height_map)
    else:
        _add_box(body, cls, "base", (-L, -W, -T), (L, W, 0.0))
    for i, f in enumerate(surface.features):
        name = f"f{i:04d}"
        if f.kind == "box":
            body.add_geom(
                cls,
                name=name,
                type=_T.mjGEOM_BOX,
                size=(f.hx, f.hy, f.height_m / 2),
                pos=(f.x, f.y, f.height_m / 2),
            )
        elif f.kind == "cylinder":
            body.add_geom(
                cls,
                name=name,
                type=_T.mjGEOM_CYLINDER,
                size=(f.hx, f.height_m / 2, 0),
                pos=(f.x, f.y, f.height_m / 2),
            )
        elif f.kind == "cap":
            body.add_geom(
                cls,
                name=name,
                type=_T.mjGEOM_SPHERE,
                size=(f.sphere_radius_m, 0, 0),
                pos=(f.x, f.y, f.sphere_z_m),
            )
        elif f.kind == "prism":
            verts = _prism_vertices(f)
            check_convex(verts)
            spec.add_mesh(name=f"mesh_{name}", uservert=verts.ravel().tolist())
            body.add_geom(
                cls, name=name, type=_T.mjGEOM_MESH, meshname=f"mesh_{name}", pos=(f.x, f.y, 0.0)
            )
        else:  # pragma: no cover
            raise GeometryError(f"unknown feature kind {f.kind!r}")
    return spec


def hfield_profile(px: np.ndarray, pz: np.ndarray, max_error_m: float = HFIELD_MAX_ERROR_M):
    """The coarsest uniform resampling of a profile whose linear interpolation stays within
    ``max_error_m`` of it, as ``(x, z)``.

    Models only what the scene needs: a fine roughness (Ra 0.4 um has peaks of 2 um) is
    nearly flat to the collider, and every extra cell costs contacts; MuJoCo keeps at most 50
    per height-field pair, filled in row order (docs/physics.md), so a contact patch spanning
    hundreds of 6 um cells would be truncated to one side of it.
    """
    n = len(px)
    for m in np.unique(np.geomspace(8, n - 1, 60).astype(int)):
        xc = np.linspace(px[0], px[-1], m + 1)
        zc = np.interp(xc, px, pz)
        if np.max(np.abs(np.interp(px, xc, zc) - pz)) <= max_error_m:
            return xc, zc
    return px, pz


def _add_roughness(spec, body, cls, plate: Plate, surface: Surface) -> None:
    """The surface's roughness profile as a two-row height field (:func:`_add_field`)."""
    tol = min(HFIELD_MAX_ERROR_M, HFIELD_MAX_ERROR_RA * surface.ra_m)
    px, pz = hfield_profile(*surface.profile, max_error_m=tol)
    area = (plate.area_length_m / 2, plate.area_width_m / 2)
    _add_field(spec, body, cls, plate, np.stack([pz, pz]), "roughness", area)


def _add_heightmap(spec, body, cls, plate: Plate, height_map: HeightMap) -> None:
    """A height map's samples as the field, one elevation each (MuJoCo's rows run along +y,
    as the map's do); samples without material lie on the field's floor."""
    z = np.asarray(height_map.z)
    floor = float(np.nanmin(z))
    half = (height_map.extent_m[0] / 2, height_map.extent_m[1] / 2)
    _add_field(spec, body, cls, plate, np.where(np.isnan(z), floor, z), "heightmap", half)


def _add_field(spec, body, cls, plate: Plate, pz: np.ndarray, name: str, half) -> None:
    """Base box below the field, flat margin boxes at z = 0 around it, and the field of
    heights ``pz`` (rows along y) over ``|x| <= half[0], |y| <= half[1]``."""
    zmin, zmax = float(pz.min()), float(pz.max())
    L, W, T = plate.length_m / 2, plate.width_m / 2, plate.thickness_m
    ax, ay = half
    floor = zmin - HFIELD_FLOOR_GAP_M
    _add_box(body, cls, "base", (-L, -W, -T), (L, W, floor))
    margins = [
        ((-L, -W), (-ax, W)),
        ((ax, -W), (L, W)),
        ((-ax, -W), (ax, -ay)),
        ((-ax, ay), (ax, W)),
    ]
    for k, ((x0, y0), (x1, y1)) in enumerate(margins):
        if x1 - x0 > 1e-12 and y1 - y0 > 1e-12:
            _add_box(body, cls, f"margin{k}", (x0, y0, floor), (x1, y1, 0.0))
    span = max(zmax - zmin, 1e-12)
    elev = (pz - zmin) / span
    spec.add_hfield(
        name=name,
        size=[ax, ay, span, HFIELD_BASE_M],
        nrow=pz.shape[0],
        ncol=pz.shape[1],
        userdata=elev.ravel().tolist(),
    )
    body.add_geom(cls, name=name, type=_T.mjGEOM_HFIELD, hfieldname=name, pos=(0.0, 0.0, zmin))


def mjcf_xml(plate: Plate) -> str:
    """The standalone MJCF text of :func:`plate_spec` (compiles on its own)."""
    spec = plate_spec(plate)
    spec.compile()  # validates; raises mujoco's error on bad geometry
    return spec.to_xml()


def geom_counts(spec_or_model) -> dict[str, int]:
    """Number of geoms per type in body ``plate``, e.g. ``{"box": 5}``."""
    m = spec_or_model.compile() if isinstance(spec_or_model, mujoco.MjSpec) else spec_or_model
    bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "plate")
    out: dict[str, int] = {}
    for g in range(m.ngeom):
        if m.geom_bodyid[g] == bid:
            name = _T(m.geom_type[g]).name.removeprefix("mjGEOM_").lower()
            out[name] = out.get(name, 0) + 1
    return out
