"""Throughput of every task scene as a data set is made: the whole-slide real-time factor per
core, and where a slide's time goes.

    python perf/bench_throughput.py [--scenes finger7-v1,...] [--slides 4] [--rounds 3]
        [--against PATH] [--json]

A scene is a simulated task (every ``-v1`` and ``-v2``, each sensor of ``textures20``). For
each, one process simulates ``--slides`` of the task's slides (the first slide of plates
spread over the task's list), after a warm-up slide of each of those plates that is not
counted, with one artefact cache as ``generate`` has (plates and skin matrices kept between
slides, no slide read from the slide cache): the steady state of a data set, whose workers
make tens of slides of each plate. The real-time factor per core is the simulated seconds over the process's
CPU seconds for those slides (CPU time, not wall: the machine is shared).

``--breakdown`` profiles the same slides again (cProfile; its overhead inflates the total,
so the shares are read, not the seconds) and sorts each function's own time into: setup (building
the scene, the skin and its matrices, choosing the fidelity), collider, solve (the skin's
contact problem and the held step), readout (taxel loads, sample averages, transducer),
MuJoCo (its step and forward calls) and Python (the rest).

``--against PATH`` runs each scene alternately with this checkout and the one at PATH
(another commit of the project, ``git worktree add``), ``--rounds`` times each, A B A B, and
reports the median real-time factor of each side and their ratio.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import pstats
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Buckets of the breakdown: the first whose pattern is in a profiled function's file path
#: or name takes its own time (checked in this order).
BUCKETS = (
    ("MuJoCo", ("mujoco._functions", "mj_step", "mj_forward", "mj_collision", "mj_kinematics")),
    (
        "setup",
        (
            "scene/model.py",
            "plates/",
            "fidelity.py",
            "measured_errors.py",
            "scene/elastic.py",
            "scene/layered.py",
            "scene/nodes.py",
            "cache.py",
            "skin.py:make_skin",
            "_cached_dense",
            "anchored.py:__init__",
            "lattice_compliance",
            "build_scene",
            "from_xml",
            "MjModel",
            "compile",
        ),
    ),
    ("collider", ("collide.py", "anchored_lines.py", "clipped.py:heights")),
    ("solve", ("contact/", "held.py", "skin.py", "anchored.py", "clipped.py", "rig_sim.py:_face")),
    (
        "readout",
        ("sensors/", "SampleAverager", "simulate.py:add", "simulate.py:end_sample", "micro.py"),
    ),
)


def scene_ids() -> list[str]:
    from sim_tactile.slides import SlideSet
    from sim_tactile.tasks import get_task, task_ids

    return [t for t in task_ids() if isinstance(get_task(t).get_data, SlideSet)]


def scene_jobs(task_id: str, n: int):
    """The warm-up slides and ``n`` measured slides: plates spread over the task's list, the
    second slide of each to warm the process up (its skin computed or read, its kernels
    compiled), then the first slide of each, measured: as in a data set, where each worker
    makes tens of slides of a plate after its first."""
    from sim_tactile.tasks import get_task

    ss = get_task(task_id).get_data
    jobs = ss.jobs(seed=0, quick=False)
    per = len(jobs) // len(ss.plates)
    picks = sorted({round(i * (len(ss.plates) - 1) / max(1, n - 1)) for i in range(n)})
    return [jobs[p * per + 1] for p in picks], [jobs[p * per] for p in picks]


def measure(task_id: str, n: int, breakdown: bool) -> dict:
    """Simulate the scene's slides in this process; CPU seconds, simulated seconds, RTF; with
    ``breakdown``, the same slides again under the profiler (a fresh cache) for the shares."""
    warm, jobs = scene_jobs(task_id, n)
    cache = _fresh_cache()
    for job in warm:
        job.simulate(cache)
    cpu, sim, _ = _run(jobs, None, cache)
    out = {"scene": task_id, "slides": len(jobs), "sim_s": sim, "cpu_s": cpu, "rtf": sim / cpu}
    if breakdown:
        prof = cProfile.Profile()
        _run(jobs, prof, cache)
        out["breakdown"] = _buckets(prof)
    return out


def _fresh_cache():
    from sim_tactile.cache import ArtefactCache

    return ArtefactCache(tempfile.mkdtemp(prefix="bench-throughput-"))


def _run(jobs, prof, cache):
    cpu = sim = 0.0
    for job in jobs:
        t0 = time.process_time()
        if prof is not None:
            prof.enable()
        rec = job.simulate(cache).recording
        if prof is not None:
            prof.disable()
        cpu += time.process_time() - t0
        sim += float(rec.meta["sim_s"])
    return cpu, sim, prof


def _buckets(prof: cProfile.Profile) -> dict[str, float]:
    """Each bucket's share of the profiled own time."""
    st = pstats.Stats(prof)
    total = {name: 0.0 for name, _ in BUCKETS} | {"Python": 0.0}
    for (file, _line, func), (_cc, _nc, tt, _ct, _callers) in st.stats.items():
        where = f"{file}:{func}"
        for name, pats in BUCKETS:
            if any(p in where for p in pats):
                total[name] += tt
                break
        else:
            total["Python"] += tt
    s = sum(total.values()) or 1.0
    return {k: round(v / s, 3) for k, v in total.items()}


def _child(checkout: Path, scene: str, n: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", scene, "--slides", str(n)]
    p = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    if p.returncode != 0:
        raise RuntimeError(f"{scene} at {checkout}: {p.stderr.strip().splitlines()[-1:]}")
    return json.loads(p.stdout)


def _commit(checkout: Path) -> str:
    p = subprocess.run(
        ["git", "-C", str(checkout), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    )
    return p.stdout.strip() or str(checkout)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default=None, help="comma-separated task ids (default: all)")
    ap.add_argument("--slides", type=int, default=4, help="slides per scene (one per plate)")
    ap.add_argument("--rounds", type=int, default=3, help="alternating runs of each side")
    ap.add_argument("--against", default=None, help="another checkout to run side by side")
    ap.add_argument("--breakdown", action="store_true", help="where the time goes (cProfile)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(measure(args.child, args.slides, False)))
        return 0
    scenes = args.scenes.split(",") if args.scenes else scene_ids()
    rows = []
    for scene in scenes:
        row = {"scene": scene}
        if args.against:
            sides = {"this": ROOT, "against": Path(args.against)}
            runs = {k: [] for k in sides}
            for _ in range(args.rounds):
                for k, path in sides.items():
                    runs[k].append(_child(path, scene, args.slides)["rtf"])
            row.update(
                rtf=statistics.median(runs["this"]),
                rtf_against=statistics.median(runs["against"]),
                ratio=statistics.median(
                    a / b for a, b in zip(runs["this"], runs["against"], strict=True)
                ),
                commits={"this": _commit(ROOT), "against": _commit(Path(args.against))},
            )
        else:
            row.update(measure(scene, args.slides, args.breakdown))
        rows.append(row)
        if not args.json:
            print(_line(row), flush=True)
    if args.json:
        print(json.dumps(rows, indent=1))
    return 0


def _line(r: dict) -> str:
    if "ratio" in r:
        c = r["commits"]
        return (
            f"| {r['scene']} | {r['rtf_against']:.2f} ({c['against']}) | {r['rtf']:.2f} "
            f"({c['this']}) | {r['ratio']:.2f}x |"
        )
    parts = (
        ""
        if "breakdown" not in r
        else " | " + ", ".join(f"{k} {100 * v:.0f}%" for k, v in r["breakdown"].items())
    )
    return f"| {r['scene']} | {r['slides']} | {r['sim_s']:.2f} s | {r['cpu_s']:.2f} s | {r['rtf']:.2f}{parts} |"


if __name__ == "__main__":
    sys.exit(main())
