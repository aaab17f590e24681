"""Build a plate's artefacts through the content-addressed cache.

Artefact kinds: ``stl`` and ``step`` (the CAD solid, mm), ``mjcf`` (collision geometry, m),
``png`` (preview) and ``heightmap`` (the analytic height map as a .npy raster, m). A cache hit
never imports cadquery; a miss builds the CAD solid at most once for STL and STEP together.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...cache import ArtefactCache, atomic_write
from ...errors import ConfigError
from ...hashing import code_version
from ..define.spec import Plate
from ..define.surface import surface_of
from ..parts.cad_run import STL_ANGULAR_TOLERANCE_RAD, STL_TOLERANCE_MM
from ..read.presets import get_plate

#: The artefacts :func:`~sim_tactile.plates.build` makes by default: STL and STEP (mm), MJCF
#: and the preview PNG.
KINDS = ("stl", "step", "mjcf", "png")
ALL_KINDS = (*KINDS, "heightmap")
_EXT = {"stl": "stl", "step": "step", "mjcf": "xml", "png": "png", "heightmap": "npy"}
#: Raster step of the cached height map [m].
HEIGHTMAP_STEP_M = 5e-5


#: The module that makes each kind of artefact, and the libraries whose versions it depends
#: on: the artefact's code version is the source of everything that module imports.
_MAKERS = {
    "stl": ("make.cad", ("cadquery",)),
    "step": ("make.cad", ("cadquery",)),
    "map_stl": ("make.map_mesh", ("cadquery", "trimesh", "numpy")),
    "map_step": ("make.map_mesh", ("cadquery", "trimesh", "numpy")),
    "mjcf": ("make.mjcf", ("mujoco", "numpy", "scipy")),
    "png": ("make.render", ("matplotlib", "numpy")),
    "heightmap": ("define.surface", ("numpy",)),
}
#: the package the makers' names are relative to
_PLATES = __package__.rpartition(".")[0]


def _code_version(kind: str) -> str:
    module, libraries = _MAKERS[kind]
    return code_version(f"{_PLATES}.{module}", libraries=libraries)


_CAD_SETTINGS = {"units": "mm", "tol_mm": STL_TOLERANCE_MM, "ang_rad": STL_ANGULAR_TOLERANCE_RAD}
#: What else an artefact of each kind depends on (in its key): the tessellation, the raster.
_SETTINGS = {"stl": _CAD_SETTINGS, "step": _CAD_SETTINGS, "heightmap": {"step_m": HEIGHTMAP_STEP_M}}


def _settings(kind: str) -> dict:
    return _SETTINGS.get(kind, {})


def artefact_key(plate: Plate, kind: str) -> str:
    sampled = kind in ("stl", "step") and surface_of(plate).height_map is not None
    maker = f"map_{kind}" if sampled else kind
    return ArtefactCache.key(
        {
            "plate": plate.params(),
            "kind": kind,
            "settings": _settings(kind),
            "code": _code_version(maker),
        }
    )


def heightmap_grid(plate: Plate) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates (xs, ys) [m] of the cached height map: the whole plate."""
    nx = round(plate.length_m / HEIGHTMAP_STEP_M) + 1
    ny = round(plate.width_m / HEIGHTMAP_STEP_M) + 1
    return (
        np.linspace(-plate.length_m / 2, plate.length_m / 2, nx),
        np.linspace(-plate.width_m / 2, plate.width_m / 2, ny),
    )


def _heightmap_bytes(plate: Plate) -> bytes:
    import io

    xs, ys = heightmap_grid(plate)
    z = surface_of(plate).height(xs[None, :], ys[:, None])
    buf = io.BytesIO()
    np.save(buf, z.astype(np.float64), allow_pickle=False)
    return buf.getvalue()


@dataclass
class BuildResult:
    """What :func:`build` made: artefact paths by kind, MuJoCo geom counts, timings."""

    plate: Plate
    files: dict[str, Path]
    geoms: dict[str, int]
    cached: dict[str, bool]
    wall_s: float
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def notes(self) -> tuple[str, ...]:
        """What loading a user's part reported (e.g. a filled overhang)."""
        return getattr(self.plate.texture, "notes", ())

    def to_json(self) -> dict:
        return {
            "name": self.plate.name,
            "family": self.plate.family,
            "hash": self.plate.hash,
            "files": {k: str(v) for k, v in self.files.items()},
            "geoms": self.geoms,
            "cached": self.cached,
            "wall_s": round(self.wall_s, 4),
        }


def build(
    plate: Plate | str,
    out_dir: str | Path | None = None,
    *,
    kinds: tuple[str, ...] = KINDS,
    cache: ArtefactCache | None = None,
) -> BuildResult:
    """Build (or fetch from the cache) the artefacts of ``plate``.

    With ``out_dir``, copies them to ``out_dir/<slug>.<ext>`` (atomically); otherwise the
    returned paths point into the cache. Raises ConfigError for an unknown kind or name.
    """
    t0 = time.perf_counter()
    if isinstance(plate, str):
        plate = get_plate(plate)
    bad = [k for k in kinds if k not in ALL_KINDS]
    if bad:
        raise ConfigError(f"artefact kind {bad[0]!r} is not valid; valid: {', '.join(ALL_KINDS)}")
    cache = cache or ArtefactCache.default()
    keys = {k: artefact_key(plate, k) for k in kinds}
    paths: dict[str, Path] = {}
    cached: dict[str, bool] = {}
    timings: dict[str, float] = {}
    missing = []
    for k in kinds:
        hit = cache.get(keys[k], _EXT[k])
        cached[k] = hit is not None
        if hit is not None:
            paths[k] = hit
        else:
            missing.append(k)
    solid = None
    for k in missing:
        t = time.perf_counter()
        if k in ("stl", "step") and surface_of(plate).height_map is not None:
            from . import map_mesh

            data = map_mesh.stl_bytes(plate) if k == "stl" else map_mesh.step_bytes(plate)
        elif k in ("stl", "step"):
            from . import cad

            if solid is None:
                solid = cad.build_solid(plate)
                timings["cad"] = time.perf_counter() - t
                t = time.perf_counter()
            data = cad.stl_bytes(solid) if k == "stl" else cad.step_bytes(solid)
        elif k == "mjcf":
            from .mjcf import mjcf_xml

            data = mjcf_xml(plate).encode()
        elif k == "png":
            from .render import preview_png

            data = preview_png(plate)
        else:
            data = _heightmap_bytes(plate)
        paths[k] = cache.put(keys[k], _EXT[k], data)
        timings[k] = time.perf_counter() - t
    geoms = _geom_counts(paths["mjcf"]) if "mjcf" in paths else {}
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        for k, p in list(paths.items()):
            dest = out / f"{plate.slug}.{_EXT[k]}"
            atomic_write(dest, p.read_bytes())
            paths[k] = dest
    return BuildResult(plate, paths, geoms, cached, time.perf_counter() - t0, timings)


def _geom_counts(mjcf_path: Path) -> dict[str, int]:
    import mujoco

    from .mjcf import geom_counts

    return geom_counts(mujoco.MjModel.from_xml_path(str(mjcf_path)))


def load_heightmap(plate: Plate | str, *, cache: ArtefactCache | None = None):
    """(xs, ys, z) of the plate's cached height map [m]; z has shape (ny, nx)."""
    res = build(plate, kinds=("heightmap",), cache=cache)
    plate = res.plate
    xs, ys = heightmap_grid(plate)
    return xs, ys, np.load(res.files["heightmap"], allow_pickle=False)


__all__ = ["KINDS", "BuildResult", "build", "artefact_key", "load_heightmap"]
