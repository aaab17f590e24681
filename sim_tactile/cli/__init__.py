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

DESCRIPTION = (
    "The sim-tactile command line of a physics-simulated benchmark for tactile texture perception. Build "
    "textured plates, simulate a finger sliding over them, and run the benchmark tasks of "
    "four papers with your own methods beside the built-in ones."
)
EPILOG = (
    "Every command takes --json, and then prints one JSON document on stdout; progress and "
    "logs go to stderr. Run 'sim-tactile COMMAND --help' for a command's options, and "
    "'sim-tactile tasks' for the tasks."
)
EXIT_ERROR = 2


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="sim-tactile", description=DESCRIPTION, epilog=EPILOG)
    p.add_argument(
        "--version",
        action="version",
        version=f"sim-tactile {__version__}",
        help="Print the version and exit.",
    )
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for group in (tasks, plates, sim, data, bench):
        group.add_parsers(sub)
    _sentence_help(p)
    return p


def _sentence_help(parser: argparse.ArgumentParser) -> None:
    """argparse's own ``-h`` says "show this help message and exit": a sentence, like ours."""
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            action.help = "Show this help and exit."
        if isinstance(action, argparse._SubParsersAction):
            for sp in action.choices.values():
                _sentence_help(sp)


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
