"""The ``sim-tactile`` command line: a thin layer over the package, one module per group of
commands (plates, sim, tasks, data, bench).

Every command takes ``--json``: stdout then carries one JSON document and nothing else;
progress and logs go to stderr. A failure exits non-zero with a one-line reason on stderr
(``--debug`` shows the traceback). SIGTERM stops a command as Ctrl-C does: its workers stop,
its store records the interrupted run, and it exits with 143 (Ctrl-C: 130). An interrupt
that surfaces as another exception (through a compiled kernel, :mod:`sim_tactile.interrupts`)
is reported as the interrupt.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import warnings
from collections.abc import Sequence

# The command line never renders: MuJoCo's OpenGL back-end (glfw, cffi and pycparser, some
# 50 ms of every command's start-up) is left unloaded, unless the environment names one.
os.environ.setdefault("MUJOCO_GL", "disable")
# A command's parallelism is its worker processes (``--workers``), each on one core, and the
# slides already run BLAS on one thread. OpenBLAS's idle threads busy-wait for about 0.1 s
# after the library loads and after each threaded call: CPU time a one-core worker pays, some
# 0.15 s at start-up alone. So the command line starts OpenBLAS with one thread, unless the
# environment names a thread count through one of the variables OpenBLAS reads, in its order
# of precedence: ``OPENBLAS_NUM_THREADS``, ``GOTO_NUM_THREADS``, ``OMP_NUM_THREADS``.
os.environ.setdefault(
    "OPENBLAS_NUM_THREADS",
    os.environ.get("GOTO_NUM_THREADS") or os.environ.get("OMP_NUM_THREADS") or "1",
)

from .. import __version__
from ..errors import SimTactileError, Terminated, os_error_message
from ..interrupts import handled, interrupt_of
from . import bench, check, data, kernels, plates, sim, tasks
from ._common import compile_notice, log

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
    for group in (tasks, check, plates, sim, data, bench, kernels):
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
    notice = compile_notice() if getattr(args, "compiles", False) else contextlib.nullcontext()
    with handled(), notice:
        try:
            return int(args.func(args) or 0)
        except KeyboardInterrupt as exc:
            return _stopped(exc)
        except Exception as exc:
            # a signal that surfaced through a compiled kernel (a SystemError with the
            # interrupt in its chain), or any failure after a signal came: the signal
            stop = interrupt_of(exc)
            if stop is not None:
                return _stopped(stop)
            if debug and not isinstance(exc, BrokenPipeError):
                raise
            return _failed(exc)


def _stopped(exc: KeyboardInterrupt) -> int:
    """The one line and exit status of a command stopped by a signal or Ctrl-C. The store's
    writes that the signal cut short leave coroutines of zarr's that were never awaited;
    their warnings at exit would follow the one line, and say nothing the line does not."""
    warnings.filterwarnings("ignore", r"coroutine .* was never awaited", RuntimeWarning)
    if isinstance(exc, Terminated):
        log(f"sim-tactile: stopped by signal {signal.Signals(exc.signum).name}")
        return 128 + exc.signum
    log("sim-tactile: interrupted")
    return EXIT_INTERRUPTED


def _failed(exc: Exception) -> int:
    """The one line and exit status of a command that failed with ``exc``."""
    if isinstance(exc, BrokenPipeError):  # e.g. `sim-tactile plates list | head`
        sys.stderr.close()
        return 0
    if isinstance(exc, SimTactileError):
        log(f"sim-tactile: error: {exc}")
        return EXIT_ERROR
    if isinstance(exc, OSError):  # the machine's fault: a full disk, a read-only folder
        where = exc.filename if exc.filename is not None else "a file"
        log(f"sim-tactile: error: {os_error_message(exc, where, 'using')}")
        return EXIT_ERROR
    if isinstance(exc, MemoryError):
        log("sim-tactile: error: out of memory (a smaller input, or fewer --workers)")
        return EXIT_ERROR
    text = str(exc).splitlines()[0] if str(exc) else ""  # a bug: one line, and how to see more
    log(
        f"sim-tactile: internal error: {type(exc).__name__}: {text} (run again with --debug "
        "for the traceback, and please report it)"
    )
    return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
