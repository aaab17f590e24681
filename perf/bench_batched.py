"""Would batched slides pay? The spectral skin's product ``C p`` for K slides of one scene in
one call (a stack of K lattices through each FFT) against K calls, per product.

    python perf/bench_batched.py [--lattices 68x95,30x40] [--batches 1,4,16] [--reps 200]

A slide's spectral contact solve is a sequence of these products (about 30 a step on the
iCub's fine grids), so their cost per product bounds what stepping K slides together could
gain, before the cost of keeping K conjugate-gradient solves in lockstep (each slide stops
at its own iteration count, so a batch runs to its slowest member). The batched products
are checked equal to the single ones bit for bit. CPU time, medians of ``--rounds``
alternating runs of the two ways.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy import fft

from sim_tactile.sim.skin.contact.spectral import Spectral


def batched_apply(S: Spectral, P: np.ndarray) -> np.ndarray:
    """``C p`` of each row of ``P`` (K, n) in one call per transform (as :meth:`Spectral.apply`)."""
    k = P.shape[0]
    Ly, Lx = S.shape
    a = fft.rfft(P.reshape(k, S.ny, S.nx), n=Lx, axis=2)
    a = fft.fft(a, n=Ly, axis=1)
    a *= S.khat
    a = fft.ifft(a, axis=1, overwrite_x=True)[:, : S.ny]
    return fft.irfft(a, n=Lx, axis=2)[:, :, : S.nx].reshape(k, -1)


def measure(ny: int, nx: int, k: int, reps: int, rounds: int) -> dict:
    x, y = np.meshgrid(np.arange(nx), np.arange(ny))
    S = Spectral(1.0 / (1.0 + np.hypot(x, y)))  # a kernel of the shape of the elastic one
    P = np.random.default_rng(0).random((k, ny * nx))
    out = batched_apply(S, P)
    equal = all(np.array_equal(out[i], S.apply(P[i])) for i in range(k))

    def single():
        for _ in range(reps):
            for i in range(k):
                S.apply(P[i])

    def batch():
        for _ in range(reps):
            batched_apply(S, P)

    times = {"single": [], "batched": []}
    for _ in range(rounds):
        for name, f in (("single", single), ("batched", batch)):
            t0 = time.process_time()
            f()
            times[name].append((time.process_time() - t0) / (reps * k))
    s, b = statistics.median(times["single"]), statistics.median(times["batched"])
    return {
        "lattice": f"{ny}x{nx}",
        "K": k,
        "single_us": s * 1e6,
        "batched_us": b * 1e6,
        "ratio": s / b,
        "bit_equal": equal,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lattices", default="68x95,25x30", help="node lattices ny x nx")
    ap.add_argument("--batches", default="1,4,16", help="slides per call")
    ap.add_argument("--reps", type=int, default=100)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    print(
        "| lattice | K | one call per slide [us/product] | batched [us/product] | ratio | bit for bit |"
    )
    print("|---|---|---|---|---|---|")
    for lat in args.lattices.split(","):
        ny, nx = (int(v) for v in lat.split("x"))
        for k in (int(v) for v in args.batches.split(",")):
            r = measure(ny, nx, k, args.reps, args.rounds)
            print(
                f"| {r['lattice']} | {r['K']} | {r['single_us']:.1f} | {r['batched_us']:.1f} | "
                f"{r['ratio']:.2f}x | {r['bit_equal']} |"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
