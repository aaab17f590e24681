"""A store for data hubs: Parquet shards of the task's splits, a dataset card and Croissant.

``sim-tactile export STORE --out DIR --format parquet`` (:func:`export_parquet`) writes::

    DIR/README.md                       the dataset card (the YAML header the Hub reads)
    DIR/croissant.json                  Croissant metadata (mlcroissant validates it)
    DIR/data/<config>/<split>-00000-of-0000N.parquet

One row per slide: ``data`` (its ``(T, N)`` samples, float32, the sensor's units), ``label``
(a class label with the class names), ``index`` (the slide's number in the store),
``slide`` (its number within its class), ``seed`` (its simulation seed) and the drawn
``speed_m_s``, ``force_n``, ``offset_y_m`` (NaN for recordings). The splits are those of the
task the store was generated for (repeat 0 of its protocol, with the store's seed: the pair
:meth:`~sim_tactile.tasks.TaskProtocol.splits` gives first); a store of no task has one split,
``train``, of every slide. A suite's store gives one configuration per part.

The columns' types are ``datasets.Features`` (its Arrow schema, written with pyarrow), so
``datasets.load_dataset("parquet", data_files=...)`` (the card's way: the files themselves)
or ``load_dataset(DIR)`` restores the class names. The card's YAML names each
configuration's content (:func:`~.card.card_data`: the shards' SHA-256, the configuration
hash, the slide code, the split sizes), because ``load_dataset(DIR)`` keys its cache by the
folder's name and that YAML, not by the files: two exports into folders of one name would
otherwise share one cache entry, and the second would serve the first's rows. The Croissant
file is built with ``mlcroissant``. Everything is written into a
temporary folder beside ``DIR`` and renamed at the end (as the numpy export is): a
failure leaves nothing behind.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .. import __version__
from ..datasets import SlideStore, open_store, parts_of
from ..datasets.fs import building
from ..datasets.store import PARAM_NAMES
from ..errors import StoreError, require
from ._source import Source
from .card import card_text, croissant_metadata

#: The hub's extra (datasets, pyarrow, mlcroissant).
EXTRA = "hub"
#: Target size of one shard's samples [bytes] before compression (the Hub's advice: a few
#: hundred MB per Parquet file).
SHARD_BYTES = 256 * 2**20


def _features(n_channels: int, class_names) -> object:
    hf = require("datasets", EXTRA)
    cols = {
        "data": hf.List(hf.List(hf.Value("float32"), length=n_channels)),
        "label": hf.ClassLabel(names=list(class_names)),
        "index": hf.Value("int64"),
        "slide": hf.Value("int64"),
        "seed": hf.Value("uint64"),
    }
    cols.update({k: hf.Value("float64") for k in PARAM_NAMES})
    return hf.Features(cols)


def _check_out(out: Path) -> None:
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise StoreError(f"--out {str(out)!r} exists and is not an empty folder")


def _splits(st: SlideStore) -> dict[str, np.ndarray]:
    src = Source(st)
    if src.task is None:
        return {"train": np.arange(len(st), dtype=np.int64)}
    return {side: src.split_indices(side, 0) for side in ("train", "test")}


def _table(st: SlideStore, features, idx: np.ndarray):
    pa = require("pyarrow", EXTRA)
    n_ch = len(st.channel_names)
    data = []
    for k in idx.tolist():
        x = np.ascontiguousarray(st[k], np.float32)  # checked against its checksum
        inner = pa.FixedSizeListArray.from_arrays(pa.array(x.reshape(-1)), n_ch)
        data.append(inner)
    offsets = np.concatenate([[0], np.cumsum([len(a) for a in data])]).astype(np.int32)
    values = pa.concat_arrays(data) if data else pa.array([], pa.list_(pa.float32(), n_ch))
    cols = {
        "data": pa.ListArray.from_arrays(pa.array(offsets), values),
        "label": pa.array(st.labels[idx], pa.int64()),
        "index": pa.array(idx, pa.int64()),
        "slide": pa.array(st.slide_numbers[idx], pa.int64()),
        "seed": pa.array(st.seeds[idx], pa.uint64()),
    }
    cols.update({k: pa.array(st.params[k][idx], pa.float64()) for k in PARAM_NAMES})
    return pa.Table.from_pydict(cols).cast(features.arrow_schema)


def _digest_file(digest, root: Path, rel: Path) -> None:
    """Add the file ``root / rel`` to ``digest``: its name, then its bytes (read in pieces)."""
    digest.update(rel.as_posix().encode() + b"\0")
    with open(root / rel, "rb") as fh:
        for piece in iter(lambda: fh.read(2**20), b""):
            digest.update(piece)


def _write_config(st: SlideStore, root: Path, config: str, rows: int | None, log) -> dict:
    """One configuration's shards; returns what the card and the Croissant file need."""
    pq = require("pyarrow.parquet", EXTRA)
    features = _features(len(st.channel_names), st.class_names)
    t_max = int(st.lengths.max()) if len(st) else 0
    per_shard = rows or max(1, SHARD_BYTES // max(1, 4 * t_max * len(st.channel_names)))
    splits, digest = {}, hashlib.sha256()
    for side, idx in _splits(st).items():
        n_shards = max(1, -(-len(idx) // per_shard))
        files, n_bytes = [], 0
        for s in range(n_shards):
            rel = Path("data") / config / f"{side}-{s:05d}-of-{n_shards:05d}.parquet"
            (root / rel).parent.mkdir(parents=True, exist_ok=True)
            part = idx[s * per_shard : (s + 1) * per_shard]
            table = _table(st, features, part)
            pq.write_table(table, root / rel, compression="zstd")
            n_bytes += int(table.nbytes)
            _digest_file(digest, root, rel)
            files.append(rel.as_posix())
        log(f"{config}/{side}: {len(idx)} slides in {n_shards} shard(s)")
        splits[side] = {"slides": len(idx), "files": files, "bytes": n_bytes}
    return {
        "config": config,
        "store": st,
        "features": features,
        "splits": splits,
        "shape": [t_max, len(st.channel_names)],
        "content_sha256": digest.hexdigest(),
        "download_bytes": sum(
            (root / f).stat().st_size for s in splits.values() for f in s["files"]
        ),
    }


def export_parquet(
    path: str | Path,
    out: str | Path,
    *,
    part: str | None = None,
    rows_per_shard: int | None = None,
    log: Callable[[str], None] | None = None,
) -> dict:
    """Write the store at ``path`` for data hubs into the new folder ``out`` (see the module
    docstring); a suite's store gives one configuration per part (``part``: only that one).
    Returns ``{out, format, slides, configs: {name: {split: slides}}, files: [...]}``."""
    log = log or (lambda m: None)
    path, out = Path(path), Path(out)
    _check_out(out)
    for mod in ("datasets", "pyarrow", "mlcroissant"):
        require(mod, EXTRA)
    parts = parts_of(path)
    names = [part] if part is not None else (parts or [None])
    stores = [(p or "default", open_store(path, p)) for p in names]
    for _, st in stores:
        st.require_complete(" before exporting")
    with building(out, log) as tmp:  # renamed to ``out`` when whole; removed on any failure
        infos = [_write_config(st, tmp, name, rows_per_shard, log) for name, st in stores]
        (tmp / "README.md").write_text(card_text(infos, __version__))
        doc = croissant_metadata(infos, tmp, __version__)
        (tmp / "croissant.json").write_text(json.dumps(doc, indent=1) + "\n")
    files = [f for i in infos for s in i["splits"].values() for f in s["files"]]
    return {
        "out": str(out),
        "format": "parquet",
        "slides": sum(s["slides"] for i in infos for s in i["splits"].values()),
        "configs": {i["config"]: {k: s["slides"] for k, s in i["splits"].items()} for i in infos},
        "files": ["README.md", "croissant.json", *files],
    }
