"""Data sets from recordings and to plain files: :func:`from_tactile` writes any
:class:`~sim_tactile.records.TactileDataset` (the real recordings) in a store's form,
:func:`export` writes a store as plain files in one of :data:`FORMATS`.

An export is built in a temporary folder beside ``--out`` and renamed when whole: a failure
(a damaged slide, a full disk, a read-only folder) leaves nothing behind, and the folder of a
killed export is removed by the next export to the same place. A new format is
one function ``(SlideStore, folder) -> {kind: file name}`` added to :data:`FORMATS`.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import ConfigError, StoreError
from ..hashing import array_digest
from ..records import TactileDataset
from .fs import building
from .integrity import DIGEST_ATTR
from .lock import StoreLock
from .reader import SlideStore, open_store, parts_of
from .store import PARAM_NAMES, SlideWriter, StoreSpec, create_store, set_attrs, zarr_module

#: attributes that check the store itself: not part of an export's metadata
_STORE_ONLY = ("integrity", DIGEST_ATTR)


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
    return array_digest(ds.data, ds.labels, header=False)[:16]


def from_tactile(ds: TactileDataset, path: str | Path, *, name: str = "dataset") -> SlideStore:
    """Write a :class:`TactileDataset` (e.g. :func:`~sim_tactile.datasets.load_biotac`) into a
    new store at ``path`` and open it. A failure part-way removes the store it began."""
    path = Path(path)
    if path.exists():
        raise StoreError(f"{str(path)!r} exists; give a new path")
    spec = spec_from_tactile(ds, name)
    with StoreLock(path):
        if path.exists():
            raise StoreError(f"{str(path)!r} exists; give a new path")
        create_store(path, {"": spec}, {})
        try:
            root = zarr_module().open_group(str(path), mode="r+")
            w = SlideWriter(root, path)
            for i in range(ds.n_samples):
                w.write(i, ds.data[i])
            set_attrs(root, {"complete": True}, path)
        except BaseException:
            shutil.rmtree(path, ignore_errors=True)
            raise
    return open_store(path)


def write_numpy(st: SlideStore, folder: Path) -> dict[str, str]:
    """A data set as ``.npy`` files and JSON in ``folder``: ``data.npy`` (slides, T, N)
    float32 (NaN past each slide's length), ``labels.npy``, ``lengths.npy``, ``slide.npy``,
    ``seed.npy``, ``params.npy`` (slides, 3), ``taxel_positions.npy`` (if known) and
    ``meta.json`` (configuration, names, versions). Slides are copied a batch at a time,
    each checked against its checksum: memory stays flat."""
    header = {"descr": "<f4", "fortran_order": False, "shape": tuple(st.data.shape)}
    with open(folder / "data.npy", "wb") as f:  # streamed: a full disk is an OSError
        np.lib.format.write_array_header_1_0(f, header)
        for _, x in st.padded_batches():
            f.write(np.ascontiguousarray(x, dtype="<f4").tobytes())
    files = {"data": "data.npy"}
    arrays = st.index_arrays()
    if st.taxel_positions is not None:
        arrays["taxel_positions"] = st.taxel_positions
    for k, arr in arrays.items():
        np.save(folder / f"{k}.npy", arr, allow_pickle=False)
        files[k] = f"{k}.npy"
    meta = {k: v for k, v in st.meta.items() if k not in _STORE_ONLY}
    (folder / "meta.json").write_text(json.dumps(meta, indent=1, sort_keys=True))
    files["meta"] = "meta.json"
    return files


#: ``--format`` -> the function that writes one data set into a folder
FORMATS: dict[str, Callable[[SlideStore, Path], dict[str, str]]] = {"numpy": write_numpy}


def export(
    path: str | Path,
    out: str | Path,
    *,
    part: str | None = None,
    format: str = "numpy",
    log: Callable[[str], None] | None = None,
) -> dict:
    """Write a complete data set as plain files into the new (or empty) folder ``out``, in
    ``format`` (:data:`FORMATS`; ``numpy``: :func:`write_numpy`). A suite's store exports
    each part into ``out/<part>/``. Everything is checked before it is copied, and the
    export is built beside ``out`` and renamed when whole: on any failure nothing is left,
    and the temporary folder a killed export left is removed (with a note to ``log``)."""
    writer = FORMATS.get(format)
    if writer is None:
        raise ConfigError(f"--format {format!r} is not valid; valid: {', '.join(FORMATS)}")
    path, out = Path(path), Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise StoreError(f"--out {str(out)!r} exists and is not an empty folder")
    parts = parts_of(path)
    suite = bool(parts) and part is None
    names = parts if suite else [part]
    stores = {name: open_store(path, name) for name in names}
    for st in stores.values():
        st.require_complete(" before exporting")
    docs = {}
    with building(out, log) as tmp:
        for name, st in stores.items():
            folder = tmp / name if suite else tmp
            folder.mkdir(exist_ok=True)
            docs[name] = {"slides": len(st), "files": writer(st, folder)}
    if suite:
        for name, doc in docs.items():
            doc["out"] = str(out / name)
        slides = sum(d["slides"] for d in docs.values())
        return {"out": str(out), "format": format, "parts": docs, "slides": slides}
    return {"out": str(out), "format": format, **docs[part]}
