"""Data sets of slides in a Zarr store: the layout, writing one slide at a time, lazy reading,
checks and export to plain numpy files.

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
import json
import math
import platform
import shutil
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import __version__
from ..errors import MissingDependencyError, StoreError
from ..hashing import content_hash
from ..records import Recording, TactileDataset

FORMAT = "sim_tactile.slides"
FORMAT_VERSION = 1
#: the columns of ``params``: as drawn for each slide (NaN for measured data)
PARAM_NAMES = ("speed_m_s", "force_n", "offset_y_m")
#: per-slide arrays written when the store is created (chunks of this many slides)
_INDEX_CHUNK = 65536


def _zarr():
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
        "zarr": _zarr().__version__,
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
    g.attrs.update(spec.attrs())


def create_store(path: str | Path, specs: dict[str, StoreSpec], root_attrs: dict) -> None:
    """Create the store at ``path`` (which must not exist) with a group per spec (key ``""``:
    the root itself). Built under a temporary name and renamed: a store either exists whole
    or not at all."""
    zarr = _zarr()
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
        return _check_slide(self.data, self.lengths, i, expected or int(self.checksum[i]))


def _check_slide(data, lengths, i: int, expected: int) -> str | None:
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


# ------------------------------------------------------------------------------- reading
def _open_root(path: str | Path, mode: str = "r"):
    zarr = _zarr()
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


def parts_of(path: str | Path) -> list[str]:
    """The part groups of a suite's store ([] for a store holding one data set)."""
    return list(_open_root(path).attrs.get("parts") or [])


class SlideStore:
    """A data set in a store, read lazily: the per-slide indices (labels, seeds, parameters)
    are loaded on open, the samples only when a slide is read; every read checks the slide's
    checksum. ``len(store)`` slides; ``store[i]`` is slide ``i``'s ``(T_i, N)`` samples;
    iterating yields ``(samples, label)`` pairs one slide at a time."""

    def __init__(self, group, path: Path) -> None:
        self.path = path
        self.group = group
        self.meta: dict = group.attrs.asdict()
        if self.meta.get("format") != FORMAT or "data" not in group:
            raise StoreError(f"{str(path)!r} holds no sim_tactile data set")
        self.labels: np.ndarray = group["labels"][:]
        self.lengths: np.ndarray = group["lengths"][:]
        self.slide_numbers: np.ndarray = group["slide"][:]
        self.seeds: np.ndarray = group["seed"][:]
        p = group["params"][:]
        self.params: dict[str, np.ndarray] = {k: p[:, j] for j, k in enumerate(PARAM_NAMES)}
        self.data = group["data"]  # the Zarr array itself: slicing reads only those chunks
        self._checksum = group["checksum"]
        self.class_names = tuple(self.meta["class_names"])
        self.channel_names = tuple(self.meta["channel_names"])
        self.rate_hz = float(self.meta["rate_hz"])
        self.units = str(self.meta["units"])
        pos = self.meta.get("taxel_positions")
        self.taxel_positions = None if pos is None else np.asarray(pos, dtype=np.float64)

    @property
    def config(self) -> dict:
        return self.meta["config"]

    @property
    def config_hash(self) -> str:
        return self.meta["config_hash"]

    @property
    def complete(self) -> bool:
        return bool(self.meta.get("complete")) or bool(self.checksums().all())

    def checksums(self) -> np.ndarray:
        return self._checksum[:]

    def __len__(self) -> int:
        return int(self.labels.shape[0])

    def _index(self, i: int) -> int:
        n = len(self)
        if not isinstance(i, int | np.integer) or not -n <= i < n:
            raise IndexError(f"slide index {i} out of range; valid: [{-n}, {n - 1}]")
        return int(i) % n

    def __getitem__(self, i: int) -> np.ndarray:
        i = self._index(i)
        expected = int(self._checksum[i])
        bad = _check_slide(self.data, self.lengths, i, expected)
        if bad:
            raise StoreError(
                f"slide {i} of {str(self.path)!r}: {bad}; 'sim-tactile generate ... --resume' "
                f"writes it again"
            )
        return np.asarray(self.data[i, : int(self.lengths[i])])

    def __iter__(self) -> Iterator[tuple[np.ndarray, int]]:
        for i in range(len(self)):
            yield self[i], int(self.labels[i])

    def batches(self, size: int = 256) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """``(samples (b, T, N), labels (b,))`` for consecutive slides, ``size`` at a time
        (one read per batch; the slides must have one length)."""
        sums = self.checksums()
        for a in range(0, len(self), size):
            b = min(a + size, len(self))
            x = np.asarray(self.data[a:b])
            for k in range(a, b):
                if int(sums[k]) == 0 or slide_digest(x[k - a, : self.lengths[k]]) != sums[k]:
                    self[k]  # raises with the reason
            if (self.lengths[a:b] != x.shape[1]).any():
                raise StoreError("batches needs slides of one length; index slides instead")
            yield x, self.labels[a:b].copy()

    def verify(self) -> list[tuple[int, str]]:
        """``(slide, reason)`` of every slide that is absent or fails its checksum."""
        sums = self.checksums()
        out = []
        for i in range(len(self)):
            bad = _check_slide(self.data, self.lengths, i, int(sums[i]))
            if bad:
                out.append((i, bad))
        return out

    def recording(self, i: int) -> Recording:
        """Slide ``i`` as a :class:`Recording` (times, taxels, units, per-slide metadata)."""
        i = self._index(i)
        x = self[i]
        pos = self.taxel_positions
        if pos is None:
            pos = np.full((x.shape[1], 3), np.nan)
        meta = {
            "rate_hz": self.rate_hz,
            "class": self.class_names[int(self.labels[i])],
            "label": int(self.labels[i]),
            "slide": int(self.slide_numbers[i]),
            "seed": int(self.seeds[i]),
            "params": {k: _num(v[i]) for k, v in self.params.items()},
            "store": str(self.path),
            "config_hash": self.config_hash,
            "channel_names": list(self.channel_names),
        }
        return Recording(x, (np.arange(x.shape[0]) + 0.5) / self.rate_hz, pos, self.units, meta)

    def to_tactile(self) -> TactileDataset:
        """The whole data set in memory, as the classifiers and protocols take it."""
        if len(set(self.lengths.tolist())) != 1:
            raise StoreError(
                f"{str(self.path)!r}: slides of several lengths ({sorted(set(self.lengths))}); "
                "a TactileDataset needs one length: crop them first"
            )
        missing = int((self.checksums() == 0).sum())
        if missing:
            raise StoreError(
                f"{str(self.path)!r} is incomplete: {missing} of {len(self)} slides are not "
                "written; finish it with 'sim-tactile generate ... --resume'"
            )
        x = np.concatenate([b for b, _ in self.batches()]) if len(self) else None
        meta = dict(self.meta.get("dataset_meta") or {})
        meta.update(
            store=str(self.path),
            config_hash=self.config_hash,
            simulate_s=0.0,
            slides_simulated=0,
            slides_cached=len(self),
            sim_warnings=[f"{w} (x{c})" for w, c in (self.meta.get("sim_warnings") or {}).items()],
        )
        return TactileDataset(
            x,
            self.labels,
            self.rate_hz,
            self.channel_names,
            self.class_names,
            self.taxel_positions,
            self.units,
            meta,
        )

    def describe(self) -> dict:
        return {
            "path": str(self.path),
            "name": self.meta.get("name"),
            "slides": len(self),
            "written": int((self.checksums() != 0).sum()),
            "config_hash": self.config_hash,
            "classes": list(self.class_names),
            "channels": len(self.channel_names),
            "n_time": int(self.meta["n_time"]),
            "rate_hz": self.rate_hz,
            "units": self.units,
        }


def _num(v) -> float | None:
    v = float(v)
    return v if math.isfinite(v) else None


def open_store(path: str | Path, part: str | None = None) -> SlideStore:
    """Open a data set written by ``sim-tactile generate`` (or :func:`from_tactile`) for
    reading. A suite's store (e.g. ``textures20-v1``) holds one data set per part: name it
    with ``part`` (or open ``path/part``)."""
    path = Path(path)
    if not path.exists():
        raise StoreError(f"data set {str(path)!r} does not exist")
    root = _open_root(path)
    parts = list(root.attrs.get("parts") or [])
    if part is None:
        if parts:
            raise StoreError(
                f"{str(path)!r} holds the parts of {root.attrs.get('suite')}: open one with "
                f"part=... ({', '.join(parts)})"
            )
        return SlideStore(root, path)
    if part not in parts:
        raise StoreError(
            f"{str(path)!r} has no part {part!r}; valid: {', '.join(parts) or '(none)'}"
        )
    return SlideStore(root[part], path / part)


# ------------------------------------------------------------------------------- from data
def spec_from_tactile(ds: TactileDataset, name: str, config: dict | None = None) -> StoreSpec:
    """The store layout of a :class:`TactileDataset` (e.g. real recordings), so measured and
    simulated data sets take the same form on disk."""
    n = ds.n_samples
    counts: dict[int, int] = {}
    slide = np.empty(n, np.int64)
    for i, y in enumerate(ds.labels.tolist()):
        slide[i] = counts.get(y, 0)
        counts[y] = slide[i] + 1
    meta = json.loads(json.dumps(ds.meta, default=str))
    cfg = config or {"kind": "recorded", "name": name, "meta": meta}
    cfg = dict(cfg, shape=list(ds.data.shape), data_digest=_dataset_digest(ds))
    return StoreSpec(
        name=name,
        config=cfg,
        labels=ds.labels,
        slide=slide,
        seeds=np.zeros(n, np.uint64),
        params=np.full((n, len(PARAM_NAMES)), np.nan),
        lengths=np.full(n, ds.n_time, np.int64),
        channel_names=ds.channel_names,
        class_names=ds.class_names,
        rate_hz=ds.rate_hz,
        units=ds.units,
        taxel_positions=ds.taxel_positions,
        dataset_meta=meta,
    )


def _dataset_digest(ds: TactileDataset) -> str:
    h = hashlib.sha256(np.ascontiguousarray(ds.data).tobytes())
    h.update(ds.labels.tobytes())
    return h.hexdigest()[:16]


def from_tactile(ds: TactileDataset, path: str | Path, *, name: str = "dataset") -> SlideStore:
    """Write a :class:`TactileDataset` (e.g. :func:`~sim_tactile.datasets.load_biotac`) into a
    new store at ``path`` and open it."""
    path = Path(path)
    if path.exists():
        raise StoreError(f"{str(path)!r} exists; give a new path")
    spec = spec_from_tactile(ds, name)
    create_store(path, {"": spec}, {})
    root = _zarr().open_group(str(path), mode="r+")
    w = SlideWriter(root)
    for i in range(ds.n_samples):
        w.write(i, ds.data[i])
    root.attrs.update({"complete": True})
    return open_store(path)


# ------------------------------------------------------------------------------- export
def export(path: str | Path, out: str | Path, *, part: str | None = None) -> dict:
    """Write a complete data set as plain numpy files into the folder ``out``: ``data.npy``
    (slides, T, N) float32 (NaN past each slide's length), ``labels.npy``, ``lengths.npy``,
    ``slide.npy``, ``seed.npy``, ``params.npy`` (slides, 3), ``taxel_positions.npy`` (if
    known) and ``meta.json`` (configuration, names, versions). A suite's store exports each
    part into ``out/<part>/``. Slides are copied a batch at a time: memory stays flat."""
    path, out = Path(path), Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise StoreError(f"--out {str(out)!r} exists and is not an empty folder")
    parts = parts_of(path)
    if parts and part is None:
        files = {p: export(path, out / p, part=p) for p in parts}
        return {"out": str(out), "parts": files, "slides": sum(f["slides"] for f in files.values())}
    st = open_store(path, part)
    missing = int((st.checksums() == 0).sum())
    if missing:
        raise StoreError(
            f"{str(st.path)!r} is incomplete ({missing} of {len(st)} slides missing); finish it "
            "with 'sim-tactile generate ... --resume' before exporting"
        )
    out.mkdir(parents=True, exist_ok=True)
    n, t, c = st.data.shape
    mm = np.lib.format.open_memmap(out / "data.npy", mode="w+", dtype=np.float32, shape=(n, t, c))
    sums = st.checksums()
    for a in range(0, n, 256):
        b = min(a + 256, n)
        x = np.asarray(st.data[a:b])
        for k in range(a, b):
            if slide_digest(x[k - a, : st.lengths[k]]) != sums[k]:
                st[k]  # raises with the reason
        mm[a:b] = x
    mm.flush()
    del mm
    files = {"data": "data.npy"}
    arrays = {
        "labels": st.labels,
        "lengths": st.lengths,
        "slide": st.slide_numbers,
        "seed": st.seeds,
        "params": np.stack([st.params[k] for k in PARAM_NAMES], axis=1),
    }
    if st.taxel_positions is not None:
        arrays["taxel_positions"] = st.taxel_positions
    for k, arr in arrays.items():
        np.save(out / f"{k}.npy", arr, allow_pickle=False)
        files[k] = f"{k}.npy"
    (out / "meta.json").write_text(json.dumps(st.meta, indent=1, sort_keys=True))
    files["meta"] = "meta.json"
    return {"out": str(out), "slides": n, "files": files}
