"""Speed of the spike-train distances and the Izhikevich encoder against reference libraries.

Runs everything side by side in one process and prints a table of median wall times over
repeated runs (after one warm-up call, so numba compilation is not counted):

- 100 x 100 Victor-Purpura matrix of ~50-spike trains: ours vs Elephant (``--elephant-repeats``)
- 100 x 100 van Rossum matrix: ours vs Elephant
- 100 x 100 ISI- and SPIKE-distance matrices: ours vs PySpike
- Izhikevich, 1000 neurons x 10 000 steps: rk4 (0.1 ms) and the papers' Euler and 2003
  schemes (1 ms), the whole call (input checks, the kernel, one spike array per neuron)
  against a plain numba loop over the same neurons and steps that records every spike into
  a preallocated array (the same arithmetic; the plain rk4 does not bisect to the crossing)

Usage::

    python perf/bench_spikes.py [--quick] [--repeats N] [--json [PATH]]

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


def _plain_loop():
    """A plain numba loop of each scheme: one pass over the neurons per step, the step and
    the spike test together, every spike recorded into a preallocated array."""
    from numba import njit

    @njit(cache=True)
    def plain(cur_t, steps, a, b, c, d, v_peak, v_init, h, rk4):
        n = cur_t.shape[1]
        v = np.full(n, v_init)
        u = b * v_init
        times = np.empty(8_000_000)
        who = np.empty(8_000_000, np.int64)
        nt = 0
        for k in range(steps.size):
            row = cur_t[steps[k]]
            for i in range(n):
                vi, ui, ci, ai, bi = v[i], u[i], row[i], a[i], b[i]
                if rk4:
                    k1v = (0.04 * vi + 5.0) * vi + 140.0 - ui + ci
                    k1u = ai * (bi * vi - ui)
                    x, y = vi + 0.5 * h * k1v, ui + 0.5 * h * k1u
                    k2v = (0.04 * x + 5.0) * x + 140.0 - y + ci
                    k2u = ai * (bi * x - y)
                    x, y = vi + 0.5 * h * k2v, ui + 0.5 * h * k2u
                    k3v = (0.04 * x + 5.0) * x + 140.0 - y + ci
                    k3u = ai * (bi * x - y)
                    x, y = vi + h * k3v, ui + h * k3u
                    k4v = (0.04 * x + 5.0) * x + 140.0 - y + ci
                    k4u = ai * (bi * x - y)
                    vn = vi + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
                    un = ui + h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u)
                else:
                    vn = vi + h * ((0.04 * vi + 5.0) * vi + 140.0 - ui + ci)
                    un = ui + h * (ai * (bi * vi - ui))
                if vn >= v_peak:
                    times[nt] = (k + 1) * h
                    who[nt] = i
                    nt += 1
                    vn, un = c[i], un + d[i]
                v[i], u[i] = vn, un
        return times[:nt], who[:nt]

    return plain


def bench_izhikevich(repeats: int) -> list[dict]:
    from sim_tactile.encoders._common import sample_of_step

    plain = _plain_loop()
    rng = np.random.default_rng(1)
    rows = []
    cases = (("rk4", 1e-4, 100), ("euler", 1e-3, 1000), ("izhikevich2003", 1e-3, 1000))
    for scheme, dt_s, n_samples in cases:
        current = rng.uniform(0.0, 15.0, (1000, n_samples))  # 100 Hz input, 1 s or 10 s
        simulate_izhikevich(current[:2], 100.0, "RS", dt_s=dt_s, scheme=scheme)  # warm-up
        t, out = _median_time(
            lambda c=current, s=scheme, d=dt_s: simulate_izhikevich(
                c, 100.0, "RS", dt_s=d, scheme=s
            ),
            repeats,
        )
        steps = 1000 * round(n_samples / 100.0 / dt_s)
        ref_s = None
        if scheme != "izhikevich2003":
            args = (
                np.ascontiguousarray(current.T),
                sample_of_step(n_samples, 100.0, dt_s),
                *(np.full(1000, x) for x in (0.02, 0.2, -65.0, 8.0)),
                30.0,
                -65.0,
                dt_s * 1e3,
                scheme == "rk4",
            )
            plain(*args)  # warm-up
            ref_s, _ = _median_time(lambda args=args: plain(*args), repeats)
        rows.append(
            {
                "task": f"izhikevich RS {scheme} dt={dt_s * 1e3:g} ms, 1000 neurons x 10000 steps",
                "ours_s": t,
                "neuron_steps_per_s": steps / t,
                "plain_loop_s": ref_s,
                "plain_loop_neuron_steps_per_s": None if ref_s is None else steps / ref_s,
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
        plain = r["plain_loop_neuron_steps_per_s"]
        vs = "" if plain is None else f" (plain loop {plain:.3g})"
        print(
            f"{r['task']:58s} {r['ours_s']:10.4f}  {r['neuron_steps_per_s']:.3g} neuron-steps/s{vs}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
