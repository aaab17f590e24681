"""``sim-tactile plates list`` and ``plates build``."""

from __future__ import annotations

import argparse

from ..errors import ConfigError
from ..tables import text_table
from ._common import (
    PLATE_FRAME_HELP,
    PLATE_HELP,
    add_command,
    add_group,
    emit,
    log,
    plate_of,
)


def cmd_plates_list(args: argparse.Namespace) -> int:
    from ..plates import get_plate, preset_names

    plates = [get_plate(name) for name in preset_names()]
    rows = [
        {"name": p.name, "family": p.family, "params": p.params(), "hash": p.hash} for p in plates
    ]
    table = [[r["name"], r["family"], r["hash"]] for r in rows]
    emit(args, rows, lambda: "\n".join(text_table(["name", "family", "hash"], table)))
    return 0


def _build_table(results) -> str:
    rows = []
    for r in results:
        geoms = ",".join(f"{k}:{v}" for k, v in sorted(r.geoms.items()))
        cached = "yes" if all(r.cached.values()) else "no"
        where = f"{r.files['stl'].parent}/{r.plate.slug}.*"
        rows.append([r.plate.name, geoms, cached, f"{r.wall_s:.2f}", where])
    return "\n".join(text_table(["plate", "geoms", "cached", "wall_s", "files"], rows, right=(3,)))


def cmd_plates_build(args: argparse.Namespace) -> int:
    from ..plates import build, preset_names

    if args.all == bool(args.name):
        raise ConfigError("plates build: give a plate NAME or --all")
    names = preset_names() if args.all else [plate_of(args.name, args.plate_frame)]
    results = []
    for n in names:
        r = build(n, args.out)
        for note in r.notes:
            log(f"note: {note}")
        log(
            f"built {r.plate.name} in {r.wall_s:.2f} s ({'cache hit' if all(r.cached.values()) else 'built'})"
        )
        results.append(r)
    payload = [r.to_json() for r in results] if args.all else results[0].to_json()
    emit(args, payload, lambda: _build_table(results))
    return 0


def add_parsers(sub) -> None:
    psub = add_group(sub, "plates", "List and build the textured plates.")
    add_command(psub, "list", cmd_plates_list, "List the preset plates with their family and hash.")
    b = add_command(
        psub,
        "build",
        cmd_plates_build,
        "Build a plate's STL and STEP (in mm), its MJCF (in m) and a preview PNG.",
    )
    b.add_argument("name", nargs="?", help=PLATE_HELP + " For example finger7/ridges-4.")
    b.add_argument("--plate-frame", default=None, help=PLATE_FRAME_HELP)
    b.add_argument("--all", action="store_true", help="Build every preset plate.")
    b.add_argument("--out", required=True, help="The folder to write the files into.")
