"""Benchmark of the format bridges on a 10,000-slide store: samples per second that the
PyTorch Dataset reads (raw and threshold-encoded, 0 and 2 DataLoader workers), the time to
export the store as Parquet (and, for scale, as numpy files), and with ``--data`` the NIR
graph's agreement with the SNN on the real BioTac task's test split (Norse).

The store is written without physics: ``datasets.from_tactile`` of synthetic slides the
shape of finger7-v1's (87 samples x 9 taxels at 100 Hz; noisy tones, 10 classes).

    python perf/bench_formats.py [--slides 10000] [--out build/bench/formats]
        [--data ../shared/datasets/biotac_slide_20_50]
"""

from __future__ import annotations

import argparse
import json
import shutil
import time
from pathlib import Path

import numpy as np

from sim_tactile import datasets
from sim_tactile.records import TactileDataset


def synthetic(n: int, t: int = 87, c: int = 9, classes: int = 10) -> TactileDataset:
    rng = np.random.default_rng(0)
    y = np.arange(n) % classes
    time_s = np.arange(t) / 100.0
    phase = rng.uniform(0, 2 * np.pi, n)
    tone = np.sin(2 * np.pi * (3.0 + y[:, None]) * time_s[None] + phase[:, None])
    x = tone[:, :, None] + rng.normal(0, 0.2, (n, t, c))
    names = [f"r{j}c{i}" for j in range(3) for i in range(3)]
    return TactileDataset(
        x.astype(np.float32),
        y,
        100.0,
        names,
        tuple(f"tone{k}" for k in range(classes)),
        meta={"grid_shape": [3, 3], "source": "synthetic tones (benchmark)"},
    )


def read_rate(store: Path, *, workers: int, encoded: bool, limit: int | None = None) -> dict:
    import torch

    from sim_tactile.encoders import ThresholdEncoder
    from sim_tactile.formats.torch_data import TactileTorchDataset

    enc = ThresholdEncoder(rate_hz=100.0, thresholds=np.array([-0.5, 0.5])) if encoded else None
    ds = TactileTorchDataset(store, encoder=enc)
    if limit is not None:
        ds.indices = ds.indices[:limit]
    loader = torch.utils.data.DataLoader(ds, batch_size=64, num_workers=workers)
    t0 = time.perf_counter()
    n = sum(len(y) for _, y in loader)
    wall = time.perf_counter() - t0
    return {"workers": workers, "encoded": encoded, "samples": n, "samples_per_s": n / wall}


def nir_agreement(data: Path) -> dict:
    from sklearn.pipeline import Pipeline

    from sim_tactile import tasks
    from sim_tactile.learn.nir import agreement
    from sim_tactile.learn.preprocess import SpikeRaster
    from sim_tactile.learn.snn import SNNClassifier

    task = "biotac20-real-v1"
    td = tasks.load(task, quick=True, data=data)
    spec = tasks.get_task(task)
    ctx = spec.context(td.dataset, True)
    raster = Pipeline(spec.encoder(ctx) + [("r", SpikeRaster(1 / td.rate_hz))]).fit_transform(td.X)
    tr, te = next(td.splits())
    params = {**spec.settings(True).params["snn"], "random_state": 0, "dt_s": 1 / td.rate_hz}
    clf = SNNClassifier(**params)
    t0 = time.perf_counter()
    clf.fit(raster[tr], td.y[tr])
    out = agreement(clf, raster[te])
    out.update(
        task=task,
        fit_s=time.perf_counter() - t0,
        accuracy=float(np.mean(clf.predict(raster[te]) == td.y[te])),
    )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--slides", type=int, default=10_000)
    ap.add_argument("--out", type=Path, default=Path("build/bench/formats"))
    ap.add_argument("--data", type=Path, default=None)
    args = ap.parse_args()
    shutil.rmtree(args.out, ignore_errors=True)
    args.out.mkdir(parents=True)
    store = args.out / "tones.zarr"
    t0 = time.perf_counter()
    datasets.from_tactile(synthetic(args.slides), store, name="tones")
    res: dict = {"slides": args.slides, "store_write_s": time.perf_counter() - t0}
    res["read"] = [
        read_rate(store, workers=w, encoded=e, limit=None if not e else 2000)
        for e in (False, True)
        for w in (0, 2)
    ]
    from sim_tactile.formats.hub import export_parquet

    t0 = time.perf_counter()
    export_parquet(store, args.out / "parquet")
    res["parquet_export_s"] = time.perf_counter() - t0
    res["parquet_mb"] = sum(f.stat().st_size for f in (args.out / "parquet").rglob("*")) / 2**20
    t0 = time.perf_counter()
    datasets.export(store, args.out / "numpy")
    res["numpy_export_s"] = time.perf_counter() - t0
    if args.data is not None:
        res["nir"] = nir_agreement(args.data)
    print(json.dumps(res, indent=1))
    (args.out / "result.json").write_text(json.dumps(res, indent=1) + "\n")


if __name__ == "__main__":
    main()
