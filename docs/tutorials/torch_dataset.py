"""Tutorial: a store as a PyTorch Dataset, read lazily by DataLoader workers.

python docs/tutorials/torch_dataset.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import torch

from sim_tactile import tasks
from sim_tactile.encoders import ThresholdEncoder
from sim_tactile.formats.torch_data import TactileTorchDataset
from sim_tactile.generate import generate

CONFIG = """\
name = "torch-demo"
plates = ["finger7/flat", "finger7/bumps-3x3"]
sensor = "grid3x3"
slides_per_plate = 4

[protocol]
duration_s = 0.3
"""


def main(out: Path, quick: bool = True) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    if quick:  # a set of your own: every slide (a store of no task has no task split)
        (out / "set.toml").write_text(CONFIG)
        generate(str(out / "set.toml"), out / "set.zarr", workers=1, progress=False)
        train = TactileTorchDataset(out / "set.zarr")
    else:  # a task's store, and the train side of its first split, as tasks.load gives it
        generate("finger7-v1", out / "f7.zarr", quick=True, progress=False)
        train = TactileTorchDataset(out / "f7.zarr", split="train")
        td = tasks.load("finger7-v1", quick=True, store=out / "f7.zarr")
        np.testing.assert_array_equal(train.indices, next(td.splits())[0])

    # raw streams: (T, N) float32 tensors, read slide by slide from the Zarr store
    loader = torch.utils.data.DataLoader(train, batch_size=4, shuffle=False, num_workers=2)
    x, y = next(iter(loader))
    print("raw batch:", tuple(x.shape), "(batch, time, taxels); labels", y.tolist())

    # encoded: 0 / 1 rasters (steps, trains), the SNN's input; a seeded shuffle repeats
    encoded = TactileTorchDataset(
        out / ("set.zarr" if quick else "f7.zarr"),
        split=None if quick else "train",
        encoder=ThresholdEncoder(rate_hz=100.0),
    )
    g = torch.Generator().manual_seed(0)
    loader = torch.utils.data.DataLoader(encoded, batch_size=4, shuffle=True, generator=g)
    r, y = next(iter(loader))
    print("encoded batch:", tuple(r.shape), "spikes:", int(r.sum()))
    return {"raw": tuple(x.shape), "encoded": tuple(r.shape)}


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
