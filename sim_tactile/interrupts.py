"""Signals are signals: an interrupt is reported as the interrupt, whatever surfaces.

A signal's Python handler runs between two bytecodes of the main thread. With one worker the
slides run in the command's own process, mostly inside compiled numba kernels; there the
handler runs when a kernel calls back into Python (numba's dispatcher rebuilding an
exception, for one), and the exception it raises comes out of the kernel as ``SystemError:
CPUDispatcher(...) returned a result with an exception set``, the interrupt only in its
chain. So:

- :func:`handled` installs the command's handlers: SIGTERM raises
  :class:`~sim_tactile.errors.Terminated`, SIGINT raises ``KeyboardInterrupt`` (where Python's
  own handler is in place), and each records the signal it received first;
- :func:`interrupt_of` finds the interrupt behind any exception: the exception itself, one
  in its chain (``__cause__``, ``__context__``), or, when the chain lost it, the signal that
  was received during the command;
- :func:`raise_pending` raises a received signal whose exception was swallowed on the way,
  at a point where the work can stop (between slides).
"""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator
from types import FrameType

from .errors import Terminated

#: The first signal received while :func:`handled` is in force (None: none).
_received: int | None = None


def received() -> int | None:
    """The signal received during the current command, if any."""
    return _received


def _on_signal(signum: int, frame: FrameType | None) -> None:
    global _received
    if _received is None:
        _received = signum
    raise _interrupt(signum)


def _interrupt(signum: int) -> KeyboardInterrupt:
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated(signum)


@contextlib.contextmanager
def handled() -> Iterator[None]:
    """For as long as a command runs: SIGTERM raises
    :class:`~sim_tactile.errors.Terminated`, SIGINT ``KeyboardInterrupt`` (unless it was set
    otherwise, e.g. ignored), and the signal is recorded for :func:`interrupt_of`. Outside
    the main thread (an embedding program) nothing is installed."""
    global _received
    _received = None
    try:
        old = {signal.SIGTERM: signal.signal(signal.SIGTERM, _on_signal)}
    except ValueError:  # not the main thread
        yield
        return
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        old[signal.SIGINT] = signal.signal(signal.SIGINT, _on_signal)
    try:
        yield
    finally:
        for signum, handler in old.items():
            signal.signal(signum, handler)
        _received = None


def interrupt_of(exc: BaseException) -> KeyboardInterrupt | None:
    """The interrupt that ``exc`` stands for: ``exc`` itself if it is one, the first
    ``KeyboardInterrupt`` in its chain, else the interrupt of the signal received during the
    command (:func:`handled`); None when there was no interrupt."""
    stack: list[BaseException | None] = [exc]
    seen: set[int] = set()
    while stack:
        e = stack.pop()
        if e is None or id(e) in seen:
            continue
        seen.add(id(e))
        if isinstance(e, KeyboardInterrupt):
            return e
        stack += [e.__context__, e.__cause__]
    return None if _received is None else _interrupt(_received)


def raise_pending() -> None:
    """Raise the interrupt of a signal received during the command (its exception was lost
    on the way, e.g. inside a compiled kernel); nothing if none was received."""
    if _received is not None:
        raise _interrupt(_received)


__all__ = ["handled", "interrupt_of", "raise_pending", "received"]
