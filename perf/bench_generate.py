"""Benchmark of ``sim-tactile generate``: slides per second on 1 and 2 workers, the store's
overhead over the simulation, and the parent's memory as the data set grows.

Slides: the finger7-v1 protocol (grid3x3, 60 mm/s, 1 N, the 0.87 s window) over the seven
finger7 plates, a fresh seed each run (generate never fills the slide cache, so nothing is
read back). Runs of 1 and 2 workers alternate, so a change of load on this shared machine
hits both alike; medians over the repeats. The store's overhead is measured inside each
1-worker run (slides simulated in this process): the time in writes and checksums against
the time in simulation, and the whole run's wall time against the time in simulation (also
store creation, configuration hashing, the run's record). A separate store-less run is no
fair baseline here: the same slides vary by +-25% in time from one minute to the next on
this shared machine. Memory: a fresh
process per size writes short slides (0.2 s) with 2 workers; the parent's resident set at
the end and its peak.

    python perf/bench_generate.py [--repeats 5] [--slides 6] [--out build/bench/generate]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
from pathlib import Path

from sim_tactile.tasks.defs.finger7 import FINGER7_PLATES

RANDOMISE = {"speed_jitter": 0.05, "force_jitter": 0.10, "offset_jitter_m": 0.5e-3}


def config(seed: int, slides: int, duration_s: float | None = None) -> dict:
    proto = {"speed_m_s": 0.06, "force_n": 1.0, "rate_hz": 100.0}
    if duration_s is not None:
        proto["duration_s"] = duration_s
    return {
        "seed": seed,
        "plates": list(FINGER7_PLATES),
        "sensor": "grid3x3",
        "slides_per_plate": slides,
        "protocol": proto,
        "randomise": RANDOMISE,
    }


def _rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def _quiet(m: str) -> None:
    pass


def memory_child(out: Path, slides: int) -> None:
    """Runs in a fresh process: generate ``7 x slides`` short slides, print the memory."""
    from sim_tactile.generate import generate

    cfg = out.with_suffix(".json")
    cfg.write_text(json.dumps(config(1000 + slides, slides, duration_s=0.2)))
    rss0 = _rss_mb()
    res = generate(str(cfg), out, workers=2, progress=False, log=_quiet)
    print(
        json.dumps(
            {
                "slides": res["trials"],
                "wall_s": res["wall_s"],
                "rss_start_mb": round(rss0, 1),
                "rss_end_mb": round(_rss_mb(), 1),
                "peak_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
                "worker_peak_mb": round(
                    resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, 1
                ),
                "store_mb": round(
                    sum(p.stat().st_size for p in out.rglob("*") if p.is_file()) / 2**20, 2
                ),
            }
        )
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--slides", type=int, default=6, help="slides per plate in a timed run")
    ap.add_argument("--sizes", default="6,60", help="slides per plate of the memory runs")
    ap.add_argument("--out", default="build/bench/generate")
    ap.add_argument("--memory-child", nargs=2, metavar=("STORE", "SLIDES"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.memory_child:
        memory_child(Path(args.memory_child[0]), int(args.memory_child[1]))
        return
    out = Path(args.out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    os.environ["SIM_TACTILE_CACHE"] = str(out / "cache")  # plates built once, no slide hits
    from sim_tactile.generate import generate

    load = [os.getloadavg()[0]]
    print("warming up (plates, compiled kernels) ...", file=sys.stderr, flush=True)
    (out / "warm.json").write_text(json.dumps(config(999, 2)))
    generate(str(out / "warm.json"), out / "warm.zarr", workers=1, progress=False, log=_quiet)

    rows: dict[str, list[dict]] = {"w1": [], "w2": []}
    for r in range(args.repeats):
        for kind in ("w1", "w2"):
            seed = 100 * int(kind[1]) + r
            cfg = out / f"{kind}-{r}.json"
            cfg.write_text(json.dumps(config(seed, args.slides)))
            la = os.getloadavg()[0]
            res = generate(
                str(cfg), out / f"{kind}-{r}.zarr", workers=int(kind[1]), progress=False, log=_quiet
            )
            row = {k: res[k] for k in ("wall_s", "simulate_s", "write_s")}
            row["slides"] = 7 * args.slides
            row["slides_per_s"] = row["slides"] / row["wall_s"]
            row["load1"] = la
            rows[kind].append(row)
            load.append(os.getloadavg()[0])
            print(
                f"  {kind} run {r}: {row['slides']} slides in {row['wall_s']:.2f} s = "
                f"{row['slides_per_s']:.3f}/s (load {la:.2f})",
                file=sys.stderr,
                flush=True,
            )

    def med(kind: str, key: str) -> float:
        return statistics.median(x[key] for x in rows[kind])

    r1, r2 = med("w1", "slides_per_s"), med("w2", "slides_per_s")
    # overhead inside the 1-worker runs: everything but simulation, and writes + checksums
    e2e = [x["wall_s"] / x["simulate_s"] - 1 for x in rows["w1"]]
    write_frac = [x["write_s"] / x["simulate_s"] for x in rows["w1"]]

    memory = []
    for n in (int(s) for s in args.sizes.split(",")):
        p = subprocess.run(
            [sys.executable, __file__, "--memory-child", str(out / f"mem-{n}.zarr"), str(n)],
            capture_output=True,
            text=True,
            env=dict(os.environ),
            check=True,
        )
        memory.append(json.loads(p.stdout))
        load.append(os.getloadavg()[0])
        print(f"  memory: {memory[-1]}", file=sys.stderr, flush=True)

    write_frac_m, e2e_m = statistics.median(write_frac), statistics.median(e2e)
    doc = {
        "cores": os.cpu_count(),
        "load_average_1min": {
            "min": min(load),
            "median": statistics.median(load),
            "max": max(load),
        },
        "slides_per_run": 7 * args.slides,
        "repeats": args.repeats,
        "slides_per_s_1_worker": round(r1, 4),
        "slides_per_s_2_workers": round(r2, 4),
        "speedup_2_vs_1": round(r2 / r1, 3),
        "s_per_slide_1_worker": round(1 / r1, 3),
        "store_overhead_end_to_end": round(statistics.median(e2e), 4),
        "store_overhead_write_vs_simulate": round(statistics.median(write_frac), 5),
        "memory": memory,
        "runs": rows,
    }
    (out / "generate.json").write_text(json.dumps(doc, indent=1))
    m0, m1 = memory[0], memory[-1]
    print(
        f"generate benchmark ({doc['cores']} cores, load average {min(load):.2f}-{max(load):.2f})"
    )
    print(f"  finger7 slides (0.87 s window), {7 * args.slides} per run, median of {args.repeats}")
    print(f"  1 worker : {r1:.3f} slides/s ({1 / r1:.2f} s a slide)")
    print(f"  2 workers: {r2:.3f} slides/s   speed-up {r2 / r1:.2f}x (goal >= 1.8x)")
    print(
        f"  store overhead (1 worker): writes + checksums {100 * write_frac_m:.2f}% of the "
        f"simulation time (goal < 5%); the whole run {100 * e2e_m:.2f}% over it"
    )
    print(
        f"  parent memory: {m0['slides']} slides -> RSS {m0['rss_end_mb']} MB (peak "
        f"{m0['peak_mb']}), {m1['slides']} slides -> RSS {m1['rss_end_mb']} MB (peak "
        f"{m1['peak_mb']}); store {m0['store_mb']} / {m1['store_mb']} MB"
    )
    print(f"  written: {out / 'generate.json'}")


if __name__ == "__main__":
    main()
