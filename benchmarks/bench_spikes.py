"""Speed of the spike-train distances and the Izhikevich encoder against reference libraries.

Runs everything side by side in one process and prints a table of median wall times over
repeated runs (after one warm-up call, so numba compilation is not counted):

- 100 x 100 Victor-Purpura matrix of ~50-spike trains: ours vs Elephant (``--elephant-repeats``)
- 100 x 100 van Rossum matrix: ours vs Elephant
- 100 x 100 ISI- and SPIKE-distance matrices: ours vs PySpike
- Izhikevich, 1000 neurons x 10 000 steps: rk4 (0.1 ms) and the papers' Euler (1 ms)

Usage::

    python benchmarks/bench_spikes.py [--quick] [--repeats N] [--json [PATH]]

``--json`` alone prints one JSON document on stdout instead of the table; ``--json PATH``
writes it to PATH as well as printing the table. ``--quick`` skips the slow Elephant VP run.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
import warnings

import numpy as np

from sim_tactile.encoders import simulate_izhikevich
from sim_tactile.spikes import distances as D


def _median_time(fn, repeats: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def _trains(seed: int, n: int = 100, mean_spikes: int = 50, t_end: float = 1.0):
    rng = np.random.default_rng(seed)
    return [np.sort(rng.uniform(0, t_end, rng.poisson(mean_spikes))) for _ in range(n)]


def bench_distances(repeats: int, elephant_repeats: int, quick: bool) -> list[dict]:
    trains = _trains(0)
    rows = []
    q, tau = 24.0, 0.01  # q = 0.024 / ms, the best of seed paper 001
    ours = {
        "victor_purpura": lambda: D.pairwise(trains, "vp", q=q),
        "van_rossum": lambda: D.pairwise(trains, "vr", tau=tau),
        "isi_distance": lambda: D.pairwise(trains, "isi", t_start=0.0, t_end=1.0),
        "spike_distance": lambda: D.pairwise(trains, "spike", t_start=0.0, t_end=1.0),
    }
    for fn in ours.values():
        fn()  # warm-up: JIT compile / load cache
    refs: dict[str, tuple[str, object, int]] = {}
    try:
        import neo
        import quantities as pq
        from elephant import spike_train_dissimilarity as sd

        neo_trains = [neo.SpikeTrain(t * pq.s, t_stop=1.0 * pq.s) for t in trains]
        if not quick:
            refs["victor_purpura"] = (
                "elephant",
                lambda: sd.victor_purpura_distance(neo_trains, cost_factor=q * pq.Hz),
                elephant_repeats,
            )
        refs["van_rossum"] = (
            "elephant",
            lambda: sd.van_rossum_distance(neo_trains, time_constant=tau * pq.s) / np.sqrt(2),
            repeats,
        )
    except ImportError:
        print("elephant not installed: no reference for VP / van Rossum", file=sys.stderr)
    try:
        import pyspike as spk

        spk_trains = [spk.SpikeTrain(t, [0.0, 1.0]) for t in trains]
        refs["isi_distance"] = ("pyspike", lambda: spk.isi_distance_matrix(spk_trains), repeats)
        refs["spike_distance"] = (
            "pyspike",
            lambda: spk.spike_distance_matrix(spk_trains),
            repeats,
        )
    except ImportError:
        print("pyspike not installed: no reference for ISI / SPIKE", file=sys.stderr)
    for name, fn in ours.items():
        t_ours, m_ours = _median_time(fn, repeats)
        row = {
            "task": f"{name} 100x100, ~50 spikes",
            "ours_s": t_ours,
            "reference": None,
            "reference_s": None,
            "speedup": None,
            "max_abs_diff": None,
        }
        if name in refs:
            lib, ref_fn, n_rep = refs[name]
            print(f"running {lib} {name} ({n_rep} run(s))...", file=sys.stderr)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t_ref, m_ref = _median_time(ref_fn, n_rep)
            row.update(
                reference=lib,
                reference_s=t_ref,
                speedup=t_ref / t_ours,
                max_abs_diff=float(np.max(np.abs(np.asarray(m_ref) - m_ours))),
            )
        rows.append(row)
    return rows


def bench_izhikevich(repeats: int) -> list[dict]:
    rng = np.random.default_rng(1)
    rows = []
    for scheme, dt_s, n_samples in (("rk4", 1e-4, 100), ("euler", 1e-3, 1000)):
        current = rng.uniform(0.0, 15.0, (1000, n_samples))  # 100 Hz input, 1 s or 10 s
        simulate_izhikevich(current[:2], 100.0, "RS", dt_s=dt_s, scheme=scheme)  # warm-up
        t, out = _median_time(
            lambda c=current, s=scheme, d=dt_s: simulate_izhikevich(
                c, 100.0, "RS", dt_s=d, scheme=s
            ),
            repeats,
        )
        steps = 1000 * round(n_samples / 100.0 / dt_s)
        rows.append(
            {
                "task": f"izhikevich RS {scheme} dt={dt_s * 1e3:g} ms, 1000 neurons x 10000 steps",
                "ours_s": t,
                "neuron_steps_per_s": steps / t,
                "spikes": int(sum(o.size for o in out)),
            }
        )
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7, help="runs per timing (median)")
    ap.add_argument("--elephant-repeats", type=int, default=1, help="runs of Elephant's VP")
    ap.add_argument("--quick", action="store_true", help="skip Elephant's slow VP matrix")
    ap.add_argument("--json", nargs="?", const="-", default=None, help="JSON to stdout or PATH")
    args = ap.parse_args(argv)
    report = {
        "distances": bench_distances(args.repeats, args.elephant_repeats, args.quick),
        "izhikevich": bench_izhikevich(args.repeats),
        "repeats": args.repeats,
    }
    doc = json.dumps(report, indent=2)
    if args.json == "-":
        print(doc)
        return 0
    if args.json:
        with open(args.json, "w") as fh:
            fh.write(doc + "\n")
    print(f"{'task':58s} {'ours [s]':>10s} {'reference':>10s} {'ref [s]':>10s} {'speedup':>8s}")
    for r in report["distances"]:
        ref_s = "-" if r["reference_s"] is None else f"{r['reference_s']:.4f}"
        sp = "-" if r["speedup"] is None else f"{r['speedup']:.1f}x"
        print(
            f"{r['task']:58s} {r['ours_s']:10.4f} {r['reference'] or '-':>10s} {ref_s:>10s} {sp:>8s}"
        )
    for r in report["izhikevich"]:
        print(f"{r['task']:58s} {r['ours_s']:10.4f}  {r['neuron_steps_per_s']:.3g} neuron-steps/s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
