"""A plate's top surface as the simulator asks about it: one :class:`Surface` per kind of
texture, each answering for itself.

- :class:`FeatureSurface`: a plate of raised features (flat, ridges, gratings, bumps): the
  highest feature at each point;
- :class:`ProfileSurface`: a rough plate: its profile z(x) (:func:`profile_samples`, linear
  between samples) across the textured area;
- :class:`MapSurface`: a height map (:class:`~.spec.HeightMap`): its samples, bilinear
  between them (:func:`map_height`), NaN where it holds no material.

Each owns four things: its height in numpy (:meth:`Surface.height`: the plate's definition,
which the CAD solid, the MuJoCo geometry, the preview and the compiled colliders are tested
against); the arrays the compiled depth kernels read (:attr:`Surface.arrays`, a named tuple
whose class is the kernel's kind: :class:`ProfileArrays`, :class:`MapArrays`; a plate of
features is read from its MuJoCo geoms instead); its scales (the feature scale, the period
along the slide and the walls, one formula each in :mod:`.scales`); and the skin nodes'
collider margin under a held force (:attr:`Surface.margin_m`). :func:`surface_of` is the one
place that tells the kinds apart; the simulator asks the surface, and never the texture's
kind. A surface is kept per plate in the process (the feature list, the profile and the
scales are computed once a plate).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ...cache import memoized
from . import scales
from .geometry import Feature
from .spec import HeightMap, Plate, Roughness

#: Collider margin [m] of the skin nodes when the pad is held at a force: nodes this far above
#: the plate are reported, so they can join the contact when the pad sinks; a step that would
#: move the pad further than this is re-collided at the new height.
QS_MARGIN_M = 0.5e-3
#: The margin on roughness plates: the profile collider keeps the one MuJoCo's height-field
#: collider had there (each node within it was a contact MuJoCo generated, which filled its
#: contact buffer at 0.5 mm), so that their slides stayed unchanged but for the depths; a
#: step that sinks further is re-collided.
QS_MARGIN_MUJOCO_M = 0.1e-3


class ProfileArrays(NamedTuple):
    """What the compiled depth kernel reads of a rough plate: the profile's samples ``px``,
    ``pz`` [m], the textured area's half-extents ``ax``, ``ay`` and the plate's ``sx``,
    ``sy`` [m]."""

    px: np.ndarray
    pz: np.ndarray
    ax: float
    ay: float
    sx: float
    sy: float


class MapArrays(NamedTuple):
    """What the compiled depth kernel reads of a height map: the samples ``z`` [m]
    (read-only, C order), the ``pixel`` [m], the map's half-span ``ax``, ``ay`` (its
    ``(samples - 1) pixel``, which covers the textured area) and the plate's half-extents
    ``sx``, ``sy`` [m]."""

    z: np.ndarray
    pixel: float
    ax: float
    ay: float
    sx: float
    sy: float


class Surface:
    """What every kind of surface answers (see the module docstring). ``plate`` is the plate
    whose geometry it is (its name plays no part)."""

    #: the skin nodes' collider margin when the pad is held at a force [m]
    margin_m: float = QS_MARGIN_M
    #: the arrays of the compiled depth kernel (their class is its kind); None: a plate of
    #: features, which the compiled collider reads from the MuJoCo model's geoms
    arrays: ProfileArrays | MapArrays | None = None
    #: the roughness profile ``(x, z)`` [m] below any node grid (None: no micro-roughness)
    profile: tuple[np.ndarray, np.ndarray] | None = None
    #: its arithmetic mean deviation Ra [m] (None: no micro-roughness)
    ra_m: float | None = None
    #: the height map whose samples the surface is (None: not a sampled surface)
    height_map: HeightMap | None = None

    def __init__(self, plate: Plate) -> None:
        self.plate = plate
        #: the raised features, in a fixed order (x-major); none but on a plate of features
        self.features: tuple[Feature, ...] = ()
        self._off_x, self._off_y = plate.length_m / 2, plate.width_m / 2

    def height(
        self, x: np.ndarray | float, y: np.ndarray | float, near: tuple[float, float] | None = None
    ) -> np.ndarray:
        """The top surface's height z(x, y) [m] above the base (z = 0), NaN off the plate;
        broadcasts ``x`` and ``y``. ``near``: ``(x_c, reach)``, points that all lie within
        ``reach`` of ``x_c`` along the slide (a plate of features then looks at the features
        there only; the same numbers)."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        z = self._top(x, y, near)
        off = (np.abs(x) > self._off_x) | (np.abs(y) > self._off_y)
        return np.where(off, np.nan, z)

    def _top(self, x: np.ndarray, y: np.ndarray, near) -> np.ndarray:
        raise NotImplementedError

    @property
    def feature_scale_m(self) -> float | None:
        """The smallest feature width or gap [m] (:func:`.scales.feature_scale_m`); None
        where there is none (flat, rough)."""
        return None

    @property
    def period_m(self) -> float | None:
        """The texture's period along the slide [m] (:func:`.scales.feature_period_m`); None
        where it has none."""
        return None

    @property
    def walls(self) -> tuple[np.ndarray, np.ndarray]:
        """The x positions of the vertical walls across the slide and the y positions of
        those along it [m] (:func:`.scales.box_walls`): the faces of the boxes."""
        return np.zeros(0), np.zeros(0)

    @property
    def has_walls(self) -> bool:
        """Whether the plate has box walls across the slide (that a grid could follow)."""
        return self.walls[0].size > 0

    @property
    def all_boxes(self) -> bool:
        """Whether the plate has features and every one is a box."""
        return False

    @property
    def boxes(self) -> np.ndarray:
        """(n, 5) the boxes' ``(x, half x, y, half y, height)`` [m]."""
        return np.zeros((0, 5))

    @property
    def all_caps(self) -> bool:
        """Whether the plate has features and every one is a spherical cap (a hemisphere's
        bumps): a relief without vertical walls where a pad rests on it."""
        return False

    def y_invariant(self, y: np.ndarray) -> bool:
        """Whether the height at points ``y`` [m] across the slide is independent of their y
        (bit for bit): then nodes with equal x share one depth."""
        return False

    def map_samples(self) -> dict[str, np.ndarray]:
        """The samples a store keeps beside the plate's parameters, by their SHA-256 (a
        height map's; none otherwise)."""
        return {}


class FeatureSurface(Surface):
    """A plate of raised features: the highest one at each point, the base elsewhere."""

    def __init__(self, plate: Plate) -> None:
        super().__init__(plate)
        self.features = tuple(plate.texture.features(plate.area_length_m, plate.area_width_m))
        fs = list(self.features)
        self._fx = np.array([f.x for f in fs])
        self._fhx = np.array([f.hx for f in fs])
        self._scale = scales.feature_scale_m(fs)
        self._period = scales.feature_period_m(fs)
        self._walls = scales.box_walls(fs)
        self._all_boxes = bool(fs) and all(f.kind == "box" for f in fs)
        self._all_caps = bool(fs) and all(f.kind == "cap" for f in fs)
        self._boxes = np.array(
            [[f.x, f.hx, f.y, f.hy, f.height_m] for f in fs if f.kind == "box"]
        ).reshape(-1, 5)

    def _top(self, x, y, near):
        z = np.zeros(x.shape)
        if near is None:
            picked = range(len(self.features))
        else:  # the features within reach (the rest are 0 there)
            picked = np.flatnonzero(np.abs(self._fx - near[0]) <= self._fhx + near[1])
        for k in picked:
            np.maximum(z, self.features[k].height(x, y), out=z)
        return z

    @property
    def feature_scale_m(self) -> float | None:
        return self._scale

    @property
    def period_m(self) -> float | None:
        return self._period

    @property
    def walls(self) -> tuple[np.ndarray, np.ndarray]:
        return self._walls

    @property
    def all_boxes(self) -> bool:
        return self._all_boxes

    @property
    def boxes(self) -> np.ndarray:
        return self._boxes

    @property
    def all_caps(self) -> bool:
        return self._all_caps


class ProfileSurface(Surface):
    """A rough plate: its profile z(x) over the textured area (linear between samples,
    constant along y: the lay), the base elsewhere on the plate."""

    margin_m = QS_MARGIN_MUJOCO_M

    def __init__(self, plate: Plate) -> None:
        super().__init__(plate)
        t = plate.texture
        self.profile = profile_samples(t, plate.area_length_m)
        self.ra_m = t.ra_m
        area = (plate.area_length_m / 2, plate.area_width_m / 2)
        self.arrays = ProfileArrays(*self.profile, *area, self._off_x, self._off_y)

    def _top(self, x, y, near):
        a = self.arrays
        inside = (np.abs(x) <= a.ax) & (np.abs(y) <= a.ay)
        return np.where(inside, np.interp(x, a.px, a.pz), 0.0)

    def y_invariant(self, y: np.ndarray) -> bool:
        """Every point inside the textured area's y extent (the profile varies along x
        only)."""
        return bool(len(y)) and float(np.abs(y).max()) < min(self.arrays.ay, self.arrays.sy)


class MapSurface(Surface):
    """A height map: its samples over the map's span (bilinear between them, NaN where it
    holds no material), the base elsewhere on the plate. Never independent of y: even where
    its rows are equal, the bilinear blend of two equal rows, ``(1 - ty) a + ty a``, rounds
    differently at different y."""

    def __init__(self, plate: Plate) -> None:
        super().__init__(plate)
        t = plate.texture
        ex, ey = t.extent_m
        z = np.ascontiguousarray(t.z, dtype=np.float64)
        self.arrays = MapArrays(z, float(t.pixel_m), ex / 2, ey / 2, self._off_x, self._off_y)
        self.height_map = t

    def _top(self, x, y, near):
        a = self.arrays
        on_map = (np.abs(x) <= a.ax) & (np.abs(y) <= a.ay)
        return np.where(on_map, map_height(x, y, self.height_map.z, self.height_map.pixel_m), 0.0)

    @property
    def feature_scale_m(self) -> float | None:
        return scales.map_scales(self.height_map)[0]

    @property
    def period_m(self) -> float | None:
        return scales.map_scales(self.height_map)[1]

    def map_samples(self) -> dict[str, np.ndarray]:
        return {self.height_map.sha256: self.height_map.z}


@memoized("plate surfaces", maxsize=128)
def surface_of(plate: Plate) -> Surface:
    """The surface of ``plate``, kept in the process per plate geometry: the one place that
    tells the kinds of texture apart."""
    if isinstance(plate.texture, Roughness):
        return ProfileSurface(plate)
    if isinstance(plate.texture, HeightMap):
        return MapSurface(plate)
    return FeatureSurface(plate)


@memoized("roughness profiles", maxsize=32)
def _profile_cached(
    ra: float, lc: float, seed: int, dx: float, length: float
) -> tuple[np.ndarray, np.ndarray]:
    n = round(length / dx) + 1
    x = np.linspace(-length / 2, length / 2, n)
    dx = x[1] - x[0]
    # White noise filtered by the square root of a Gaussian spectrum, on a grid twice as long
    # so that the circular FFT does not join the two ends of the profile.
    m = 2 * n
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal(m)
    k = 2 * np.pi * np.fft.rfftfreq(m, d=dx)
    # autocorrelation exp(-(x/lc)^2)  <->  PSD proportional to exp(-(k lc)^2 / 4)
    z = np.fft.irfft(np.fft.rfft(noise) * np.exp(-((k * lc) ** 2) / 8), n=m)[:n]
    z -= z.mean()
    z *= ra / np.mean(np.abs(z))
    x.setflags(write=False)
    z.setflags(write=False)
    return x, z


def profile_samples(texture: Roughness, length_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The sampled roughness profile ``(x, z)`` [m] of ``texture`` over a textured area
    ``length_m`` long, shape (n,) each, read-only; kept in the process by its parameters.

    Deterministic: the same parameters give the same bytes in any process (numpy's PCG64
    and pocketfft are deterministic on one platform)."""
    t = texture
    return _profile_cached(t.ra_m, t.corr_length_m, t.seed, t.resolution_m, length_m)


def samples_apart(params: dict) -> bool:
    """Whether plate parameters (:meth:`~.spec.Plate.params`) leave the surface's samples
    out: a height map's name them by their SHA-256, so the plate is built again from its file
    or a store's copy of them, not from the parameters alone."""
    texture = params.get("texture") if isinstance(params, dict) else None
    return isinstance(texture, dict) and texture.get("kind") == HeightMap.kind


def map_height(x: np.ndarray, y: np.ndarray, z: np.ndarray, pixel: float) -> np.ndarray:
    """Bilinear height of the map ``z`` (ny, nx) [m], sampled every ``pixel`` [m] and centred
    on the origin, at ``(x, y)`` (broadcast); NaN where a corner of the cell is NaN (no
    material). Points beyond the map take its edge cells' extrapolation: callers mask them.

    The arithmetic, in this order, is the compiled collider's (tested bit for bit): ``fx =
    (x + (nx - 1) pixel / 2) / pixel``, ``j = clip(floor(fx), 0, nx - 2)``, ``tx = fx - j``
    (so for y), then ``(1 - ty) ((1 - tx) z00 + tx z01) + ty ((1 - tx) z10 + tx z11)``.
    """
    ny, nx = z.shape
    fx = (x + (nx - 1) * pixel / 2) / pixel
    fy = (y + (ny - 1) * pixel / 2) / pixel
    j = np.clip(np.floor(fx), 0, nx - 2).astype(np.intp)
    i = np.clip(np.floor(fy), 0, ny - 2).astype(np.intp)
    tx, ty = fx - j, fy - i
    lower = (1 - tx) * z[i, j] + tx * z[i, j + 1]
    upper = (1 - tx) * z[i + 1, j] + tx * z[i + 1, j + 1]
    return (1 - ty) * lower + ty * upper
