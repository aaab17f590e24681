"""Time building every preset plate cold (empty cache) and from the cache, in one run.

    python perf/bench_plates.py [--json] [--repeats N]

Cold: a fresh temporary cache, so every STL, STEP, MJCF and PNG is made (CadQuery import
included once, as a user pays it). Cached: the same builds again, repeated; medians.
A cached build must not import cadquery; this script checks that in a subprocess.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()

    from sim_tactile.cache import ArtefactCache
    from sim_tactile.plates import build, preset_names

    names = preset_names()
    with tempfile.TemporaryDirectory() as d:
        cache = ArtefactCache(Path(d))
        t0 = time.perf_counter()
        cold = {n: build(n, cache=cache).wall_s for n in names}
        cold_total = time.perf_counter() - t0
        warm_totals = []
        warm = {n: [] for n in names}
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            for n in names:
                warm[n].append(build(n, cache=cache).wall_s)
            warm_totals.append(time.perf_counter() - t0)
        probe = subprocess.run(
            [
                sys.executable,
                "-c",
                "import sys; from pathlib import Path; from sim_tactile.cache import ArtefactCache;"
                "from sim_tactile.plates import build, preset_names;"
                f"[build(n, cache=ArtefactCache(Path({d!r}))) for n in preset_names()];"
                "print('cadquery' in sys.modules)",
            ],
            capture_output=True,
            text=True,
            check=True,
        )
    rows = [
        {"plate": n, "cold_s": round(cold[n], 4), "cached_s": round(statistics.median(warm[n]), 5)}
        for n in names
    ]
    doc = {
        "plates": len(names),
        "cold_total_s": round(cold_total, 2),
        "cached_total_s_median": round(statistics.median(warm_totals), 4),
        "speedup": round(cold_total / statistics.median(warm_totals), 1),
        "cache_hit_imports_cadquery": probe.stdout.strip() == "True",
        "rows": rows,
    }
    if args.json:
        print(json.dumps(doc, indent=2))
    else:
        print(f"{'plate':36s} {'cold [s]':>9s} {'cached [s]':>11s}")
        for r in rows:
            print(f"{r['plate']:36s} {r['cold_s']:9.3f} {r['cached_s']:11.5f}")
        print(
            f"\n{len(names)} plates: cold {doc['cold_total_s']} s, cached {doc['cached_total_s_median']} s "
            f"(median of {args.repeats}), {doc['speedup']}x; cache hit imports cadquery: "
            f"{doc['cache_hit_imports_cadquery']}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
