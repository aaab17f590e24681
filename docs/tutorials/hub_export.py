"""Tutorial: a store for data hubs: Parquet shards, a dataset card and Croissant metadata.

python docs/tutorials/hub_export.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

import datasets
import mlcroissant
import numpy as np

import sim_tactile.datasets as st_datasets
from sim_tactile.formats.hub import export_parquet
from sim_tactile.generate import generate

CONFIG = """\
name = "hub-demo"
plates = ["finger7/flat", "finger7/ridges-8"]
sensor = "grid3x3"
slides_per_plate = 3

[protocol]
duration_s = 0.3
"""


def main(out: Path, quick: bool = True) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    if quick:  # a set of your own (no task: one split, train)
        (out / "set.toml").write_text(CONFIG)
        generate(str(out / "set.toml"), out / "set.zarr", workers=1, progress=False)
        store = out / "set.zarr"
    else:  # a task's store: the train and test splits of its protocol
        generate("finger7-v1", out / "f7.zarr", quick=True, progress=False)
        store = out / "f7.zarr"
    # the same as: sim-tactile export STORE --out DIR --format parquet
    res = export_parquet(store, out / "hub")
    print(res["configs"], res["files"][:3])
    print((out / "hub" / "README.md").read_text()[:400])  # the card's YAML header

    # Hugging Face datasets reads the splits and the class names: from the files, as the
    # card says (its cache is keyed by the files), or by folder (keyed by the folder's name
    # and the card's YAML, which names the content: another export into a folder of the
    # same name is read anew, not served from this one's cache)
    hub = out / "hub"
    ds = datasets.load_dataset(
        "parquet", data_files={"train": f"{hub}/data/default/train-*.parquet"}
    )
    assert len(datasets.load_dataset(str(hub))["train"]) == len(ds["train"])
    train = ds["train"].with_format("numpy")
    x = np.stack(list(train["data"]))
    print(ds, train.features["label"].names, x.shape)
    np.testing.assert_array_equal(x[0], st_datasets.open(store)[int(train["index"][0])])

    # mlcroissant validates the metadata and reads the same records
    meta = mlcroissant.Dataset(jsonld=str(out / "hub" / "croissant.json"))
    first = next(iter(meta.records(record_set="default-train")))
    print("a Croissant record's label:", first["default-train/label"])
    return res


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
