"""The route of one slide of a task down to its first held step: which of the package's
modules run code on the way, and how often the route enters each.

    python tools/trace_route.py [--task finger7-v1] [--plate finger7/ridges-4] [--json]

One fresh process makes the task's first quick slide of ``--plate`` (no cache), with a
profile hook (``sys.setprofile``) that stops at the first call of a held step's ``step``.
A module is on the route when one of its functions runs (a module's or a class's body run
by an import does not count). An *entry* is a call into a module from another one; the
planner's entries (``sim_tactile.sim.plan``) show how often the route comes back to it.

Run it on another commit of the project (``git worktree add``, then ``PYTHONPATH`` at it)
to compare two layouts on the same terms.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys

#: ``co_flags`` of a function's code (a module's or a class's body lacks it)
CO_OPTIMIZED = 0x1


class _Reached(Exception):
    """The first held step was called."""


def trace(task: str, plate: str) -> dict:
    from sim_tactile.tasks import get_task

    jobs = get_task(task).get_data.jobs(seed=0, quick=True)
    picked = [j for j in jobs if j.label.startswith(f"{plate} ")]
    if not picked:
        names = sorted({j.label.rsplit(" slide", 1)[0] for j in jobs})
        raise SystemExit(f"--plate {plate!r} is not in {task}'s quick run; valid: {names}")
    modules: set[str] = set()
    entries: collections.Counter[str] = collections.Counter()

    def hook(frame, event, arg):
        if event != "call":
            return
        name = frame.f_globals.get("__name__", "")
        if not name.startswith("sim_tactile"):
            return
        caller = frame.f_back.f_globals.get("__name__", "") if frame.f_back else ""
        if frame.f_code.co_flags & CO_OPTIMIZED:
            modules.add(name)
        if caller != name:
            entries[name] += 1
        owner = frame.f_locals.get("self")
        if frame.f_code.co_name == "step" and type(owner).__name__.endswith("HeldStep"):
            sys.setprofile(None)
            raise _Reached

    sys.setprofile(hook)
    try:
        picked[0].simulate()
    except _Reached:
        pass
    else:
        raise SystemExit(f"{plate}: the slide made no held step")
    finally:
        sys.setprofile(None)
    return {
        "task": task,
        "plate": plate,
        "modules": sorted(modules),
        "entries": dict(entries.most_common()),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", default="finger7-v1")
    ap.add_argument("--plate", default="finger7/ridges-4")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    out = trace(args.task, args.plate)
    if args.json:
        print(json.dumps(out, indent=1))
        return 0
    planner = {m: n for m, n in out["entries"].items() if ".sim.plan" in m}
    print(f"{args.task}, {args.plate}: {len(out['modules'])} modules on the route")
    print("planner entries: " + ", ".join(f"{m.rsplit('.', 1)[1]} {n}" for m, n in planner.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
