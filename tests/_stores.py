"""Small stores for the store tests, made without physics: ``generate`` with a fake worker
(each slide: normal samples seeded by the slide's seed), and what reading one back gives."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from sim_tactile import datasets
from sim_tactile.generate import generate
from sim_tactile.records import Recording
from sim_tactile.slides import SlideOutcome

#: 2 plates x 3 slides of 0.2 s on a 3 x 3 grid (the slides are drawn, never simulated)
TINY = {
    "name": "tiny",
    "seed": 7,
    "plates": ["finger7/flat", "finger7/ridges-2"],
    "sensor": "grid3x3",
    "slides_per_plate": 3,
    "protocol": {"duration_s": 0.2},
    "randomise": {"speed_jitter": 0.05, "force_jitter": 0.1, "offset_jitter_m": 0.5e-3},
}


def fake_slide(job) -> SlideOutcome:
    """A slide of the job's shape, its samples drawn from the job's seed (no physics)."""
    taxels = job.sensor.layout.positions
    rng = np.random.default_rng(job.seed)
    x = rng.normal(size=(job.n_samples(), len(taxels))).astype(np.float32)
    times = np.arange(len(x)) / job.protocol.rate_hz
    return SlideOutcome(Recording(x, times, taxels), (), 0.0, False)


def write_config(folder: Path, cfg: dict | None = None, name: str = "tiny.json") -> Path:
    path = folder / name
    path.write_text(json.dumps(cfg or TINY))
    return path


def quiet_generate(target, out, **kw) -> dict:
    kw.setdefault("workers", 1)
    kw.setdefault("_worker", fake_slide)
    return generate(str(target), out, progress=False, log=lambda m: None, **kw)


def make_store(folder: Path, name: str = "s.zarr", cfg: dict | None = None) -> Path:
    """A complete store of ``cfg`` (default :data:`TINY`) in ``folder``."""
    out = folder / name
    quiet_generate(write_config(folder, cfg), out)
    return out


def store_files(path: Path) -> list[Path]:
    """Every file under a store, relative to it."""
    return sorted(p.relative_to(path) for p in path.rglob("*") if p.is_file())


def chunk_file(group: Path, array: str, *index: int) -> Path:
    """The file of the chunk at ``index`` of ``array`` in the store folder ``group``, by the
    chunk key encoding the array's own metadata gives (its separator), as Zarr keys it."""
    meta = json.loads((group / array / "zarr.json").read_text())
    sep = meta["chunk_key_encoding"].get("configuration", {}).get("separator", "/")
    return group / array / sep.join(["c", *map(str, index)])


def sample_chunk(group: Path, slide: int) -> Path:
    """The file of slide ``slide``'s samples (``data``'s chunk ``(slide, 0, 0)``)."""
    return chunk_file(group, "data", slide, 0, 0)


def flip_bit(path: Path, bit: int) -> None:
    b = bytearray(path.read_bytes())
    b[bit // 8] ^= 1 << (bit % 8)
    path.write_bytes(bytes(b))


def read_back(path: Path, part: str | None = None) -> dict:
    """Everything a reader serves from a store, through every reader: open, verify, each
    slide, the batches, the whole data set. Raises StoreError if any of them refuses."""
    st = datasets.open(path, part)
    bad = st.verify()
    if bad:
        from sim_tactile.errors import StoreError

        raise StoreError(f"verify: {bad}")
    ds = st.to_tactile()
    slides = np.stack([st[i] for i in range(len(st))])
    batches = np.concatenate([x for x, _ in st.batches(4)])
    return {
        "meta": st.meta,
        "index": st.index_arrays(),
        "data": ds.data,
        "slides": slides,
        "batches": batches,
        "labels": ds.labels,
        "names": (ds.class_names, ds.channel_names, ds.units, ds.rate_hz),
        "taxels": ds.taxel_positions,
    }


def assert_same(a: dict, b: dict, history: bool = False) -> None:
    """Two read-backs are equal in every value (NaN equal to NaN); with ``history``, the
    runs recorded in the store too."""

    def meta(m: dict) -> str:
        if not history:
            m = {k: v for k, v in m.items() if k not in ("runs", "attrs_sha256")}
        return json.dumps(m, sort_keys=True)

    assert meta(a["meta"]) == meta(b["meta"])
    for k in a["index"]:
        np.testing.assert_array_equal(a["index"][k], b["index"][k], err_msg=k)
    for k in ("data", "slides", "batches", "labels", "taxels"):
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    assert a["names"] == b["names"]


def within(call, timeout_s: float) -> tuple[bool, dict]:
    """Run ``call()`` in a daemon thread: whether it is still running after ``timeout_s``
    (a hang), and ``{"value": ...}`` or ``{"exc": ...}`` when it returned."""
    import threading

    box: dict = {}

    def target():
        try:
            box["value"] = call()
        except BaseException as exc:  # noqa: BLE001 - handed to the test
            box["exc"] = exc

    t = threading.Thread(target=target, daemon=True)
    t.start()
    t.join(timeout_s)
    return t.is_alive(), box
