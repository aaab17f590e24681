"""Data sets of slides in a Zarr store: the layout, and writing one slide at a time
(:mod:`.reader` reads them lazily, :mod:`.export` writes recordings in and plain files out).

Layout of one data set (a Zarr v3 group: the store's root, or one group per part of a suite
such as ``textures20-v1``)::

    data       float32 (slides, T, N)  chunks (1, T, N): one chunk per slide, fill NaN
    lengths    int64   (slides,)       samples of each slide (<= T; the rest of its row is NaN)
    checksum   uint64  (slides,)       chunks (1,): a slide's digest, written last (0 = absent)
    labels     int64   (slides,)       class index (``class_names``)
    slide      int64   (slides,)       the slide's number within its class
    seed       uint64  (slides,)       the seed the slide was simulated with
    params     float64 (slides, 3)     the drawn speed [m/s], force [N] and offset [m]

and as attributes the whole configuration, its hash, the version of the simulating code,
package versions, class / channel names, rate, units, taxel positions and ``complete``.

Why a padded array with ``lengths`` rather than a group per slide: one array per quantity
keeps the store to a handful of metadata files whatever its size (a group per slide would be
three files of metadata per slide, listed on every open), reads any range of slides in one
call, and exports to one stacked ``.npy``. Every slide of a configuration has the same window
(the protocol fixes ``duration_s``), so in practice nothing is padded; ``lengths`` keeps the
layout valid for data sets whose slides differ.

A slide is complete when its ``checksum`` chunk exists: the writer writes the data chunk and
then the checksum (each chunk file is written atomically by Zarr's local store), so a run
killed at any point leaves every slide either whole or absent. The checksum (the first 8
bytes of the SHA-256 of the slide's samples) also finds a chunk that was later truncated or
altered: every read verifies it.
"""

from __future__ import annotations

import hashlib
import platform
import shutil
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import __version__
from ..errors import MissingDependencyError, StoreError
from ..hashing import content_hash

FORMAT = "sim_tactile.slides"
FORMAT_VERSION = 1
#: the columns of ``params``: as drawn for each slide (NaN for measured data)
PARAM_NAMES = ("speed_m_s", "force_n", "offset_y_m")
#: per-slide arrays written when the store is created (chunks of this many slides)
_INDEX_CHUNK = 65536


def zarr_module():
    try:
        import zarr
    except ImportError as exc:  # pragma: no cover - zarr is a runtime dependency
        raise MissingDependencyError("zarr is needed for data sets: pip install zarr") from exc
    return zarr


def config_hash(config: dict) -> str:
    """The content hash (16 hex digits) of a configuration."""
    return content_hash(config, 16)


def slide_digest(x: np.ndarray) -> int:
    """The checksum of one slide's samples: never 0 (0 marks an absent slide)."""
    x = np.ascontiguousarray(x, dtype="<f4")
    h = hashlib.sha256(repr(x.shape).encode())
    h.update(x.tobytes())
    return int.from_bytes(h.digest()[:8], "little") or 1


def versions() -> dict:
    """Versions of the packages that make and read the data."""
    import numcodecs

    out = {
        "sim_tactile": __version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "zarr": zarr_module().__version__,
        "numcodecs": numcodecs.__version__,
    }
    mj = sys.modules.get("mujoco")
    if mj is not None:
        out["mujoco"] = mj.__version__
    return out


@dataclass
class StoreSpec:
    """Everything a data set's group holds before any slide is written."""

    name: str
    config: dict
    labels: np.ndarray
    slide: np.ndarray
    seeds: np.ndarray
    params: np.ndarray
    lengths: np.ndarray
    channel_names: tuple[str, ...]
    class_names: tuple[str, ...]
    rate_hz: float
    units: str
    taxel_positions: np.ndarray | None = None
    dataset_meta: dict = field(default_factory=dict)
    code_version: str | None = None
    #: the samples of its height-map plates by their SHA-256 (a user's part or height map:
    #: the store holds it whole, so the plates can be re-created without the files)
    plate_maps: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n_slides(self) -> int:
        return int(self.labels.shape[0])

    @property
    def n_time(self) -> int:
        return int(self.lengths.max())

    @property
    def hash(self) -> str:
        return config_hash(self.config)

    def attrs(self) -> dict:
        pos = self.taxel_positions
        return {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "name": self.name,
            "task": self.config.get("task"),
            "config": self.config,
            "config_hash": self.hash,
            "code_version": self.code_version,
            "versions": versions(),
            "n_slides": self.n_slides,
            "n_time": self.n_time,
            "class_names": list(self.class_names),
            "channel_names": list(self.channel_names),
            "rate_hz": float(self.rate_hz),
            "units": self.units,
            "taxel_positions": None if pos is None else np.asarray(pos).tolist(),
            "param_names": list(PARAM_NAMES),
            "dataset_meta": self.dataset_meta,
            "complete": False,
            "sim_warnings": {},
        }


def _create_group(root, path: str, spec: StoreSpec) -> None:
    g = root.create_group(path) if path else root
    n, t, c = spec.n_slides, spec.n_time, len(spec.channel_names)
    idx = (min(n, _INDEX_CHUNK),)

    def arr(name, values, dtype, chunks=idx, fill=0):
        a = g.create_array(name, shape=values.shape, dtype=dtype, chunks=chunks, fill_value=fill)
        a[...] = values
        return a

    g.create_array("data", shape=(n, t, c), dtype="float32", chunks=(1, t, c), fill_value=np.nan)
    # 8 bytes a chunk: compressing them would only cost time
    g.create_array(
        "checksum", shape=(n,), dtype="uint64", chunks=(1,), fill_value=0, compressors=None
    )
    arr("lengths", spec.lengths.astype(np.int64), "int64")
    arr("labels", spec.labels.astype(np.int64), "int64")
    arr("slide", spec.slide.astype(np.int64), "int64")
    arr("seed", spec.seeds.astype(np.uint64), "uint64")
    arr("params", spec.params.astype(np.float64), "float64", (idx[0], len(PARAM_NAMES)), np.nan)
    if spec.plate_maps:
        maps = g.create_group("plate_maps")
        for sha, z in sorted(spec.plate_maps.items()):
            a = maps.create_array(sha, shape=z.shape, dtype="float64", fill_value=np.nan)
            a[...] = z
    g.attrs.update(spec.attrs())


def create_store(path: str | Path, specs: dict[str, StoreSpec], root_attrs: dict) -> None:
    """Create the store at ``path`` (which must not exist) with a group per spec (key ``""``:
    the root itself). Built under a temporary name and renamed: a store either exists whole
    or not at all."""
    zarr = zarr_module()
    path = Path(path)
    tmp = path.with_name(f".{path.name}.creating")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.parent.mkdir(parents=True, exist_ok=True)
    root = zarr.open_group(str(tmp), mode="w")
    for name, spec in specs.items():
        _create_group(root, name, spec)
    if "" not in specs:
        root.attrs.update({"format": FORMAT, "format_version": FORMAT_VERSION, **root_attrs})
    else:
        root.attrs.update(root_attrs)
    tmp.rename(path)


class SlideWriter:
    """Writes slides into a data set's group (one process writes; workers only simulate)."""

    def __init__(self, group) -> None:
        self.group = group
        self.data = group["data"]
        self.checksum = group["checksum"]
        self.lengths = group["lengths"][:]
        self.n_time, self.n_channels = self.data.shape[1:]

    def write(self, i: int, x: np.ndarray) -> None:
        x = np.asarray(x)
        want = (int(self.lengths[i]), self.n_channels)
        if x.shape != want or x.dtype != np.float32:
            raise StoreError(
                f"slide {i} has shape {x.shape} {x.dtype}; the store expects {want} float32"
            )
        if not np.isfinite(x).all():
            raise StoreError(f"slide {i} holds non-finite samples; not written")
        row = x
        if want[0] < self.n_time:  # pad a shorter slide with the fill value
            row = np.full((self.n_time, self.n_channels), np.nan, np.float32)
            row[: want[0]] = x
        self.data[i] = row  # the data chunk first...
        self.checksum[i] = np.uint64(slide_digest(x))  # ...then the mark that it is whole

    def clear(self, i: int) -> None:
        """Mark slide ``i`` absent (before it is written again)."""
        self.checksum[i] = np.uint64(0)

    def done(self) -> np.ndarray:
        """Boolean mask of the slides whose checksum is written."""
        return self.checksum[:] != 0

    def check(self, i: int, expected: int | None = None) -> str | None:
        """None if slide ``i`` reads back with its checksum, else why not."""
        return check_slide(self.data, self.lengths, i, expected or int(self.checksum[i]))


def check_slide(data, lengths, i: int, expected: int) -> str | None:
    if expected == 0:
        return "not written"
    try:
        row = np.asarray(data[i])
    except Exception as exc:  # a truncated or garbled chunk fails to decode
        return f"chunk unreadable ({type(exc).__name__}: {str(exc)[:120]})"
    x = row[: int(lengths[i])]
    if slide_digest(x) != expected:
        return "checksum mismatch (the chunk was altered or truncated)"
    return None


def open_root(path: str | Path, mode: str = "r"):
    """The store's root group at ``path``, checked to be a sim_tactile data set of this
    format version."""
    zarr = zarr_module()
    path = Path(path)
    if not (path / "zarr.json").is_file():
        raise StoreError(f"{str(path)!r} is not a Zarr store (no zarr.json)")
    root = zarr.open_group(str(path), mode=mode)
    if root.attrs.get("format") != FORMAT:
        raise StoreError(f"{str(path)!r} is a Zarr store but not a sim_tactile data set")
    v = root.attrs.get("format_version")
    if v != FORMAT_VERSION:
        raise StoreError(f"{str(path)!r} has format version {v}; this code reads {FORMAT_VERSION}")
    return root


def plate_maps(group) -> dict[str, np.ndarray]:
    """The height-map plates' samples a data set's group holds, by SHA-256."""
    if "plate_maps" not in group:
        return {}
    maps = group["plate_maps"]
    return {name: maps[name][...] for name in sorted(maps.array_keys())}
