"""Plates from a user's files: STEP, STL, a CadQuery script, or a height map.

A plate reference is a path, optionally a script's function after a colon and options after
a question mark::

    knurl.py:make?pixel_m=2.5e-05     a CadQuery script; its function make() (default plate())
    part.step?up=+y&rotate_deg=90     a STEP file drawn y-up, turned a quarter about z
    part.stl?units=m                  an STL written in metres (CAD files are in mm by default)
    scan.npy?pixel_m=1e-05            a height map in metres, rows along +y, a sample every 10 um
    scan.png?pixel_m=1e-05&z_scale_m=1e-08   a 16-bit PNG: height = count x z_scale_m

Each becomes a :class:`~.spec.Plate` with a :class:`~.spec.HeightMap` texture in the plate
frame: top surface at z = 0 (the lowest point of the part's top surface), features rising,
the textured area centred, sliding along +x. The options (``Source``): ``units``, ``up``,
``rotate_deg``, ``scale`` (the placement, :class:`~.mesh_map.Placement`), ``pixel_m``,
``z_scale_m``, ``thickness_m`` (a height map's base), ``fill_overhangs``, ``holes``,
``timeout_s`` (a script's or STEP reader's time limit) and ``name``.

A plate has material wherever its part or map has: a map's samples must all be numbers, and
a part's top surface must cover its outline (beyond it, where the grid centred on the
texture reaches past an off-centre part, the plate's flat base is the surface). Holes (NaN
in a map, a hole through a part) are refused, saying where, unless ``holes=true`` says they
are intended; the plate's notes then report them. The samples, NaN included, are the
plate's identity, so a plate with holes is another plate than one without.

Files are read within bounds (:mod:`.map_files`): their size, a ``.npy``'s header and a
PNG's dimensions are checked before their contents are read.

A STEP file is read and a script is run in a separate process (:mod:`.cad_worker`) under a
time limit, in its own session, killed whole at the limit or when it ends (:mod:`.cad_run`):
**a script is code** and runs only because its path was given. STL, NPY and
PNG files are read as data (numpy's reader without pickles, Pillow, trimesh). The checks
(closed solid, size, overhangs, resolution) are :mod:`.mesh_map`'s; every refusal names the
file, the value and the valid range, and nothing is written.

The plate is its samples: its hash (and so every cache key of its slides) is their SHA-256,
never the file's path, so an edited file is another plate. Loaded plates are kept in this
process by the file's content and the options.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
from dataclasses import dataclass, fields, replace
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from ...cache import register_memo
from ...errors import ConfigError
from ..define.spec import HeightMap, Plate
from . import map_files
from .mesh_map import (
    DEFAULT_PIXEL_M,
    PLATE_SIDE_RANGE_M,
    Placement,
    closed_mesh,
    describe_nan,
    sample_part,
)

SUFFIXES = {
    ".stl": "stl",
    ".step": "step",
    ".stp": "step",
    ".py": "script",
    ".npy": "npy",
    ".png": "png",
}
#: Time limit of a script or a STEP reader [s] (CadQuery's import takes about 5 s).
DEFAULT_TIMEOUT_S = 120.0
DEFAULT_THICKNESS_M = 0.005
#: Flat ground a plate has beyond its textured area along the slide, each side [m]: the
#: presets' (36 mm for a 36 mm texture on a 108 mm plate), where a pad lands and leaves.
RUN_IN_M = 0.036
_MEMO: dict[tuple, Plate] = {}
register_memo("users' plates", _MEMO.clear)
_MEMO_MAX = 16


@dataclass(frozen=True)
class Source:
    """A parsed plate reference (see the module)."""

    path: str
    function: str = "plate"
    units: str | None = None
    up: str = "+z"
    rotate_deg: float = 0.0
    scale: float = 1.0
    pixel_m: float | None = None
    z_scale_m: float | None = None
    thickness_m: float | None = None
    fill_overhangs: bool = False
    holes: bool = False
    timeout_s: float = DEFAULT_TIMEOUT_S
    name: str | None = None

    @property
    def kind(self) -> str:
        return SUFFIXES[Path(self.path).suffix.lower()]

    def ref(self) -> str:
        """The reference string that parses back to this source."""
        out = self.path + (f":{self.function}" if self.function != "plate" else "")
        opts = [
            f"{f.name}={_text(getattr(self, f.name))}"
            for f in fields(self)
            if f.name not in ("path", "function") and getattr(self, f.name) != f.default
        ]
        return out + ("?" + "&".join(opts) if opts else "")


def _text(x) -> str:
    if isinstance(x, bool):
        return "true" if x else "false"
    return repr(x) if isinstance(x, float) else str(x)


_FLOATS = ("rotate_deg", "scale", "pixel_m", "z_scale_m", "thickness_m", "timeout_s")
_BOOLS = ("fill_overhangs", "holes")


def is_user_plate(ref) -> bool:
    """Whether ``ref`` names a user's file (by its suffix), not a preset or a plate file."""
    path = str(ref).split("?", 1)[0]
    if path.lower().endswith(".py") or ".py:" in path.lower():
        return True
    return Path(path).suffix.lower() in SUFFIXES


def parse_ref(ref: str, **options) -> Source:
    """The :class:`Source` of a plate reference; ``options`` add to (or override) the ones
    after its ``?``."""
    text, _, query = str(ref).partition("?")
    function = "plate"
    head, colon, tail = text.rpartition(":")
    if colon and head.lower().endswith(".py") and tail.isidentifier():
        text, function = head, tail
    if Path(text).suffix.lower() not in SUFFIXES:
        raise ConfigError(
            f"plate file {text!r}: suffix {Path(text).suffix!r} is not valid; valid: "
            f"{', '.join(sorted(SUFFIXES))}"
        )
    known = {f.name for f in fields(Source)} - {"path"}
    opts: dict = {}
    pairs = []
    for item in filter(None, query.split("&")):
        key, eq, val = item.partition("=")
        if not eq:
            raise ConfigError(f"plate {text!r}: option {item!r} is not key=value")
        pairs.append((unquote(key), unquote(val)))  # '+' stays a plus: up=+y
    for key, val in [*pairs, *options.items()]:
        if key not in known:
            raise ConfigError(
                f"plate {text!r}: option {key!r} is not valid; valid: {', '.join(sorted(known))}"
            )
        opts[key] = _option(text, key, val)
    return Source(path=text, function=opts.pop("function", function), **opts)


def _option(where: str, key: str, val):
    if val is None:
        return None
    try:
        if key in _FLOATS:
            x = float(val)
            if not math.isfinite(x):
                raise ValueError
            return x
        if key in _BOOLS:
            if isinstance(val, bool):
                return val
            if str(val).lower() not in ("true", "false", "1", "0"):
                raise ValueError
            return str(val).lower() in ("true", "1")
    except (TypeError, ValueError):
        raise ConfigError(
            f"plate {where!r}: {key} = {val!r} is not valid; valid: "
            + ("true or false" if key in _BOOLS else "a number")
        ) from None
    return str(val)


def load_user_plate(ref: str | Source, *, base_dir: str | Path | None = None, **options) -> Plate:
    """The plate of a user's file (see the module); ``base_dir``: where a relative path is
    found (default: the working directory)."""
    src = ref if isinstance(ref, Source) else parse_ref(ref, **options)
    path = Path(src.path)
    if base_dir is not None and not path.is_absolute():
        path = Path(base_dir) / path
    where = f"plate file {str(src.path)!r}"
    if not path.is_file():
        raise ConfigError(f"{where}: no such file ({path.resolve()})")
    map_files.check_size(path, where)
    digest = map_files.file_sha256(path)
    key = (str(path.resolve()), digest, replace(src, path=""))
    if key in _MEMO:
        return _MEMO[key]
    plate = _load(src, path, digest, where)
    if len(_MEMO) >= _MEMO_MAX:
        _MEMO.pop(next(iter(_MEMO)))
    _MEMO[key] = plate
    return plate


def plate_name(src: Source, path: Path) -> str:
    """A user's plate's name: its ``name`` option, else the file's stem, with the script's
    function after it where that says more (``knurl.py:fine`` is ``knurl-fine``;
    ``pins.py:pins`` and ``pins.py:plate`` are ``pins``)."""
    if src.name:
        return src.name
    own = src.function in ("plate", path.stem)
    return path.stem if own else f"{path.stem}-{src.function}"


def _load(src: Source, path: Path, digest: str, where: str) -> Plate:
    name = plate_name(src, path)
    if src.kind in ("npy", "png"):
        z, pixel, notes = _raster(src, path, where)
        span = ((z.shape[1] - 1) * pixel, (z.shape[0] - 1) * pixel)
        thickness = src.thickness_m or DEFAULT_THICKNESS_M
        return _plate(z, pixel, span, thickness, name, src, digest, notes)
    placement = Placement(src.units or "mm", src.up, src.rotate_deg, src.scale)
    if src.kind == "stl":
        vertices, faces = _read_stl(path.read_bytes(), where)
    else:
        vertices, faces = _run_worker(src, path, where)
    mesh = closed_mesh(vertices, faces, where)
    part = sample_part(
        mesh,
        placement,
        src.pixel_m or DEFAULT_PIXEL_M,
        where,
        fill_overhangs=src.fill_overhangs,
        holes=src.holes,
    )
    thickness = src.thickness_m or part.thickness_m
    return _plate(part.z, part.pixel_m, part.area_m, thickness, name, src, digest, part.notes)


def _plate(z, pixel: float, area, thickness: float, name: str, src: Source, digest, notes) -> Plate:
    """The plate of a map: the map over the textured area ``area`` (x, y) [m] and the rest of
    the part; a flat base extends it to :data:`RUN_IN_M` beyond the texture along x."""
    where = f"plate file {src.path!r}"
    digest = digest[:16]
    ny, nx = z.shape
    span = ((nx - 1) * pixel, (ny - 1) * pixel)
    length = max(span[0], area[0] + 2 * RUN_IN_M)
    if length > span[0] + 1e-9:
        notes = [
            *notes,
            f"a flat base extends the part from {span[0] * 1e3:.4g} to {length * 1e3:.4g} mm along "
            f"x, {RUN_IN_M * 1e3:g} mm beyond the texture each side, where a pad lands and leaves",
        ]
    try:
        texture = HeightMap(
            z, pixel, source=f"{src.ref()} (file sha256 {digest})", notes=tuple(notes)
        )
        return Plate(
            texture,
            float(length),
            float(span[1]),
            float(thickness),
            float(area[0]),
            float(area[1]),
            name=name,
        )
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _read_stl(data: bytes, where: str):
    import io

    import trimesh

    try:
        mesh = trimesh.load(io.BytesIO(data), file_type="stl", process=False)
    except Exception as exc:  # noqa: BLE001  (any parse failure of the user's bytes)
        raise ConfigError(f"{where}: not a readable STL file ({exc})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ConfigError(f"{where}: the STL holds no triangles; valid: a closed solid")
    return mesh.vertices, mesh.faces


def _raster(src: Source, path: Path, where: str) -> tuple[np.ndarray, float, list[str]]:
    """A height map file's samples [m] (rows along +y, lowest at 0), pixel size and notes;
    its size checked from its header before it is read (:mod:`.map_files`)."""
    if src.pixel_m is None:
        raise ConfigError(f"{where}: a height map needs its sample spacing: pass pixel_m=... (m)")
    if src.up != "+z":
        raise ConfigError(f"{where}: up = {src.up!r} is not valid for a height map; valid: +z")
    turns = src.rotate_deg / 90
    if turns != round(turns):
        raise ConfigError(
            f"{where}: rotate_deg = {src.rotate_deg:g} is not valid for a height map; valid: "
            "a multiple of 90"
        )
    pixel = src.pixel_m * src.scale
    if src.kind == "npy":
        unit = {None: 1.0, "m": 1.0, "mm": 1e-3, "um": 1e-6}.get(src.units)
        if unit is None:
            raise ConfigError(f"{where}: units = {src.units!r} is not valid; valid: m, mm, um")
        shape, _, _ = map_files.npy_header(path, where)
        _check_sides(shape[::-1] if round(turns) % 2 else shape, pixel, where)
        z = map_files.read_npy(path, where) * unit
    else:
        if src.z_scale_m is None:
            raise ConfigError(
                f"{where}: a PNG height map needs its scale: pass z_scale_m=... (m a count)"
            )
        z = map_files.read_png(path, where)[::-1] * src.z_scale_m  # picture rows run -y
    z = np.rot90(np.asarray(z, float), int(round(turns)) % 4) * src.scale
    _check_sides(z.shape, pixel, where)
    notes = []
    if np.isnan(z).any():
        what = f"the map has {describe_nan(z, pixel)}"
        if not src.holes:
            raise ConfigError(
                f"{where}: {what}; valid: a height at every sample, or pass holes=true if the "
                "NaN samples are intended holes (no material: the pad meets nothing there)"
            )
        notes.append(f"{what}; kept as holes (holes=true)")
    if np.isfinite(z).any():
        z = z - np.nanmin(z)
    return z, pixel, notes


def _check_sides(shape: tuple[int, ...], pixel: float, where: str) -> None:
    lo_m, hi_m = PLATE_SIDE_RANGE_M
    for axis, n in zip("yx", shape, strict=True):
        side = (n - 1) * pixel
        if not lo_m <= side <= hi_m:
            raise ConfigError(
                f"{where}: the map is {side:.4g} m along {axis} ({n} samples of {pixel:g} m); "
                f"valid: [{lo_m:g}, {hi_m:g}] m"
            )


def _run_worker(src: Source, path: Path, where: str):
    """The tessellation of a STEP file or a script's part, made in a separate process in its
    own session, which is killed whole when it ends or at the limit (:mod:`.cad_run`)."""
    from .cad_run import run_limited

    if not 1 <= src.timeout_s <= 3600:
        raise ConfigError(
            f"{where}: timeout_s = {src.timeout_s:g} is not valid; valid: [1, 3600] s"
        )
    with tempfile.TemporaryDirectory(prefix="sim_tactile_cad_") as tmp:
        out = Path(tmp) / "mesh.npz"
        cmd = [
            sys.executable,
            "-m",
            "sim_tactile.plates.parts.cad_worker",
            src.kind,
            str(path.resolve()),
            str(out),
        ]
        if src.kind == "script":
            cmd.append(src.function)
        finished, status, err = run_limited(
            cmd,
            cwd=str(path.resolve().parent),
            env={**os.environ, "PYTHONPATH": _package_root()},
            timeout_s=src.timeout_s,
            log=Path(tmp) / "stderr.txt",
        )
        if not finished:
            what = f"{src.function}()" if src.kind == "script" else "reading it"
            raise ConfigError(
                f"{where}: {what} did not finish within timeout_s = {src.timeout_s:g} s; valid: "
                "a part made within the limit (pass timeout_s=... for a slow one)"
            )
        if status != 0 or not out.is_file():
            lines = [ln for ln in err.splitlines() if ln.strip()]
            reason = lines[-1] if lines else f"exit status {status}"
            what = f"{src.function}() failed" if src.kind == "script" else "could not be read"
            raise ConfigError(f"{where}: {what}: {reason}")
        with np.load(out, allow_pickle=False) as npz:
            return npz["vertices"], npz["faces"]


def _package_root() -> str:
    root = str(Path(__file__).resolve().parents[2])
    extra = os.environ.get("PYTHONPATH")
    return root + (os.pathsep + extra if extra else "")
