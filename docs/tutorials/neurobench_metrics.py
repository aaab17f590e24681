"""Tutorial: NeuroBench's figures of the spiking network, and an encoder's spike rate.

python docs/tutorials/neurobench_metrics.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from sklearn.pipeline import Pipeline

from sim_tactile import tasks
from sim_tactile.encoders.encodings import threshold_encoding
from sim_tactile.learn.neurobench import encoder_rate
from sim_tactile.learn.preprocess import SpikeRaster
from sim_tactile.learn.snn import SNNClassifier
from sim_tactile.records import TactileDataset


def _tones(n_per_class: int = 6) -> TactileDataset:
    """Two classes of noisy tones on 9 channels at 100 Hz (1 s): data to look at the figures
    on without simulating."""
    rng = np.random.default_rng(0)
    t = np.arange(100) / 100.0
    x, y = [], []
    for label, f_hz in enumerate((4.0, 11.0)):
        for _ in range(n_per_class):
            s = np.sin(2 * np.pi * f_hz * t + rng.uniform(0, 6.3))[:, None]
            x.append(s + rng.normal(0, 0.2, (100, 9)))
            y.append(label)
    return TactileDataset(np.array(x), np.array(y), 100.0, [f"t{i}" for i in range(9)], ("a", "b"))


def main(out: Path, quick: bool = True) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    if not quick:  # a task's report: every spiking row carries the figures (report.md too)
        rep = tasks.run_task("finger7-v1", out / "run", quick=True, classifiers="snn,svm-spike")
        return {r["label"]: r.get("neuromorphic") for r in rep["results"]}
    ds = _tones()
    encode = Pipeline(threshold_encoding(ds)).fit(ds.data)
    trains = encode.transform(ds.data)
    print("encoder:", encoder_rate(trains))  # spikes per second of input, all channels
    raster = SpikeRaster(dt_s=0.01).fit_transform(trains)
    clf = SNNClassifier(hidden=16, target_true=20, target_false=3, dt_s=0.01, epochs=10)
    clf.set_params(lr=0.03, batch_size=4, random_state=0).fit(raster, ds.labels)
    figs = clf.neuromorphic_metrics(raster)
    for key in (
        "footprint_bytes",
        "parameter_count",
        "connection_sparsity",
        "activation_sparsity",
        "synaptic_operations",
    ):
        print(f"{key}: {figs[key]}")
    return figs


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
