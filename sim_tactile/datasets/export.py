"""Data sets from recordings and to plain files: :func:`from_tactile` writes any
:class:`~sim_tactile.records.TactileDataset` (the real recordings) in a store's form,
:func:`export` writes a store as ``.npy`` files and JSON."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import StoreError
from ..hashing import array_digest
from ..records import TactileDataset
from .reader import SlideStore, open_store, parts_of
from .store import PARAM_NAMES, SlideWriter, StoreSpec, create_store, slide_digest, zarr_module


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
    new store at ``path`` and open it."""
    path = Path(path)
    if path.exists():
        raise StoreError(f"{str(path)!r} exists; give a new path")
    spec = spec_from_tactile(ds, name)
    create_store(path, {"": spec}, {})
    root = zarr_module().open_group(str(path), mode="r+")
    w = SlideWriter(root)
    for i in range(ds.n_samples):
        w.write(i, ds.data[i])
    root.attrs.update({"complete": True})
    return open_store(path)


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
