"""The ``sim-tactile`` command line: a thin layer over the package, one module per group of
commands (plates, sim, tasks, data, bench).

Every command takes ``--json``: stdout then carries one JSON document and nothing else;
progress and logs go to stderr. A failure exits non-zero with a one-line reason on stderr.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from .. import __version__
from ..errors import SimTactileError
from . import bench, data, plates, sim, tasks
from ._common import log

EXIT_ERROR = 2


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="sim-tactile", description=__doc__.splitlines()[0])
    p.add_argument("--version", action="version", version=f"sim-tactile {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    for group in (plates, sim, tasks, data, bench):
        group.add_parsers(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except SimTactileError as exc:
        log(f"sim-tactile: error: {exc}")
        return EXIT_ERROR
    except BrokenPipeError:  # e.g. `sim-tactile plates list | head`
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        log("sim-tactile: interrupted")
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
