"""Parametric plate definitions: frozen, validated, hashable, in SI units.

Geometry conventions (the manual's plates reference, for every plate and sensor): the plate's top surface is at z = 0, features rise to
z > 0, the textured area is centred on the origin, sliding goes along +x and ridges run
along y. The base is a box of ``length_m`` (x) by ``width_m`` (y) by ``thickness_m`` below
z = 0.

A :class:`Plate` holds one texture: :class:`Flat`, :class:`Ridges`, :class:`Grating`,
:class:`Bumps` or :class:`Roughness`. Every constructor validates its input and raises a
:class:`~sim_tactile.errors.ConfigError` that names the parameter, the value and the valid
range, before anything is built or cached.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import asdict, dataclass, field, fields
from typing import Literal

import numpy as np

from ... import _validate as v
from ...errors import ConfigError
from ...hashing import content_hash
from .geometry import Feature, bump_features, grating_features, ridge_features

#: Tallest feature a plate may carry [m]: the finger pads of the scenes are at most 10 mm
#: thick, so a taller feature would hit the finger's bone rather than its skin.
MAX_FEATURE_HEIGHT_M = 0.010
#: Smallest feature dimension [m]: the STL tolerance is 1 um, keep features 10x above it.
MIN_FEATURE_SIZE_M = 10e-6
#: Largest number of raster samples a roughness profile may have (memory and STL size).
MAX_ROUGHNESS_SAMPLES = 200_001
#: Largest draft angle [deg]; at 60 degrees a drafted ridge is a low wedge already.
MAX_DRAFT_DEG = 60.0
#: Largest number of samples a height map may have (128 MB of float64).
MAX_HEIGHTMAP_SAMPLES = 16_000_000
#: Most raised features (ridges, grating ridges, bumps) a plate may carry: each is a MuJoCo
#: geom, and 10,000 build in 0.4 s into a 1 MB MJCF; a million took minutes and 100 MB.
MAX_FEATURES = 10_000

BumpShape = Literal["box", "cylinder", "hemisphere"]
BUMP_SHAPES = ("box", "cylinder", "hemisphere")


def _canon(x: object) -> object:
    """A canonical JSON-able form: floats rounded to 1e-12 m (far below any tolerance)."""
    if isinstance(x, float):
        r = round(x, 12)
        return 0.0 if r == 0 else r
    if isinstance(x, dict):
        return {k: _canon(val) for k, val in x.items()}
    if isinstance(x, list | tuple):
        return [_canon(val) for val in x]
    return x


@dataclass(frozen=True)
class Flat:
    """No texture: the textured area is flat."""

    kind: Literal["flat"] = field(default="flat", init=False)

    def features(self, area_length_m: float, area_width_m: float) -> list[Feature]:
        return []


@dataclass(frozen=True)
class Ridges:
    """``count`` straight ridges along y, evenly spread over the textured area's x extent.

    Ridge ``i`` is centred at ``x = -Lx/2 + (i + 1/2) * Lx / count`` (Lx the textured area's
    length), so the pitch is ``Lx / count``. The cross-section is a trapezoid of bottom
    width ``width_m`` and top width ``width_m - 2 * height_m * tan(draft_deg)``; draft 0 is a
    rectangle. ``length_m`` is the ridge length along y (default: the textured area's width).
    """

    count: int
    width_m: float
    height_m: float
    draft_deg: float = 0.0
    length_m: float | None = None
    kind: Literal["ridges"] = field(default="ridges", init=False)

    def __post_init__(self) -> None:
        v.integer("ridges.count", self.count, 1, MAX_FEATURES)
        v.in_range("ridges.width_m", self.width_m, MIN_FEATURE_SIZE_M, None, unit="m")
        v.in_range(
            "ridges.height_m", self.height_m, MIN_FEATURE_SIZE_M, MAX_FEATURE_HEIGHT_M, unit="m"
        )
        v.in_range("ridges.draft_deg", self.draft_deg, 0.0, MAX_DRAFT_DEG, hi_open=True, unit="deg")
        if self.length_m is not None:
            v.in_range("ridges.length_m", self.length_m, MIN_FEATURE_SIZE_M, None, unit="m")
        top = self.top_width_m
        if top < MIN_FEATURE_SIZE_M:
            max_draft = math.degrees(
                math.atan((self.width_m - MIN_FEATURE_SIZE_M) / (2 * self.height_m))
            )
            raise ConfigError(
                f"ridges.draft_deg = {self.draft_deg:g} deg leaves a top width of {top:g} m for "
                f"width_m = {self.width_m:g} and height_m = {self.height_m:g}; valid: "
                f"[0, {max_draft:.3g}] deg"
            )

    @property
    def top_width_m(self) -> float:
        return self.width_m - 2.0 * self.height_m * math.tan(math.radians(self.draft_deg))

    def features(self, area_length_m: float, area_width_m: float) -> list[Feature]:
        return ridge_features(
            area_length_m,
            area_width_m,
            self.count,
            self.width_m,
            self.height_m,
            self.draft_deg,
            self.length_m,
            "ridges",
        )


@dataclass(frozen=True)
class Grating:
    """A periodic grating of ridges along y filling the textured area's x extent.

    Give the ridge width either as ``duty`` (fraction of the period, bottom width) or as
    ``width_m``. The number of ridges is ``floor(Lx / period_m)`` and they are centred as in
    :class:`Ridges`, so the pitch is exactly ``period_m``.
    """

    period_m: float
    height_m: float
    duty: float | None = 0.5
    width_m: float | None = None
    draft_deg: float = 0.0
    kind: Literal["grating"] = field(default="grating", init=False)

    def __post_init__(self) -> None:
        v.in_range("grating.period_m", self.period_m, 2 * MIN_FEATURE_SIZE_M, None, unit="m")
        v.in_range(
            "grating.height_m", self.height_m, MIN_FEATURE_SIZE_M, MAX_FEATURE_HEIGHT_M, unit="m"
        )
        if (self.duty is None) == (self.width_m is None):
            raise ConfigError("grating: give exactly one of duty or width_m")
        if self.duty is not None:
            v.in_range("grating.duty", self.duty, 0.0, 1.0, lo_open=True, hi_open=True)
        else:
            v.in_range(
                "grating.width_m",
                self.width_m,
                MIN_FEATURE_SIZE_M,
                self.period_m,
                hi_open=True,
                unit="m",
            )
        v.in_range(
            "grating.draft_deg", self.draft_deg, 0.0, MAX_DRAFT_DEG, hi_open=True, unit="deg"
        )
        w = self.ridge_width_m
        top = w - 2.0 * self.height_m * math.tan(math.radians(self.draft_deg))
        if top < MIN_FEATURE_SIZE_M:
            max_draft = math.degrees(math.atan((w - MIN_FEATURE_SIZE_M) / (2 * self.height_m)))
            raise ConfigError(
                f"grating.draft_deg = {self.draft_deg:g} deg leaves a top width of {top:g} m for a "
                f"ridge width of {w:g} m and height_m = {self.height_m:g}; valid: [0, {max_draft:.3g}] deg"
            )

    @property
    def ridge_width_m(self) -> float:
        return self.duty * self.period_m if self.duty is not None else float(self.width_m)

    def features(self, area_length_m: float, area_width_m: float) -> list[Feature]:
        return grating_features(
            area_length_m,
            area_width_m,
            self.period_m,
            self.ridge_width_m,
            self.height_m,
            self.draft_deg,
        )


@dataclass(frozen=True)
class Bumps:
    """A ``rows`` (y) by ``cols`` (x) grid of bumps centred on the origin.

    ``size_m`` is the footprint (box side or cylinder / hemisphere diameter); ``spacing_m``
    is the centre-to-centre pitch (default: the textured area divided evenly, e.g. 36 mm / 6
    = 6 mm). A ``hemisphere`` of height below ``size_m / 2`` is a spherical cap; its height
    may not exceed ``size_m / 2``. ``height_m`` defaults to ``size_m / 2`` for hemispheres.
    """

    rows: int
    cols: int
    shape: BumpShape
    size_m: float
    height_m: float | None = None
    spacing_m: float | None = None
    kind: Literal["bumps"] = field(default="bumps", init=False)

    def __post_init__(self) -> None:
        v.integer("bumps.rows", self.rows, 1, 1000)
        v.integer("bumps.cols", self.cols, 1, 1000)
        v.one_of("bumps.shape", self.shape, BUMP_SHAPES)
        if self.rows * self.cols > MAX_FEATURES:
            raise ConfigError(
                f"bumps.rows x bumps.cols = {self.rows} x {self.cols} = {self.rows * self.cols} "
                f"bumps; valid: at most {MAX_FEATURES} (each bump is a MuJoCo geom)"
            )
        v.in_range("bumps.size_m", self.size_m, MIN_FEATURE_SIZE_M, None, unit="m")
        if self.height_m is None:
            if self.shape != "hemisphere":
                raise ConfigError(f"bumps.height_m is required for shape {self.shape!r}")
            object.__setattr__(self, "height_m", self.size_m / 2)
        hi = self.size_m / 2 if self.shape == "hemisphere" else MAX_FEATURE_HEIGHT_M
        v.in_range(
            "bumps.height_m",
            self.height_m,
            MIN_FEATURE_SIZE_M,
            min(hi, MAX_FEATURE_HEIGHT_M),
            unit="m",
        )
        if self.spacing_m is not None:
            v.positive("bumps.spacing_m", self.spacing_m, unit="m")
            if self.spacing_m <= self.size_m and (self.rows > 1 or self.cols > 1):
                raise ConfigError(
                    f"bumps.spacing_m = {self.spacing_m:g} m makes bumps of size_m = "
                    f"{self.size_m:g} m overlap; valid: spacing_m > {self.size_m:g} m"
                )

    def features(self, area_length_m: float, area_width_m: float) -> list[Feature]:
        return bump_features(
            area_length_m,
            area_width_m,
            self.rows,
            self.cols,
            self.shape,
            self.size_m,
            self.height_m,
            self.spacing_m,
        )


@dataclass(frozen=True)
class Roughness:
    """Random isotropic-in-x roughness with a lay along y (a turned surface's feed marks run
    across the slide), from a seeded spectral method.

    The profile z(x) is Gaussian with a Gaussian autocorrelation of length
    ``corr_length_m``, sampled every ``resolution_m`` (default ``corr_length_m / 8``), made
    zero-mean and scaled so that its arithmetic mean deviation Ra (ISO 4287, over the
    samples) equals ``ra_m`` exactly. Between samples the surface is linear, as the STL and
    MuJoCo's height field are. The surface is constant along y (the lay): Ra is a profile
    parameter, measured across the lay, which is how the roughness paper's standards were
    made (cylindrical turning).
    """

    ra_m: float
    corr_length_m: float
    seed: int = 0
    resolution_m: float | None = None
    kind: Literal["roughness"] = field(default="roughness", init=False)

    def __post_init__(self) -> None:
        v.in_range("roughness.ra_m", self.ra_m, 1e-9, 1e-3, unit="m")
        v.in_range("roughness.corr_length_m", self.corr_length_m, 1e-6, 0.01, unit="m")
        v.integer("roughness.seed", self.seed, 0, 2**63 - 1)
        if self.resolution_m is None:
            object.__setattr__(self, "resolution_m", self.corr_length_m / 8)
        v.in_range(
            "roughness.resolution_m", self.resolution_m, 1e-7, self.corr_length_m / 2, unit="m"
        )

    def features(self, area_length_m: float, area_width_m: float) -> list[Feature]:
        """None: a rough surface is a height profile (:func:`.features.roughness_profile`)."""
        return []


@dataclass(frozen=True, eq=False)
class HeightMap:
    """A sampled top surface: heights ``z`` [m] (rows along y, columns along x) every
    ``pixel_m`` over the textured area, bilinear between samples; NaN where there is no
    material. Made from a user's CAD, script or height map (:mod:`.user`).

    Sample ``(i, j)`` lies at ``x = -(nx - 1) pixel / 2 + j pixel``, ``y = -(ny - 1) pixel / 2
    + i pixel``: the map is centred on the textured area and spans at least it (a part's map
    spans the part, its textured area the raised part of it) and at most the plate, whose
    base (z = 0) lies around it. The geometry is the samples' bytes
    (their SHA-256 is in :meth:`params`), so two files that give the same map give the same
    plate, and an edited file another one. ``source`` says where it came from (not part of
    the geometry), ``notes`` what its loading reported (a filled overhang).
    """

    z: np.ndarray
    pixel_m: float
    source: str = ""
    notes: tuple[str, ...] = ()
    kind: Literal["heightmap"] = field(default="heightmap", init=False)

    def __post_init__(self) -> None:
        v.in_range("heightmap.pixel_m", self.pixel_m, 1e-6, 1e-2, unit="m")
        z = np.asarray(self.z)
        if z.ndim != 2 or min(z.shape) < 2:
            raise ConfigError(
                f"heightmap.z must be a 2-D array of at least 2 x 2 samples, got shape {z.shape}"
            )
        if z.size > MAX_HEIGHTMAP_SAMPLES:
            raise ConfigError(
                f"heightmap.z has {z.size} samples ({z.shape[0]} x {z.shape[1]}); valid: at most "
                f"{MAX_HEIGHTMAP_SAMPLES} (a coarser pixel_m, or a smaller part)"
            )
        if not np.issubdtype(z.dtype, np.floating) and not np.issubdtype(z.dtype, np.integer):
            raise ConfigError(f"heightmap.z must hold numbers, got dtype {z.dtype}")
        z = np.ascontiguousarray(z, dtype="<f8")
        z = np.where(np.isnan(z), np.nan, z + 0.0)  # one NaN, no -0.0: one geometry, one hash
        if np.isinf(z).any():
            raise ConfigError(
                "heightmap.z holds an infinite height; valid: finite, or NaN (no material)"
            )
        if np.isnan(z).all():
            raise ConfigError("heightmap.z holds no material (every sample is NaN)")
        lo, hi = float(np.nanmin(z)), float(np.nanmax(z))
        if lo < -MAX_FEATURE_HEIGHT_M or hi > MAX_FEATURE_HEIGHT_M:
            raise ConfigError(
                f"heightmap.z spans [{lo:g}, {hi:g}] m; valid: within +-{MAX_FEATURE_HEIGHT_M:g} m "
                "of the base (z = 0)"
            )
        z.setflags(write=False)
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "_sha", hashlib.sha256(z.tobytes()).hexdigest())

    @property
    def sha256(self) -> str:
        """SHA-256 of the samples (little-endian float64, C order)."""
        return self._sha

    @property
    def extent_m(self) -> tuple[float, float]:
        """The map's span (x, y) [m]."""
        ny, nx = self.z.shape
        return (nx - 1) * self.pixel_m, (ny - 1) * self.pixel_m

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """The samples' coordinates (xs, ys) [m]."""
        ny, nx = self.z.shape
        p = self.pixel_m
        return (np.arange(nx) - (nx - 1) / 2) * p, (np.arange(ny) - (ny - 1) / 2) * p

    def params(self) -> dict:
        return {
            "kind": self.kind,
            "pixel_m": self.pixel_m,
            "shape": list(self.z.shape),
            "sha256": self.sha256,
        }

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, HeightMap):
            return NotImplemented
        return self.pixel_m == other.pixel_m and self.sha256 == other.sha256

    def __hash__(self) -> int:
        return hash((self.pixel_m, self.sha256))

    def features(self, area_length_m: float, area_width_m: float) -> list[Feature]:
        """None: a height map is its samples."""
        return []


Texture = Flat | Ridges | Grating | Bumps | Roughness | HeightMap
_TEXTURES = {
    "flat": Flat,
    "ridges": Ridges,
    "grating": Grating,
    "bumps": Bumps,
    "roughness": Roughness,
}


@dataclass(frozen=True)
class Plate:
    """A textured plate. Dimensions in metres; see the module docstring for the frame."""

    texture: Texture
    length_m: float = 0.108
    width_m: float = 0.036
    thickness_m: float = 0.005
    area_length_m: float = 0.036
    area_width_m: float = 0.036
    name: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.texture, Flat | Ridges | Grating | Bumps | Roughness | HeightMap):
            raise ConfigError(
                f"plate.texture must be one of {', '.join(_TEXTURES)} or a heightmap, got "
                f"{type(self.texture).__name__}"
            )
        v.in_range("plate.length_m", self.length_m, 1e-3, 2.0, unit="m")
        v.in_range("plate.width_m", self.width_m, 1e-3, 2.0, unit="m")
        v.in_range("plate.thickness_m", self.thickness_m, 0.5e-3, 0.1, unit="m")
        v.in_range("plate.area_length_m", self.area_length_m, 1e-3, self.length_m, unit="m")
        v.in_range("plate.area_width_m", self.area_width_m, 1e-3, self.width_m, unit="m")
        t = self.texture
        if isinstance(t, Roughness):
            n = round(self.area_length_m / t.resolution_m) + 1
            if n > MAX_ROUGHNESS_SAMPLES:
                raise ConfigError(
                    f"roughness.resolution_m = {t.resolution_m:g} m gives {n} samples over "
                    f"{self.area_length_m:g} m; valid: at most {MAX_ROUGHNESS_SAMPLES} samples "
                    f"(resolution_m >= {self.area_length_m / (MAX_ROUGHNESS_SAMPLES - 1):g} m)"
                )
        if isinstance(t, HeightMap):
            for key, span, area, side in (
                ("x", t.extent_m[0], self.area_length_m, self.length_m),
                ("y", t.extent_m[1], self.area_width_m, self.width_m),
            ):
                if not area - 1e-9 <= span <= side + 1e-9:
                    raise ConfigError(
                        f"the height map spans {span:g} m along {key} ((samples - 1) x pixel_m); "
                        f"valid: from the textured area's {area:g} m to the plate's {side:g} m"
                    )
        n = math.floor(self.area_length_m / t.period_m + 1e-9) if isinstance(t, Grating) else 0
        if n > MAX_FEATURES:
            raise ConfigError(
                f"grating.period_m = {t.period_m:g} m gives {n} ridges over {self.area_length_m:g} m; valid: at most {MAX_FEATURES} (each "
                f"ridge is a MuJoCo geom: period_m >= {self.area_length_m / MAX_FEATURES:g} m)"
            )
        # expanding the features checks that they fit and do not overlap
        self.texture.features(self.area_length_m, self.area_width_m)

    @property
    def family(self) -> str:
        return self.texture.kind

    def params(self) -> dict:
        """Canonical parameters: everything that defines the geometry (not the name)."""
        d = {
            f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("texture", "name")
        }
        t = self.texture
        d["texture"] = t.params() if isinstance(t, HeightMap) else asdict(t)
        return _canon(d)

    @property
    def hash(self) -> str:
        """A 16-hex-digit content hash of :meth:`params`."""
        return content_hash(self.params(), 16)

    @property
    def slug(self) -> str:
        return (self.name or f"plate-{self.hash}").replace("/", "_")

    @classmethod
    def from_params(
        cls, params: dict, name: str | None = None, maps: dict[str, np.ndarray] | None = None
    ) -> Plate:
        """Build a plate from :meth:`params`-style data (e.g. a TOML or JSON file). A height
        map's parameters name its samples by SHA-256: ``maps`` holds them by that hash (a
        data set's store does, :func:`~sim_tactile.datasets.store.plate_maps`)."""
        if not isinstance(params, dict) or not isinstance(params.get("texture"), dict):
            raise ConfigError("plate parameters must be a table with a 'texture' table")
        p = dict(params)
        tex = dict(p.pop("texture"))
        kind = tex.pop("kind", None)
        if kind == "heightmap":
            return cls._from_map_params(p, tex, name, maps or {})
        if not isinstance(kind, str) or kind not in _TEXTURES:
            raise ConfigError(
                f"texture.kind = {kind!r} is not valid; valid: {', '.join(_TEXTURES)}"
            )
        if kind == "grating" and tex.get("width_m") is not None and "duty" not in tex:
            tex["duty"] = None  # a width given, the default duty does not apply (TOML has no null)
        try:
            texture = _TEXTURES[kind](**tex)
            return cls(texture=texture, name=name, **p)
        except TypeError as exc:
            raise ConfigError(f"plate parameters: {exc}") from None

    @classmethod
    def _from_map_params(cls, p: dict, tex: dict, name, maps: dict) -> Plate:
        sha = tex.get("sha256")
        if not isinstance(sha, str) or sha not in maps:
            raise ConfigError(
                f"plate {name or ''!s}: its height map (sha256 {sha}) is not given; a height-map "
                "plate is re-created from its samples (a data set's store holds them)"
            )
        texture = HeightMap(np.asarray(maps[sha]), float(tex.get("pixel_m", 0.0)))
        if texture.sha256 != sha or list(texture.z.shape) != list(tex.get("shape", [])):
            raise ConfigError(
                f"plate {name or ''!s}: the height map given for sha256 {sha} has sha256 "
                f"{texture.sha256} and shape {list(texture.z.shape)}; valid: the recorded map"
            )
        return cls(texture=texture, name=name, **p)
