"""Data sets of slides in a Zarr store: the layout, and writing one slide at a time
(:mod:`.reader` reads them lazily, :mod:`.export` writes recordings in and plain files out,
:mod:`.integrity` checks what is read, :mod:`.fs` keeps one writer at a time).

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
package versions, class / channel names, rate, units, taxel positions, ``complete``, and
the digests that every reader checks (:mod:`.integrity`: of the attributes themselves, of
each array's ``zarr.json`` and of the index arrays' values).

Why a padded array with ``lengths`` rather than a group per slide: one array per quantity
keeps the store to a handful of metadata files whatever its size (a group per slide would be
three files of metadata per slide, listed on every open), reads any range of slides in one
call, and exports to one stacked ``.npy``. Every slide of a configuration has the same window
(the protocol fixes ``duration_s``), so in practice nothing is padded; ``lengths`` keeps the
layout valid for data sets whose slides differ.

A slide is complete when its ``checksum`` chunk exists: the writer writes the data chunk and
then the checksum (each chunk file written atomically, as :mod:`.chunks` says), so a run
killed at any point leaves every slide either whole or absent. The checksum (the first 8
bytes of the SHA-256 of the slide's samples, its index and the configuration's hash) also
finds a chunk that was later truncated, altered or moved: every read verifies it.

A store is made under a fresh temporary name beside it and renamed when whole, by a writer
holding the store's lock (:class:`~.lock.StoreLock`).
"""

from __future__ import annotations

import platform
import shutil
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from glob import escape
from pathlib import Path

import numpy as np

from .. import __version__
from ..errors import ConfigError, MissingDependencyError, StoreError
from .chunks import ChunkFile
from .fs import fs_errors, take, temp_name
from .integrity import (
    FORMAT,
    FORMAT_VERSION,
    INDEX_CHUNK,
    INDEX_DTYPES,
    MAX_CHANNELS,
    MAX_SLIDE_VALUES,
    MAX_SLIDES,
    MAX_TIME,
    PARAM_NAMES,
    REMAKE_HINT,
    check_arrays,
    check_data_attrs,
    check_files,
    check_root_attrs,
    chunk_files,
    config_hash,
    file_digest,
    index_values,
    reading,
    sealed,
    slide_digest,
    values_digest,
)

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "PARAM_NAMES",
    "DataGroup",
    "SlideWriter",
    "StoreSpec",
    "check_fits",
    "check_slide",
    "config_hash",
    "create_store",
    "open_data",
    "open_root",
    "plate_maps",
    "read_checksums",
    "set_attrs",
    "slide_digest",
]

#: How the samples array keys its chunks, one a slide: Zarr's default key encoding with ``.``
#: between the chunk's indices (``c.12.0.0``), so every slide's chunk lies in the array's own
#: folder. With ``/`` (Zarr's default) each slide made two folders (``c/12/0/``), and on this
#: project's CI host (ext4 on a virtual disk) a folder cost about 0.9 ms of system CPU, as a
#: file does: a third of what a small sensor's slide costs to simulate. The other arrays keep
#: Zarr's default (their chunks share one folder already). A store made with either is read
#: and appended to alike: its arrays' metadata says how they are keyed.
SAMPLE_KEYS = {"name": "default", "configuration": {"separator": "."}}


def zarr_module():
    try:
        import zarr
    except ImportError as exc:  # pragma: no cover - zarr is a runtime dependency
        raise MissingDependencyError("zarr is needed for data sets: pip install zarr") from exc
    return zarr


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

    def index(self) -> dict[str, np.ndarray]:
        """The index arrays as the store holds them (name -> values)."""
        cols = (self.lengths, self.labels, self.slide, self.seeds, self.params)
        pairs = zip(INDEX_DTYPES.items(), cols, strict=True)
        return {k: np.asarray(v).astype(t) for (k, t), v in pairs}

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


def _create_group(root, folder: Path, path: str, spec: StoreSpec) -> None:
    g = root.create_group(path) if path else root
    n, t, c = spec.n_slides, spec.n_time, len(spec.channel_names)
    idx = (min(n, INDEX_CHUNK),)
    # a slide's samples are one chunk, keyed ``c.<slide>.0.0`` in the array's own folder: the
    # default key (``c/<slide>/0/0``) made two folders a slide, which cost as much as the
    # slide's two files on some file systems (see SAMPLE_KEYS)
    g.create_array(
        "data",
        shape=(n, t, c),
        dtype="float32",
        chunks=(1, t, c),
        fill_value=np.nan,
        chunk_key_encoding=SAMPLE_KEYS,
    )
    # 8 bytes a chunk: compressing them would only cost time
    g.create_array(
        "checksum", shape=(n,), dtype="uint64", chunks=(1,), fill_value=0, compressors=None
    )
    values = spec.index()
    for name, x in values.items():
        chunks = (idx[0], len(PARAM_NAMES)) if x.ndim == 2 else idx
        fill = np.nan if x.dtype.kind == "f" else 0
        g.create_array(name, shape=x.shape, dtype=x.dtype, chunks=chunks, fill_value=fill)[...] = x
    names = ["data", "checksum", *values]
    if spec.plate_maps:
        maps = g.create_group("plate_maps")
        names.append("plate_maps")
        for sha, z in sorted(spec.plate_maps.items()):
            z = np.asarray(z, dtype=np.float64)
            maps.create_array(sha, shape=z.shape, dtype="float64", fill_value=np.nan)[...] = z
            values[f"plate_maps/{sha}"] = z
            names.append(f"plate_maps/{sha}")
    here = folder / path if path else folder
    files = {f"{k}/zarr.json": file_digest(here / k / "zarr.json") for k in names}
    for k in INDEX_DTYPES:
        files.update(chunk_files(here, k))
    integrity = {"files": files, "values": {k: values_digest(x) for k, x in values.items()}}
    g.attrs.put(sealed({**spec.attrs(), "integrity": integrity}))


def check_fits(spec: StoreSpec, where: str) -> None:
    """Refuse, before anything is created, a data set that a store cannot hold: the bounds
    every reader checks (:mod:`.integrity`: slides, samples, channels, samples x channels of
    one slide, the chunk of one slide), each named with its limit and the configuration's
    values; then the attributes the store would hold, checked as a reader checks them. A
    ConfigError (``where``: the data set, for messages)."""
    n, t, c = spec.n_slides, spec.n_time, len(spec.channel_names)
    window = f"{t / spec.rate_hz:.4g} s at {spec.rate_hz:g} Hz"
    shorter = "shorten protocol.duration_s or lower protocol.rate_hz"
    limits = (
        (n, MAX_SLIDES, "slides", f"{n:,} slides", "fewer plates or slides_per_plate"),
        (t, MAX_TIME, "samples a slide", f"{t:,} samples a slide ({window})", shorter),
        (c, MAX_CHANNELS, "channels", f"{c:,} channels", "a sensor with fewer taxels"),
        (len(spec.class_names), MAX_SLIDES, "classes", f"{len(spec.class_names):,} classes", ""),
        (
            t * c,
            MAX_SLIDE_VALUES,
            f"values a slide ({MAX_SLIDE_VALUES * 4 / 1e6:,.0f} MB)",
            f"{t:,} samples ({window}) x {c} channels = {t * c:,} values a slide",
            shorter,
        ),
    )
    for value, limit, unit, what, remedy in limits:
        if value > limit:
            raise ConfigError(
                f"{where}: {what}; a store holds at most {limit:,} {unit}"
                + (f": {remedy}" if remedy else "")
                + "; nothing was created"
            )
    names = ("data", "checksum", *INDEX_DTYPES)
    files = {f"{k}/zarr.json": "" for k in names}
    files.update({f"lengths/c/{k}": "" for k in range(-(-n // INDEX_CHUNK))})
    integrity = {"files": files, "values": dict.fromkeys(INDEX_DTYPES, "")}
    try:
        check_data_attrs(sealed({**spec.attrs(), "integrity": integrity}), where)
    except StoreError as exc:  # what a reader would refuse: this configuration's fault
        what = str(exc).split(": the store's metadata is damaged")[0]
        raise ConfigError(f"{what}: a store cannot hold it; nothing was created") from None


def create_store(path: str | Path, specs: dict[str, StoreSpec], root_attrs: dict) -> None:
    """Create the store at ``path`` (which must not exist) with a group per spec (key ``""``:
    the root itself). Built under a fresh temporary name beside it and renamed: a store
    either exists whole or not at all, and is refused if ``path`` appeared meanwhile. The
    caller holds the store's lock (:class:`~.lock.StoreLock`): any temporary folder of this
    store still there is a dead writer's, and is removed."""
    zarr = zarr_module()
    path = Path(path)
    for name, spec in specs.items():  # before anything is created
        check_fits(spec, f"{path}/{name}" if name else f"{path}")
    with fs_errors(path):
        path.parent.mkdir(parents=True, exist_ok=True)
        for stale in path.parent.glob(f".{escape(path.name)}.*.creating"):
            shutil.rmtree(stale, ignore_errors=True)
    tmp = temp_name(path, "creating")
    try:
        with fs_errors(path):
            root = zarr.open_group(str(tmp), mode="w-")
            for name, spec in specs.items():
                _create_group(root, tmp, name, spec)
            if "" not in specs:
                base = {"format": FORMAT, "format_version": FORMAT_VERSION}
                root.attrs.put(sealed({**base, **root_attrs}))
            else:
                root.attrs.put(sealed({**root.attrs.asdict(), **root_attrs}))
            take(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def set_attrs(group, updates: dict, where: str | Path) -> None:
    """Update a group's attributes and their digest in one atomic write of its zarr.json."""
    with fs_errors(where):
        group.attrs.put(sealed({**group.attrs.asdict(), **updates}))


def read_checksums(arr, where: str) -> tuple[np.ndarray, dict[int, str]]:
    """The ``checksum`` array's values (0: absent) and ``{slide: damage}`` for chunks that
    cannot be read (their value reads as 0)."""
    try:
        return np.asarray(arr[:], dtype=np.uint64), {}
    except Exception:  # a damaged chunk: read them one at a time to say which
        pass
    n = arr.shape[0]
    out, bad = np.zeros(n, np.uint64), {}
    for i in range(n):
        try:
            out[i] = arr[i]
        except Exception as exc:
            bad[i] = f"its checksum chunk cannot be read ({type(exc).__name__})"
    return out, bad


class SlideWriter:
    """Writes slides into a data set's group (one process writes; workers only simulate).
    ``where``: the store's path as the user named it, ``hint``: what to do when the file
    system refuses a write (for messages), ``guard``: called before each write, raises to
    stop it (``generate``'s check that the store is still at ``where``)."""

    def __init__(
        self,
        group,
        where: str | Path,
        lengths: np.ndarray | None = None,
        hint: str = "",
        guard: Callable[[], None] | None = None,
    ) -> None:
        self.group = group
        self.where = str(where)
        self.hint = hint
        self.guard = guard
        self.key = str(group.attrs["config_hash"])
        self.data = group["data"]
        self.checksum = group["checksum"]
        self.lengths = group["lengths"][:] if lengths is None else lengths
        self.n_time, self.n_channels = self.data.shape[1:]
        #: the chunks' files as Zarr writes them, without its asynchronous path (:mod:`.chunks`)
        self._files = (ChunkFile.for_array(self.data), ChunkFile.for_array(self.checksum))

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
        if self.guard is not None:
            self.guard()
        mark = np.uint64(slide_digest(x, i, self.key))
        data_file, mark_file = self._files
        with fs_errors(self.where, self.hint):
            if data_file is None or want[0] == 0:  # (a row of the fill value alone: Zarr's)
                self.data[i] = row
            else:
                data_file.write(i, row)  # the data chunk first...
            if mark_file is None or mark == 0:
                self.checksum[i] = mark
            else:
                mark_file.write(i, mark)  # ...then its mark

    def clear(self, i: int) -> None:
        """Mark slide ``i`` absent (before it is written again)."""
        if self.guard is not None:
            self.guard()
        with fs_errors(self.where, self.hint):
            self.checksum[i] = np.uint64(0)

    def done(self) -> tuple[np.ndarray, dict[int, str]]:
        """Boolean mask of the slides whose checksum is written, and the slides whose
        checksum chunk cannot be read (``{slide: damage}``; not in the mask)."""
        sums, bad = read_checksums(self.checksum, self.where)
        return sums != 0, bad

    def check(self, i: int) -> str | None:
        """None if slide ``i`` reads back with its checksum, else why not."""
        try:
            expected = int(self.checksum[i])
        except Exception as exc:
            return f"its checksum chunk cannot be read ({type(exc).__name__})"
        return check_slide(self.data, self.lengths, i, expected, self.key)


def check_slide(data, lengths, i: int, expected: int, key: str) -> str | None:
    """None if slide ``i`` of ``data`` matches ``expected`` (its checksum), else why not."""
    if expected == 0:
        return "not written"
    try:
        row = np.asarray(data[i])
    except Exception as exc:  # a truncated or garbled chunk fails to decode
        return f"chunk unreadable ({type(exc).__name__}: {' '.join(str(exc).split())[:120]})"
    bad = rows_damage(row[None], lengths[i : i + 1], [expected], i, key)
    return None if bad is None else bad[1]


def rows_damage(
    rows: np.ndarray, lengths, expected, start: int, key: str
) -> tuple[int, str] | None:
    """None if every row of ``rows`` (slides ``start...``) matches its checksum in
    ``expected``, else ``(slide, why not)`` of the first that does not."""
    for k in range(rows.shape[0]):
        want = int(expected[k])
        if want == 0:
            return start + k, "not written"
        if slide_digest(rows[k, : int(lengths[k])], start + k, key) != want:
            return start + k, "checksum mismatch (the chunk was altered, truncated or moved)"
    return None


def open_root(path: str | Path, mode: str = "r"):
    """The store's root group at ``path``, checked to be a sim_tactile data set of this
    format version whose attributes match their digest."""
    zarr = zarr_module()
    path = Path(path)
    if not path.is_dir() or not (path / "zarr.json").is_file():
        raise StoreError(f"{str(path)!r} is not a Zarr store (no zarr.json)")
    where = repr(str(path))
    with reading(where, "its zarr.json"):
        root = zarr.open_group(str(path), mode=mode)
        attrs = root.attrs.asdict()
    check_root_attrs(attrs, where)
    return root


@dataclass
class DataGroup:
    """A data set's group, checked: attributes, arrays, index values (and what of those is
    damaged: ``{array: damage}``)."""

    group: object
    attrs: dict
    arrays: dict
    index: dict
    damage: dict


def open_data(group, folder: Path, where: str) -> DataGroup:
    """Check a data set's group (in the folder ``folder``): its attributes against their
    digest, types and ranges, its arrays' metadata files and layout, and its index arrays'
    values (damage there is reported in ``damage``, not raised: ``--resume`` writes them
    again)."""
    with reading(where, "its zarr.json"):
        attrs = group.attrs.asdict()
    if attrs.get("format") != FORMAT:
        raise StoreError(f"{where} holds no sim_tactile data set")
    check_data_attrs(attrs, where)
    damage = check_files(folder, attrs, where)
    arrays = check_arrays(group, attrs, where)
    index, bad_values = index_values(arrays, attrs, where)
    return DataGroup(group, attrs, arrays, index, {**damage, **bad_values})


def plate_maps(group, attrs: dict | None = None, where: str = "the store") -> dict[str, np.ndarray]:
    """The height-map plates' samples a data set's group holds, by SHA-256, each checked
    against the digest the store recorded."""
    with reading(where, "its plate maps"):
        if "plate_maps" not in group:
            return {}
        maps = group["plate_maps"]
        out = {name: maps[name][...] for name in sorted(maps.array_keys())}
    digests = (attrs or group.attrs.asdict())["integrity"]["values"]
    for name, z in out.items():
        if digests.get(f"plate_maps/{name}") != values_digest(z):
            raise StoreError(
                f"{where}: the plate map {name} does not match its digest (altered or "
                f"damaged); {REMAKE_HINT}"
            )
    return out
