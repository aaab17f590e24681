"""The ``sim-tactile`` command line: a thin layer over the package, one module per group of
commands (plates, sim, tasks, data, bench).

Every command takes ``--json``: stdout then carries one JSON document and nothing else;
progress and logs go to stderr. A failure exits non-zero with a one-line reason on stderr
(``--debug`` shows the traceback). SIGTERM stops a command as Ctrl-C does: its workers stop,
its store records the interrupted run, and it exits with 143.
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import warnings
from collections.abc import Iterator, Sequence

from .. import __version__
from ..errors import SimTactileError, Terminated, os_error_message
from . import bench, check, data, plates, sim, tasks
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
#: An error the package did not expect (a bug): exit status, and what the line asks for.
EXIT_INTERNAL = 3
EXIT_INTERRUPTED = 130


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="sim-tactile", description=DESCRIPTION, epilog=EPILOG)
    p.add_argument(
        "--version",
        action="version",
        version=f"sim-tactile {__version__}",
        help="Print the version and exit.",
    )
    p.add_argument(
        "--debug",
        action="store_true",
        help="Show the traceback of an error instead of its one-line reason.",
    )
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for group in (tasks, check, plates, sim, data, bench):
        group.add_parsers(sub)
    _sentence_help(p)
    return p


def documented_parser() -> argparse.ArgumentParser:
    """:func:`build_parser` with every help text written out (some are computed only when a
    help is printed), for the manual's command-line page."""
    p = build_parser()
    stack = [p]
    while stack:
        parser = stack.pop()
        for action in parser._actions:
            if callable(action.help):
                action.help = action.help()
            if isinstance(action, argparse._SubParsersAction):
                stack.extend(action.choices.values())
    return p


def _raise_terminated(signum, frame) -> None:
    raise Terminated(signum)


@contextlib.contextmanager
def _signals() -> Iterator[None]:
    """SIGTERM raises :class:`~sim_tactile.errors.Terminated` (a KeyboardInterrupt) in the
    main thread for as long as a command runs."""
    try:
        old = signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:  # not the main thread (an embedding program): leave it be
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _one_line_warnings(message, category, filename, lineno, line=None) -> str:
    return f"sim-tactile: warning: {message}\n"


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
    debug = bool(getattr(args, "debug", False))
    if not debug:
        warnings.formatwarning = _one_line_warnings
    with _signals():
        try:
            return int(args.func(args) or 0)
        except Terminated as exc:
            log(f"sim-tactile: stopped by signal {signal.Signals(exc.signum).name}")
            return 128 + exc.signum
        except KeyboardInterrupt:
            log("sim-tactile: interrupted")
            return EXIT_INTERRUPTED
        except BrokenPipeError:  # e.g. `sim-tactile plates list | head`
            sys.stderr.close()
            return 0
        except SimTactileError as exc:
            if debug:
                raise
            log(f"sim-tactile: error: {exc}")
            return EXIT_ERROR
        except OSError as exc:  # the machine's fault: a full disk, a read-only folder
            if debug:
                raise
            where = exc.filename if exc.filename is not None else "a file"
            log(f"sim-tactile: error: {os_error_message(exc, where, 'using')}")
            return EXIT_ERROR
        except MemoryError:
            if debug:
                raise
            log("sim-tactile: error: out of memory (a smaller input, or fewer --workers)")
            return EXIT_ERROR
        except Exception as exc:  # a bug: one line, and how to see more
            if debug:
                raise
            text = str(exc).splitlines()[0] if str(exc) else ""
            log(
                f"sim-tactile: internal error: {type(exc).__name__}: {text} (run again with "
                "--debug for the traceback, and please report it)"
            )
            return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
