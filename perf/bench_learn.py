"""Training time per epoch of the spiking network and the LSTM on this machine.

The inputs have the sizes of seed paper 000's data sets, with the training split of its 7:3
protocol (700 of 1000 slides) and its network sizes:

- BioTac: 400 steps; SNN 95 spike channels -> 60 hidden -> 20; LSTM 19 channels, hidden 60.
- iCub: 75 steps; SNN 300 spike channels -> 1200 hidden -> 20; LSTM 60 taxels with the
  convolutional front (6 x 10 grid), hidden 60.

Random inputs of the right shape and spike density stand in for the data (an epoch's cost
does not depend on the values). Each model trains ``--epochs`` epochs (default 4); the table
gives the median epoch time, after the first epoch (numba compilation, allocation) is dropped.

Usage::

    python perf/bench_learn.py [--epochs N] [--threads N] [--json [PATH]]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys

import numpy as np

from sim_tactile.learn.lstm import LSTMClassifier
from sim_tactile.learn.snn import SNNClassifier

N_TRAIN = 700  # 7:3 split of 20 x 50 slides
N_CLASSES = 20
#: mean fraction of (step, channel) cells holding a spike in the threshold encoding of the
#: real data (measured: 0.063 BioTac, 0.14 iCub)
SPIKE_DENSITY = {"biotac": 0.063, "icub": 0.14}

CASES = {
    "biotac": {"steps": 400, "channels": 19, "rate_hz": 100.0, "hidden": 60, "targets": (250, 30)},
    "icub": {"steps": 75, "channels": 60, "rate_hz": 50.0, "hidden": 1200, "targets": (70, 3)},
}


def _labels(rng) -> np.ndarray:
    return rng.permutation(np.arange(N_TRAIN) % N_CLASSES)


def bench_case(name: str, epochs: int, threads: int) -> list[dict]:
    c = CASES[name]
    rng = np.random.default_rng(0)
    y = _labels(rng)
    spikes = (rng.random((N_TRAIN, c["steps"], 5 * c["channels"])) < SPIKE_DENSITY[name]).astype(
        np.float32
    )
    raw = rng.normal(size=(N_TRAIN, c["steps"], c["channels"])).astype(np.float32)
    common = {"epochs": epochs, "random_state": 0, "device": "cpu", "num_threads": threads}
    models = {
        "snn": (
            SNNClassifier(
                hidden=c["hidden"],
                target_true=c["targets"][0],
                target_false=c["targets"][1],
                dt_s=1.0 / c["rate_hz"],
                batch_size=32,
                **common,
            ),
            spikes,
        ),
        "lstm": (
            LSTMClassifier(grid_shape=(6, 10) if name == "icub" else None, batch_size=32, **common),
            raw,
        ),
    }
    rows = []
    for model, (est, X) in models.items():
        est.fit(X, y)
        times = est.epoch_times_s_[1:] or est.epoch_times_s_
        params = sum(p.numel() for p in est.module_.parameters())
        rows.append(
            {
                "data": name,
                "model": model,
                "input": list(X.shape),
                "parameters": int(params),
                "epoch_s": round(statistics.median(times), 3),
                "epochs_timed": len(times),
            }
        )
        print(f"{name:7s} {model:5s} {rows[-1]['epoch_s']:8.2f} s/epoch", file=sys.stderr)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--epochs", type=int, default=4)
    ap.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    ap.add_argument("--json", nargs="?", const="-", default=None)
    args = ap.parse_args(argv)
    rows = [r for name in CASES for r in bench_case(name, args.epochs, args.threads)]
    doc = {
        "rows": rows,
        "threads": args.threads,
        "batch_size": 32,
        "machine": platform.machine(),
        "python": platform.python_version(),
    }
    if args.json == "-":
        json.dump(doc, sys.stdout, indent=2)
        print()
        return 0
    print(f"{'data':8s} {'model':6s} {'input (n, T, C)':20s} {'params':>9s} {'s/epoch':>9s}")
    for r in rows:
        shape = "x".join(str(s) for s in r["input"])
        print(
            f"{r['data']:8s} {r['model']:6s} {shape:20s} {r['parameters']:9d} {r['epoch_s']:9.2f}"
        )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(doc, fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
