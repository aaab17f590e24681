"""Tutorial: the spiking network (and an LIF encoder) out as NIR, run again in Norse.

python docs/tutorials/nir_export.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

from sklearn.pipeline import Pipeline

import sim_tactile.datasets as st_datasets
from sim_tactile import tasks
from sim_tactile.encoders import LIFEncoder
from sim_tactile.encoders.encodings import threshold_encoding
from sim_tactile.generate import generate
from sim_tactile.learn import nir as nir_bridge
from sim_tactile.learn.preprocess import SpikeRaster
from sim_tactile.learn.protocols import repeated_splits
from sim_tactile.learn.snn import SNNClassifier

CONFIG = """\
name = "nir-demo"
plates = ["finger7/flat", "finger7/ridges-2", "finger7/ridges-8"]
sensor = "grid3x3"
slides_per_plate = 4

[protocol]
duration_s = 0.5
"""


def main(out: Path, quick: bool = True) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    if quick:  # a set of your own: train on half of each class, test on the rest
        (out / "set.toml").write_text(CONFIG)
        generate(str(out / "set.toml"), out / "set.zarr", workers=1, progress=False)
        ds = st_datasets.open(out / "set.zarr").to_tactile()
        x, y = ds.data, ds.labels
        train, test = repeated_splits(y, "2/2", 1)[0]
    else:  # a task's data and the first split of its protocol
        td = tasks.load("finger7-v1", quick=True)
        x, y, ds = td.X, td.y, td.dataset
        train, test = next(td.splits())
    steps = threshold_encoding(ds) + [("raster", SpikeRaster(dt_s=1 / ds.rate_hz))]
    raster = Pipeline(steps).fit_transform(x)  # (samples, steps, 5 trains x taxels)
    clf = SNNClassifier(hidden=16, target_true=20, target_false=3, dt_s=1 / ds.rate_hz)
    clf.set_params(epochs=20 if quick else 100, lr=0.03, batch_size=4, random_state=0)
    clf.fit(raster[train], y[train])

    graph = clf.to_nir()  # input -> Linear -> CubaLIF -> Linear -> CubaLIF -> output
    path = nir_bridge.write_nir(graph, out / "snn.nir")  # HDF5: snnTorch, Norse, Lava, ...
    again = nir_bridge.read_nir(path)
    print({k: type(n).__name__ for k, n in again.nodes.items()})

    # a consumer written elsewhere (Norse) runs the graph; how often it decides as we do
    agree = nir_bridge.agreement(clf, raster[test])
    print(
        f"agreement {agree['agreement']:.2f} over {agree['samples']} test slides; count "
        f"correlation {agree['count_correlation']:.2f}; kernel (Euler) {agree['kernel']}"
    )

    # an LIF encoder's parameters go out as Affine (its normalisation) and LIF
    enc = LIFEncoder(rate_hz=ds.rate_hz, gain=3.0, normalize="minmax").fit(x)
    lif_graph = nir_bridge.lif_encoder_to_nir(enc)
    nir_bridge.write_nir(lif_graph, out / "lif_encoder.nir")
    return agree


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
