"""The default fidelity's error against physics on every plate of every simulated task.

    python perf/physics_per_plate.py [--tasks finger7-v1,...] [--plates P,...]
        [--offsets 4] [--refine 1,2,4] [--json] [--ref-cache DIR]

``bench speed-error`` measures one plate per task (its bench scene) at every level; this
measures the level each task actually runs (``auto``: its node grid as ``choose_fidelity``
picks it for that plate) on each of the task's plates. For each plate, the task's sensor is
pressed with the task's force at a few pad offsets over the texture period; its taxel loads
are set against Tamaas's boundary-element half-space on a 0.0625 mm grid, read by the same
taxels (:mod:`sim_tactile.bench.physics`). Columns: the node grid, the relative norm over
offsets x taxels, the largest taxel difference in units of the largest reference load, and
how far the reference moves on a grid twice as coarse. ``--refine 1,2,4`` also measures the
node grid at 1/2 and 1/4 of auto's pitch in both directions (what it would take to get
within a given error; above 1200 nodes the solve is spectral). Where the grid that resolves
the features is more than 10% from the physics, auto takes the coarsest finer grid of the
table within 10% (the divisors it knows are ``measured_errors.REFINEMENTS``); the pitches
here are always divisions of that resolving grid.

``--write-table`` stores the rows in ``sim_tactile/sim/measured_errors.json`` (each keyed by
the scene and node grid, with the commit measured at), where ``auto`` finds its expected
error; a partial run (``--tasks``/``--plates``) replaces only the rows it measured.

``textures20-icub60-v1`` is left out unless named: its 36 x 26 mm pad needs a 90 mm
reference cell, about 10 minutes a plate. The references are kept in the package's cache
(``--ref-cache``), keyed by their content and code, so measuring another grid on a plate
takes seconds. Tamaas is a test extra.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

from sim_tactile.bench import physics
from sim_tactile.cache import default_root
from sim_tactile.plates import get_plate, surface_of
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.plan import measured_errors
from sim_tactile.sim.plan.fidelity import choose_fidelity
from sim_tactile.sim.plan.lattices import anchor_refusals
from sim_tactile.slides import SlideSet
from sim_tactile.tasks import get_task, task_ids

SLOW = ("textures20-icub60-v1", "textures20-icub60-v2")


def measure(
    task_id: str,
    n_offsets: int,
    refine=(1,),
    plates=None,
    log=print,
    clipped=False,
    anchored=(),
    ref_cache=None,
) -> list[dict]:
    """The rows of one task: auto's resolving grid at 1/f of its pitch for f in ``refine``
    (``clipped``: its patches clipped), or, with ``anchored`` ((wall, x, y) in m), the
    lattices anchored to the walls, on the plates they serve."""
    ss = get_task(task_id).get_data
    sensor = get_sensor(ss.sensor)
    proto = ss.protocol.at_rate(sensor.layout.rate_hz)
    rows = []
    for name in ss.plates:
        if plates and name not in plates:
            continue
        plate = get_plate(name)
        if clipped and not surface_of(plate).has_walls:
            continue
        if anchored and anchor_refusals(plate, sensor.layout, "L1", sensor.finger):
            continue
        # the grid that resolves the features, before auto refines it from this table
        fid = choose_fidelity(plate, sensor.layout, sensor.finger, proto, "auto", refine=False)
        t0 = time.perf_counter()
        ref = physics.reference(plate, sensor, proto.force_n, n_offsets, ref_cache)
        grids = (
            [(w, px, py, None) for w, px, py in anchored]
            if anchored
            else [
                (None, fid.pitch_m / f, None if fid.pitch_y_m is None else fid.pitch_y_m / f, f)
                for f in refine
            ]
        )
        for k, (wall, px, py, f) in enumerate(grids):
            t1 = time.perf_counter()
            loads = physics.configuration_loads(
                ref, plate, sensor, proto.force_n, fid.level, px, py, clipped, wall
            )
            norm, worst = ref.error(loads)
            r = {
                "task": task_id,
                "plate": name,
                "sensor": ss.sensor,
                "level": fid.level,
                "force_n": proto.force_n,
                "refine": f,
                "pitch_m": px,
                "pitch_y_m": py,
                "key": measured_errors.grid_key(
                    plate, sensor.layout, sensor.finger, fid.level, px, py, clipped, wall
                ),
                "clipped": clipped,
                "wall_m": wall,
                "error_vs_physics": norm,
                "largest_taxel": worst,
                "ref_change": ref.ref_change,
                "wall_s": time.perf_counter() - (t0 if k == 0 else t1),
            }
            rows.append(r)
            log(
                f"{task_id:24s} {name:34s} {_grid(r):>14s} {100 * norm:6.1f}% "
                f"{100 * worst:6.1f}% {100 * ref.ref_change:5.1f}% {r['wall_s']:5.0f} s"
            )
    return rows


def _grid(r: dict) -> str:
    x = r["pitch_m"] * 1e3
    g = f"{x:.3g} mm" if r["pitch_y_m"] is None else f"{x:.3g} x {r['pitch_y_m'] * 1e3:.3g} mm"
    if r.get("wall_m") is not None:
        return f"{r['wall_m'] * 1e3:.3g}/" + g + " anch"
    return g + (" clip" if r.get("clipped") else "")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", default=None, help="comma-separated task ids")
    ap.add_argument("--plates", default=None, help="comma-separated plates (default: all)")
    ap.add_argument("--offsets", type=int, default=4)
    ap.add_argument(
        "--refine", default="1", help="comma-separated divisors of auto's node pitch (default 1)"
    )
    ap.add_argument("--json", action="store_true")
    ap.add_argument(
        "--clipped",
        action="store_true",
        help="measure the grids with patches clipped at the walls and taxel edges (plates with "
        "box walls only)",
    )
    ap.add_argument(
        "--anchored",
        default=None,
        help="measure lattices anchored to the walls instead: comma-separated "
        "wall:x:y cell sizes in mm (e.g. 0.5:2:2; box plates and surface taxels only)",
    )
    ap.add_argument(
        "--write-table", action="store_true", help="store the rows where auto finds them"
    )
    ap.add_argument(
        "--ref-cache",
        default=str(default_root() / "physics-ref"),
        help="where the references are kept between runs, keyed by their content and code "
        "(default: the package's cache; 'none' to compute them each time)",
    )
    args = ap.parse_args()
    missing = physics.tamaas_missing()
    if missing:
        print(missing, file=sys.stderr)
        return 2
    sims = [t for t in task_ids() if isinstance(get_task(t).get_data, SlideSet)]
    tasks = args.tasks.split(",") if args.tasks else [t for t in sims if t not in SLOW]
    log = (lambda m: print(m, file=sys.stderr)) if args.json else print
    if not args.json:
        print(f"{'task':24s} {'plate':34s} {'nodes':>14s}  error  largest  ref   wall")
    refine = tuple(int(x) for x in args.refine.split(","))
    plates = args.plates.split(",") if args.plates else None
    anchored = tuple(
        tuple(float(v) * 1e-3 for v in c.split(":")) for c in (args.anchored or "").split(",") if c
    )
    ref_cache = None if args.ref_cache == "none" else Path(args.ref_cache)
    rows = [
        r
        for t in tasks
        for r in measure(t, args.offsets, refine, plates, log, args.clipped, anchored, ref_cache)
    ]
    if args.json:
        print(json.dumps(rows, indent=1))
    if args.write_table:
        write_table(rows, measured_errors.TABLE)
    return 0


def commit() -> str:
    """The commit measured at (with ``+`` when the work tree differs from it)."""
    root = Path(__file__).resolve().parents[1]
    git = ["git", "-C", str(root)]
    head = subprocess.run([*git, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    dirty = subprocess.run(
        [*git, "status", "--porcelain", "--", "sim_tactile"], capture_output=True, text=True
    )
    return head.stdout.strip() + ("+" if dirty.stdout.strip() else "")


def write_table(rows: list[dict], path: Path, at: str | None = None) -> None:
    """Store ``rows`` in ``path``, replacing the rows of the same task, plate and grid."""
    at = at or commit()
    old = json.loads(path.read_text())["rows"] if path.is_file() else []
    new = [
        {
            **{k: r[k] for k in KEEP},
            **({"clipped": True} if r.get("clipped") else {}),
            **({"wall_m": r["wall_m"]} if r.get("wall_m") is not None else {}),
            "commit": at,
        }
        for r in rows
    ]
    keys = {r["key"] for r in new}
    merged = [r for r in old if r["key"] not in keys] + new
    merged.sort(
        key=lambda r: (
            r["task"],
            r["plate"],
            r.get("clipped", False),
            r.get("wall_m") is not None,
            -(r.get("wall_m") or 0.0),
            -r["pitch_m"],
        )
    )
    doc = {
        "about": "error of the taxel loads against Tamaas (0.0625 mm, cell faces on the grid), static presses at "
        "4 pad offsets; written by perf/physics_per_plate.py --write-table",
        "rows": merged,
    }
    path.write_text(json.dumps(doc, indent=1) + "\n")


KEEP = (
    "key",
    "task",
    "plate",
    "sensor",
    "level",
    "force_n",
    "pitch_m",
    "pitch_y_m",
    "error_vs_physics",
    "largest_taxel",
    "ref_change",
)


if __name__ == "__main__":
    sys.exit(main())
