"""The ``sim-tactile`` command line: a thin layer over the package.

Every command takes ``--json``: stdout then carries one JSON document and nothing else;
progress and logs go to stderr. A failure exits non-zero with a one-line reason on stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from . import __version__
from .errors import SimTactileError

EXIT_ERROR = 2


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _emit(args: argparse.Namespace, payload: object, text: Callable[[], str]) -> None:
    if args.json:
        json.dump(payload, sys.stdout, indent=2, sort_keys=False)
        sys.stdout.write("\n")
    else:
        print(text())


# ---------------------------------------------------------------- plates
def _plate_rows():
    from .plates import get_plate, preset_names

    for name in preset_names():
        yield get_plate(name)


def cmd_plates_list(args: argparse.Namespace) -> int:
    plates = list(_plate_rows())
    rows = [
        {"name": p.name, "family": p.family, "params": p.params(), "hash": p.hash} for p in plates
    ]

    def text() -> str:
        lines = [f"{'name':36s} {'family':10s} hash"]
        lines += [f"{r['name']:36s} {r['family']:10s} {r['hash']}" for r in rows]
        return "\n".join(lines)

    _emit(args, rows, text)
    return 0


def _build_table(results) -> str:
    lines = [f"{'plate':36s} {'geoms':22s} {'cached':7s} {'wall_s':>7s}  files"]
    for r in results:
        geoms = ",".join(f"{k}:{v}" for k, v in sorted(r.geoms.items()))
        cached = "yes" if all(r.cached.values()) else "no"
        lines.append(
            f"{r.plate.name:36s} {geoms:22s} {cached:7s} {r.wall_s:7.2f}  {r.files['stl'].parent}/{r.plate.slug}.*"
        )
    return "\n".join(lines)


def cmd_plates_build(args: argparse.Namespace) -> int:
    from .errors import ConfigError
    from .plates import build, preset_names

    if args.all == bool(args.name):
        raise ConfigError("plates build: give a plate NAME or --all")
    names = preset_names() if args.all else [args.name]
    results = []
    for n in names:
        r = build(n, args.out)
        _log(
            f"built {n} in {r.wall_s:.2f} s ({'cache hit' if all(r.cached.values()) else 'built'})"
        )
        results.append(r)
    if args.all:
        _emit(args, [r.to_json() for r in results], lambda: _build_table(results))
    else:
        _emit(args, results[0].to_json(), lambda: _build_table(results))
    return 0


# ---------------------------------------------------------------- demo
def cmd_demo(args: argparse.Namespace) -> int:
    """The most complete job that exists so far: build every preset plate."""
    from .plates import build, preset_names

    out = Path(args.out)
    _log(
        f"sim-tactile demo: building all {len(preset_names())} preset plates into {out}/ "
        "(STL, STEP, MJCF, PNG; cached after the first run)"
    )
    t0 = time.perf_counter()
    results = [build(n, out) for n in preset_names()]
    wall = time.perf_counter() - t0
    payload = {
        "what": "built every preset plate",
        "out": str(out),
        "plates": [r.to_json() for r in results],
        "wall_s": round(wall, 3),
    }
    _emit(
        args,
        payload,
        lambda: _build_table(results) + f"\n\n{len(results)} plates in {wall:.1f} s -> {out}/",
    )
    return 0


# ---------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="sim-tactile", description=__doc__.splitlines()[0])
    p.add_argument("--version", action="version", version=f"sim-tactile {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    def add(parent, name: str, func, help: str) -> argparse.ArgumentParser:
        sp = parent.add_parser(name, help=help, description=help)
        sp.add_argument("--json", action="store_true", help="print one JSON document on stdout")
        sp.set_defaults(func=func)
        return sp

    plates = sub.add_parser("plates", help="list and build the textured plates")
    psub = plates.add_subparsers(dest="plates_command", required=True)
    add(psub, "list", cmd_plates_list, "list the preset plates")
    b = add(psub, "build", cmd_plates_build, "build a plate's STL, STEP, MJCF and preview PNG")
    b.add_argument("name", nargs="?", help="preset name, e.g. finger7/ridges-4")
    b.add_argument("--all", action="store_true", help="build every preset")
    b.add_argument("--out", required=True, help="output directory")

    d = add(sub, "demo", cmd_demo, "run the main demo job")
    d.add_argument("--out", default="demo-out", help="output directory (default: demo-out)")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except SimTactileError as exc:
        _log(f"sim-tactile: error: {exc}")
        return EXIT_ERROR
    except BrokenPipeError:  # e.g. `sim-tactile plates list | head`
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        _log("sim-tactile: interrupted")
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
