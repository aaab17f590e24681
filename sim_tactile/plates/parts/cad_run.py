"""Running :mod:`.cad_worker` under a time limit, and ending every process it started.

The worker runs in its own session (``start_new_session``); its output goes to a file, never
to a pipe, so that a process the user's script leaves behind (which would hold a pipe open)
cannot keep the caller waiting. When the worker ends, or at the limit, its whole session is
killed: the worker is stopped, then every process of its session, of its process group, and
every descendant of it (found through ``/proc`` on Linux, where the worker also makes itself
the reaper of its orphans, so that a grandchild that started a session of its own still
descends from it) is stopped, until no new one appears, and then all are killed. Where
``/proc`` is missing, the process group is killed.

It also holds the tolerances every CAD solid is tessellated with, a user's part in the worker
as a plate's STL (:mod:`sim_tactile.plates.make.cad`): they sit here, below both.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

#: STL tessellation: linear tolerance [mm] and angular tolerance [rad]. docs/physics.md: the
#: angular one controls curved features; 0.15 rad gives a sag of R (1 - cos 0.075) = 5.6 um
#: on a 2 mm hemisphere, the linear one caps it at 5 um.
STL_TOLERANCE_MM = 0.005
STL_ANGULAR_TOLERANCE_RAD = 0.15
#: How much of the worker's stderr is read back for its reason [bytes].
STDERR_TAIL_BYTES = 65536
#: Rounds of stopping new processes before the kill (each finds the children forked since).
_STOP_ROUNDS = 50


def _table() -> dict[int, tuple[int, int, int]]:
    """``pid -> (ppid, process group, session)`` of every process in ``/proc``."""
    out = {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", "rb") as fh:
                stat = fh.read()
        except OSError:
            continue  # it ended meanwhile
        rest = stat[stat.rindex(b")") + 2 :].split()  # after "pid (comm) "
        out[int(name)] = (int(rest[1]), int(rest[2]), int(rest[3]))
    return out


def _members(root: int, table: dict[int, tuple[int, int, int]]) -> set[int]:
    """``root``, the processes of its session and process group, and their descendants."""
    found = {pid for pid, (_, pgrp, sid) in table.items() if pid == root or root in (pgrp, sid)}
    children: dict[int, list[int]] = {}
    for pid, (ppid, _, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    todo = list(found)
    while todo:
        for child in children.get(todo.pop(), ()):
            if child not in found:
                found.add(child)
                todo.append(child)
    return found


def _signal(pid: int, sig: int) -> None:
    try:
        os.kill(pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


def kill_session(root: int, *, spare: int | None = None) -> set[int]:
    """SIGKILL the session led by ``root`` (see the module); ``spare``: a pid left alone (the
    worker itself, when it ends its own children). The pids signalled."""
    me = {os.getpid(), spare}
    hit: set[int] = set()
    if os.path.isdir("/proc"):
        for _ in range(_STOP_ROUNDS):
            new = _members(root, _table()) - hit - me
            if not new:
                break
            for pid in new:
                _signal(pid, signal.SIGSTOP)  # stopped, it forks no more
            hit |= new
        for pid in hit:
            _signal(pid, signal.SIGKILL)
    if root not in me:
        try:
            os.killpg(root, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    return hit


def become_subreaper() -> None:
    """Make this process the reaper of its orphaned descendants (Linux; elsewhere nothing),
    so that they stay its descendants for :func:`kill_session`."""
    try:
        import ctypes

        pr_set_child_subreaper = 36
        ctypes.CDLL(None, use_errno=True).prctl(pr_set_child_subreaper, 1, 0, 0, 0)
    except (OSError, AttributeError):
        pass


def _exited(proc: subprocess.Popen, timeout_s: float) -> bool:
    """Whether the child ``proc`` exited within ``timeout_s``; it is not reaped (where
    ``os.waitid`` can wait without reaping), so that its pid, process group and session stay
    its own until :func:`kill_session` has run."""
    if not hasattr(os, "waitid") or not hasattr(os, "WNOWAIT"):
        try:
            proc.wait(timeout_s)
            return True
        except subprocess.TimeoutExpired:
            return False
    pid = proc.pid
    deadline = time.monotonic() + timeout_s
    delay = 0.002
    while True:
        if os.waitid(os.P_PID, pid, os.WEXITED | os.WNOHANG | os.WNOWAIT) is not None:
            return True
        left = deadline - time.monotonic()
        if left <= 0:
            return False
        time.sleep(min(delay, left))
        delay = min(2 * delay, 0.05)


def run_limited(cmd: list[str], *, cwd: str, env: dict, timeout_s: float, log: Path):
    """Run ``cmd`` in its own session with stderr to the file ``log``; ``(finished, returncode,
    the tail of its stderr)``. Within ``timeout_s`` or not, its session is killed before this
    returns."""
    with open(log, "wb") as err:
        proc = subprocess.Popen(
            cmd,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=err,
            cwd=cwd,
            start_new_session=True,
            env=env,
        )
    try:
        finished = _exited(proc, timeout_s)
    finally:
        kill_session(proc.pid)
        proc.wait()
    with open(log, "rb") as fh:
        fh.seek(max(0, log.stat().st_size - STDERR_TAIL_BYTES))
        tail = fh.read().decode(errors="replace")
    return finished, proc.returncode, tail
