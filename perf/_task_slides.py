"""A task's own slides, plate by plate, for the per-plate benches (``bench_every_plate.py``,
``bench_solver.py``): the command line's ``--scene``, ``--plates``, ``--slides`` and
``--json``, and the slides they name."""

from __future__ import annotations

import argparse
from collections.abc import Iterator
from dataclasses import replace


def add_arguments(ap: argparse.ArgumentParser, slides: str, scene: str | None = None) -> None:
    """The options that name a scene's slides (``slides``: the default indices; ``scene``:
    the default scene, else it must be named)."""
    ap.add_argument("--scene", required=scene is None, default=scene, help="a simulated task id")
    ap.add_argument("--plates", default=None, help="comma-separated plate names (default: all)")
    ap.add_argument("--slides", default=slides, help="comma-separated slide indices per plate")
    ap.add_argument("--json", action="store_true")


def task_slides(args: argparse.Namespace) -> Iterator[tuple[str, int, object]]:
    """``(plate, index, slide)``: the full task's slides (seed 0) of each plate named (all,
    sorted, by default), at the indices named among that plate's slides, recording the
    ideal loads (a task's job is a :class:`~sim_tactile.sim.Slide`)."""
    from sim_tactile.tasks import get_task

    jobs = get_task(args.scene).get_data.jobs(seed=0, quick=False)
    names = sorted({j.plate.name for j in jobs})
    if args.plates:
        names = [p for p in args.plates.split(",") if p]
    for plate in names:
        mine = [j for j in jobs if j.plate.name == plate]
        for k in (int(s) for s in args.slides.split(",")):
            yield plate, k, replace(mine[k], ideal=True)
