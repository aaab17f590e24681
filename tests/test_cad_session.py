"""A CadQuery script runs in its own session, and the whole session is killed at its limit (or
when it ends) without waiting on what its processes hold: a child it started, a grandchild
that escaped into a session of its own, a script that never returns."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.plates.parts.cad_run import kill_session
from sim_tactile.plates.parts.user import load_user_plate

#: How long a killed process may take to be gone (it is SIGKILLed; the kernel ends it at
#: once, this is slack for a loaded machine) [s].
GONE_WITHIN_S = 10.0
#: The scripts' limit [s], and the bound on the whole call: the limit plus the worker's
#: start and the kill, far below the 600 s its children would hold it [s].
LIMIT_S = 3
BOUND_S = LIMIT_S + 30

SCRIPT = textwrap.dedent(
    """
    import os
    import subprocess
    import time
    from pathlib import Path


    def _note(name, pid):
        Path(name + ".tmp").write_text(str(pid))
        os.replace(name + ".tmp", name)


    def child_and_sleep():
        p = subprocess.Popen(["sleep", "600"], start_new_session=False)
        _note("child.pid", p.pid)
        time.sleep(10**6)


    def escaped_and_sleep():
        if os.fork() == 0:  # a double fork: the grandchild in a session of its own
            os.setsid()
            if os.fork() == 0:
                _note("grandchild.pid", os.getpid())
                time.sleep(600)
            os._exit(0)
        os.wait()
        time.sleep(10**6)


    def detached_and_return():
        p = subprocess.Popen(["sleep", "600"], start_new_session=True)
        _note("child.pid", p.pid)
        return "not a shape"


    def forever():
        while True:
            pass
    """
)


def _alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie, killed and waiting for its reaper, does not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return False
    return stat[stat.rindex(")") + 2] not in "ZX"


def _gone(pid: int) -> bool:
    deadline = time.monotonic() + GONE_WITHIN_S
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not _alive(pid)


def _pid(path: Path) -> int:
    deadline = time.monotonic() + GONE_WITHIN_S
    while not path.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    return int(path.read_text())


pytestmark = pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc (Linux)")


@pytest.fixture
def script(tmp_path) -> Path:
    path = tmp_path / "parts.py"
    path.write_text(SCRIPT)
    return path


def _stopped_at_the_limit(ref: str) -> None:
    t0 = time.monotonic()
    with pytest.raises(ConfigError, match=f"did not finish within timeout_s = {LIMIT_S} s"):
        load_user_plate(f"{ref}?timeout_s={LIMIT_S}")
    assert time.monotonic() - t0 < BOUND_S


@pytest.mark.slow
def test_a_script_with_a_child_is_stopped_at_its_limit_child_included(script):
    _stopped_at_the_limit(f"{script}:child_and_sleep")
    assert _gone(_pid(script.parent / "child.pid"))


@pytest.mark.slow
def test_a_grandchild_in_a_session_of_its_own_is_killed_too(script):
    _stopped_at_the_limit(f"{script}:escaped_and_sleep")
    assert _gone(_pid(script.parent / "grandchild.pid"))


@pytest.mark.slow
def test_a_script_that_sleeps_forever_is_stopped(script):
    _stopped_at_the_limit(f"{script}:forever")


@pytest.mark.slow
def test_a_script_that_returns_leaving_a_detached_child_is_not_waited_for(script):
    """The script returns at once (its result is refused: not a shape); its detached child
    would hold a pipe for 600 s: the call returns without waiting, and the child is ended."""
    t0 = time.monotonic()
    with pytest.raises(ConfigError, match="detached_and_return"):
        load_user_plate(f"{script}:detached_and_return?timeout_s=120")
    assert time.monotonic() - t0 < BOUND_S
    assert _gone(_pid(script.parent / "child.pid"))


def test_kill_session_ends_a_process_tree_and_spares_the_caller():
    code = textwrap.dedent(
        """
        import subprocess, sys, time
        a = subprocess.Popen(["sleep", "600"])
        b = subprocess.Popen(["sleep", "600"], start_new_session=True)
        print(a.pid, b.pid, flush=True)
        time.sleep(600)
        """
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, start_new_session=True
    )
    try:
        pids = [int(p) for p in proc.stdout.readline().split()]
        hit = kill_session(proc.pid)
        assert {proc.pid, *pids} <= hit
        proc.wait()
        assert all(_gone(p) for p in pids)
        assert _alive(os.getpid())
    finally:
        proc.kill()
        proc.wait()
