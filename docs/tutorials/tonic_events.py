"""Tutorial: a data set's spikes as Tonic events, framed and batched by Tonic.

python docs/tutorials/tonic_events.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import tonic
import torch

from sim_tactile import tasks
from sim_tactile.encoders import ThresholdEncoder
from sim_tactile.formats.events import TactileEvents
from sim_tactile.generate import generate

CONFIG = """\
name = "events-demo"
plates = ["finger7/flat", "finger7/ridges-4"]
sensor = "grid3x3"
slides_per_plate = 3

[protocol]
duration_s = 0.3
"""


def main(out: Path, quick: bool = True) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    if quick:  # a small set of your own, threshold-encoded (K = 2: 5 trains per taxel)
        (out / "set.toml").write_text(CONFIG)
        generate(str(out / "set.toml"), out / "set.zarr", workers=1, progress=False)
        data, encoder, split = out / "set.zarr", ThresholdEncoder(rate_hz=100.0), None
    else:  # a task's test split, encoded by the task's own encoder (SA Izhikevich)
        data, encoder, split = tasks.load("finger7-v1", quick=True), None, "test"
    events = TactileEvents(data, encoder=encoder, split=split)
    print("sensor_size (W, H, P):", events.sensor_size, "ordering:", events.ordering)
    ev, target = events[0]
    print(len(ev), "events of class", events.classes[target], "first:", ev[:3])

    # Tonic's ToFrame: (frames, P, H, W), one frame per 10 ms over the whole window; its
    # counts are the encoder's, train by train
    trains = events.spike_trains(0)
    to_frame = tonic.transforms.ToFrame(
        sensor_size=events.sensor_size,
        time_window=10_000,
        start_time=0,
        end_time=round(trains.t_end * 1e6),
    )
    frames = to_frame(ev)
    codec, lay = events.codec, events.layout
    for m, times in enumerate(trains.times):
        c, k = codec.tmap.channel[m], codec.tmap.kind[m]
        p = lay.layer[c] * codec.tmap.per_channel + k
        assert frames[:, p, lay.y[c], lay.x[c]].sum() == times.size
    # and back: the same spike trains
    back = codec.to_spike_trains(ev, t_end_s=trains.t_end)
    assert all(np.array_equal(a, b) for a, b in zip(trains.times, back.times, strict=True))

    # a DataLoader with Tonic's PadTensors batches recordings of any number of frames
    framed = TactileEvents(data, encoder=events.encode.encoder, split=split, transform=to_frame)
    loader = torch.utils.data.DataLoader(
        framed, batch_size=2, collate_fn=tonic.collation.PadTensors(batch_first=True)
    )
    x, y = next(iter(loader))
    print("a batch:", tuple(x.shape), "(batch, frames, P, H, W); targets", y.tolist())
    return {"sensor_size": events.sensor_size, "events": len(ev), "batch": tuple(x.shape)}


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
