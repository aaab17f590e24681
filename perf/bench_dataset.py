"""A data set's cost through ``sim-tactile generate`` on one worker: the whole command, its
start-up and its worker's set-up counted, as a user pays it.

    python perf/bench_dataset.py CONFIG.toml [CONFIG.toml ...] [--against PATH]
        [--rounds 2] [--json]

Each run is a fresh process (``generate CONFIG --workers 1``) on a fresh cache that holds
the artefacts a data set reuses from earlier runs (plates' files and MJCF, skin matrices)
but no slide and no phase table: what a first ``generate`` of a new configuration pays on
an installation that has run before (its compiled kernels warm). The real-time factor per
core is the set's simulated seconds over the command's CPU seconds (user + system of the
process and its children: the machine is shared, wall time is not a measure).

The runs write and reuse Python's bytecode (``__pycache__``) as an installation does:
``PYTHONDONTWRITEBYTECODE``, where the shell sets it, is dropped from their environment (it
made every run compile the package's hundred modules from source, 0.13 s).

``--fixed`` measures a set's fixed cost instead (the command's start-up and a worker's
set-up, warm caches: its phase tables are kept too): each configuration, and the same with
twice its slides a plate, alternately; the fixed cost is ``2 T(N) - T(2N)`` of their median
CPU seconds, and a slide's own cost ``(T(2N) - T(N)) / N``, with the real-time factor per
core that it gives at scale (a slide's simulated seconds over its own cost). With
``--cold-tables`` every run makes its own phase tables (the warm-up's are removed, as for the
plain runs): the fixed cost then holds the tables the set's slides share (made once a plate
and force level, whatever the set's size), and a slide's own cost holds its own table where
it has one (a slide whose table depends on its offset): the cost a large set pays a slide.

``--build-kernels`` runs ``sim-tactile kernels build`` in each side after its warm-up run:
the kernels' code version follows every module a kernel module imports, so a side whose
modules were edited since its kernels were built would otherwise run on numba, whose start
(about 0.6 s a command) its every run would pay (an A/B of an edit in ``sim/`` read 0.99x
so where it was a gain). It adds a build (a minute or two) a side and configuration.

``--against PATH`` runs each configuration alternately with this checkout and the one at
PATH (another commit, ``git worktree add``), ``--rounds`` times each, A B A B, after one
warm-up run of each side (which fills that side's artefact cache and compiles its
kernels), and reports each side's median and the ratio of medians; the commits are printed
with the figures.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Entries of the cache that are results, not set-up: slides and phase tables (in either
#: layout, a file or an entry folder), removed from the seeded cache before a counted run.
RESULTS = ("slide.npz", "phase.npz")
#: The command line, run by this Python with the checkout first on its path.
CLI = (sys.executable, "-c", "import sys; from sim_tactile.cli import main; sys.exit(main())")


def commit(checkout: Path) -> str:
    out = subprocess.run(
        ["git", "-C", str(checkout), "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
        check=False,
    )
    return out.stdout.strip() or "unknown"


def _strip_results(cache: Path, results=RESULTS) -> None:
    for p in sorted(cache.rglob("*"), key=lambda q: len(q.parts), reverse=True):
        if any(r in p.name for r in results) and p.exists():
            if p.is_dir():
                shutil.rmtree(p)
            else:
                p.unlink()


def run_once(checkout: Path, config: Path, seed_cache: Path) -> dict:
    """One counted ``generate`` in a fresh process on a copy of ``seed_cache``."""
    work = Path(tempfile.mkdtemp(prefix="bench-dataset-"))
    try:
        cache = work / "cache"
        shutil.copytree(seed_cache, cache)
        env = _env(checkout, cache)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        proc = subprocess.run(
            [
                *CLI,
                "generate",
                str(config),
                "--out",
                str(work / "set.zarr"),
                "--workers",
                "1",
                "--json",
            ],
            env=env,
            capture_output=True,
            text=True,
            cwd=str(work),
            check=False,
        )
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if proc.returncode != 0:
            raise SystemExit(f"generate failed ({proc.returncode}): {proc.stderr[-2000:]}")
        out = json.loads(proc.stdout)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        return {
            "cpu_s": cpu,
            "wall_s": wall,
            "simulate_s": out.get("simulate_s"),
            "sim_s": _simulated_seconds(work / "set.zarr", checkout),
        }
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _simulated_seconds(store: Path, checkout: Path) -> float:
    """The store's slides times their window [s]."""
    code = (
        "import json, sys, zarr; r = zarr.open_group(sys.argv[1], mode='r'); "
        "a = dict(r.attrs); n = a.get('n_slides'); "
        "rate = a.get('rate_hz'); t = a.get('n_time'); "
        "print(json.dumps([n, rate, t]))"
    )
    env = dict(os.environ, PYTHONPATH=str(checkout))
    out = subprocess.run(
        [sys.executable, "-c", code, str(store)],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    try:
        n, rate, t = json.loads(out.stdout)
        return float(n) * float(t) / float(rate)
    except (ValueError, TypeError):
        return float("nan")


def _env(checkout: Path, cache: Path) -> dict:
    """A run's environment: this checkout first on the path, its own cache, bytecode kept."""
    env = dict(os.environ, SIM_TACTILE_CACHE=str(cache), PYTHONPATH=str(checkout))
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def doubled(config: Path, into: Path) -> Path:
    """``config`` with twice its slides a plate, written into the folder ``into``."""
    text = config.read_text()
    n = int(re.search(r"(?m)^slides_per_plate\s*=\s*(\d+)", text).group(1))
    out = into / f"{config.stem}-x2.toml"
    out.write_text(re.sub(r"(?m)^slides_per_plate\s*=\s*\d+", f"slides_per_plate = {2 * n}", text))
    return out


def _slides_in(config: Path) -> int:
    """The slides of a configuration: its plates times its slides a plate."""
    import tomllib

    data = tomllib.loads(config.read_text())
    return len(data["plates"]) * int(data["slides_per_plate"])


def seed(
    checkout: Path, config: Path, keep_tables: bool = False, build_kernels: bool = False
) -> Path:
    """A warm-up run's cache with its results removed (its slides; its phase tables too
    unless ``keep_tables``): the artefacts a counted run reuses; ``build_kernels``: the
    kernels it compiled then built ahead of time."""
    work = Path(tempfile.mkdtemp(prefix="bench-dataset-seed-"))
    env = _env(checkout, work / "cache")
    subprocess.run(
        [*CLI, "generate", str(config), "--out", str(work / "set.zarr"), "--workers", "1"],
        env=env,
        capture_output=True,
        text=True,
        cwd=str(work),
        check=True,
    )
    shutil.rmtree(work / "set.zarr", ignore_errors=True)
    if build_kernels:  # what the warm-up compiled, ahead of time (see the module docstring)
        subprocess.run(
            [*CLI, "kernels", "build"],
            env=env,
            capture_output=True,
            text=True,
            cwd=str(work),
            check=True,
        )
    _strip_results(work / "cache", RESULTS[:1] if keep_tables else RESULTS)
    return work / "cache"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("configs", nargs="+", type=Path)
    ap.add_argument("--against", type=Path, default=None, help="another checkout (B)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--fixed", action="store_true", help="measure the fixed cost (see above)")
    ap.add_argument(
        "--cold-tables", action="store_true", help="--fixed: each run makes its phase tables"
    )
    ap.add_argument(
        "--build-kernels",
        action="store_true",
        help="build each side's kernels ahead of time after its warm-up run (see above)",
    )
    args = ap.parse_args()
    sides = [("A", ROOT)] + ([("B", args.against.resolve())] if args.against else [])
    if args.fixed:
        return fixed_costs(args, sides)
    rows = []
    for config in args.configs:
        config = config.resolve()
        seeds = {name: seed(path, config, build_kernels=args.build_kernels) for name, path in sides}
        runs = {name: [] for name, _ in sides}
        for _ in range(args.rounds):
            for name, path in sides:
                runs[name].append(run_once(path, config, seeds[name]))
        for s in seeds.values():
            shutil.rmtree(s.parent, ignore_errors=True)
        row = {"config": config.name}
        for name, path in sides:
            rs = runs[name]
            sim = rs[0]["sim_s"]
            cpu = statistics.median(r["cpu_s"] for r in rs)
            row[name] = {
                "commit": commit(path),
                "sim_s": sim,
                "cpu_s": round(cpu, 2),
                "wall_s": round(statistics.median(r["wall_s"] for r in rs), 2),
                "rtf_per_core": round(sim / cpu, 2),
                "runs_cpu_s": [round(r["cpu_s"], 2) for r in rs],
            }
        if "B" in row:
            row["speed_up"] = round(row["B"]["cpu_s"] / row["A"]["cpu_s"], 2)
        rows.append(row)
        if not args.json:
            line = f"{config.name}: " + "; ".join(
                f"{n} {row[n]['commit']} RTF/core {row[n]['rtf_per_core']} "
                f"({row[n]['sim_s']:.1f} s simulated, CPU {row[n]['runs_cpu_s']})"
                for n, _ in sides
            )
            if "speed_up" in row:
                line += f"; A is {row['speed_up']}x B"
            print(line, flush=True)
    if args.json:
        print(json.dumps(rows, indent=1))
    return 0


def fixed_costs(args, sides) -> int:
    """``--fixed``: each configuration and its double, A B A B; the fixed cost."""
    rows = []
    for config in args.configs:
        config = config.resolve()
        tmp = Path(tempfile.mkdtemp(prefix="bench-dataset-x2-"))
        both = {"N": config, "2N": doubled(config, tmp)}
        # one warm cache a side, from the double: its tables and artefacts serve both sets
        keep = not args.cold_tables
        seeds = {
            name: seed(path, both["2N"], keep_tables=keep, build_kernels=args.build_kernels)
            for name, path in sides
        }
        runs = {(name, k): [] for name, _ in sides for k in both}
        for _ in range(args.rounds):
            for name, path in sides:
                for k, c in both.items():
                    runs[name, k].append(run_once(path, c, seeds[name]))
        for s in seeds.values():
            shutil.rmtree(s.parent, ignore_errors=True)
        shutil.rmtree(tmp, ignore_errors=True)
        row = {"config": config.name}
        for name, path in sides:
            t1 = statistics.median(r["cpu_s"] for r in runs[name, "N"])
            t2 = statistics.median(r["cpu_s"] for r in runs[name, "2N"])
            n = runs[name, "N"][0]["sim_s"]
            slides = _slides_in(config)
            own = (t2 - t1) / slides
            row[name] = {
                "commit": commit(path),
                "cpu_s": round(t1, 3),
                "cpu_2n_s": round(t2, 3),
                "fixed_s": round(2 * t1 - t2, 3),
                "slides": slides,
                "slide_cpu_ms": round(1e3 * own, 2),
                "rtf_per_core_at_scale": round(n / slides / own, 1) if own > 0 else None,
                "runs_cpu_s": [round(r["cpu_s"], 2) for r in runs[name, "N"]],
                "runs_cpu_2n_s": [round(r["cpu_s"], 2) for r in runs[name, "2N"]],
                "sim_s": n,
            }
        rows.append(row)
        if not args.json:
            print(
                f"{config.name}: "
                + "; ".join(
                    f"{k} {row[k]['commit']} fixed cost {row[k]['fixed_s']:.2f} s, a slide's "
                    f"own {row[k]['slide_cpu_ms']:.1f} ms (RTF/core at scale "
                    f"{row[k]['rtf_per_core_at_scale']}; CPU {row[k]['runs_cpu_s']} for the "
                    f"set, {row[k]['runs_cpu_2n_s']} for its double)"
                    for k, _ in sides
                ),
                flush=True,
            )
    if args.json:
        print(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
