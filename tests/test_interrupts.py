"""Signals are signals (sim_tactile/interrupts.py): an interrupt that surfaces through a
compiled kernel is reported as the interrupt.

With one worker the slides run in the command's own process, inside numba kernels; SIGTERM
there came out as ``internal error: SystemError: CPUDispatcher(...) returned a result with
an exception set`` (exit 3) in most runs, and the store's history recorded ``interrupted:
False``. The fast tests replay that exception (the interrupt in its chain, or lost from it
after the signal came); the slow one sends SIGTERM and SIGINT to real ``generate`` runs."""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import threading
import time
import warnings
from pathlib import Path

import pytest
from _stores import quiet_generate, write_config
from conftest import EXE

from sim_tactile import cli
from sim_tactile.errors import Terminated

KERNEL_ERROR = "CPUDispatcher(<function _held_kernel>) returned a result with an exception set"


def _kernel_error(signum: int = signal.SIGTERM) -> SystemError:
    """What a kernel raises when the signal's handler ran inside it: a SystemError whose
    cause is the interrupt (as Python chains it)."""
    try:
        try:
            raise Terminated(signum) if signum != signal.SIGINT else KeyboardInterrupt()
        except KeyboardInterrupt as exc:
            raise SystemError(KERNEL_ERROR) from exc
    except SystemError as exc:
        return exc


def _signal_swallowed(signum: int) -> None:
    """A signal arrives and its exception is lost on the way (as inside a kernel)."""
    try:
        os.kill(os.getpid(), signum)
        time.sleep(1.0)  # the handler runs here
    except KeyboardInterrupt:
        pass


def _main(monkeypatch, capsys, command) -> tuple[int, list[str]]:
    """The command line's ``main`` running ``command`` as a command: exit status, stderr."""

    class Parser:
        def parse_args(self, argv):
            return argparse.Namespace(func=lambda args: command(), debug=False)

    monkeypatch.setattr(cli, "build_parser", Parser)
    status = cli.main([])
    return status, capsys.readouterr().err.splitlines()


def test_an_interrupt_behind_a_kernels_system_error_is_the_interrupt(monkeypatch, capsys):
    def kernel():
        raise _kernel_error()

    status, err = _main(monkeypatch, capsys, kernel)
    assert (status, err) == (143, ["sim-tactile: stopped by signal SIGTERM"])

    def ctrl_c():
        raise _kernel_error(signal.SIGINT)

    status, err = _main(monkeypatch, capsys, ctrl_c)
    assert (status, err) == (130, ["sim-tactile: interrupted"])


def test_a_failure_after_a_signal_whose_exception_was_lost_is_the_signal(monkeypatch, capsys):
    def kernel():
        _signal_swallowed(signal.SIGTERM)
        raise SystemError(KERNEL_ERROR)  # the chain holds no interrupt

    status, err = _main(monkeypatch, capsys, kernel)
    assert (status, err) == (143, ["sim-tactile: stopped by signal SIGTERM"])

    def bug():
        raise SystemError("a real bug")

    status, err = _main(monkeypatch, capsys, bug)
    assert status == cli.EXIT_INTERNAL and "internal error: SystemError: a real bug" in err[0]


def test_a_signal_whose_exception_was_lost_stops_the_slides_between_two():
    from sim_tactile.interrupts import handled, interrupt_of, received
    from sim_tactile.slides.run import SerialBackend, stream

    done = []

    def slide(i):
        if i == 1:
            _signal_swallowed(signal.SIGTERM)
        done.append(i)
        return i

    with handled(), pytest.raises(Terminated):
        for _ in stream(SerialBackend(slide), [(i, i) for i in range(5)]):
            pass
    assert done == [0, 1]
    assert received() is None  # the command is over: the next starts afresh
    assert interrupt_of(ValueError("after the command")) is None


def test_generate_records_an_interrupt_that_surfaced_through_a_kernel(tmp_path):
    out = tmp_path / "x.zarr"
    calls = {"n": 0}

    def worker(job):
        calls["n"] += 1
        if calls["n"] == 3:
            raise _kernel_error()
        from _stores import fake_slide

        return fake_slide(job)

    with pytest.raises(Terminated):
        quiet_generate(write_config(tmp_path), out, _worker=worker)
    runs = json.loads((out / "zarr.json").read_text())["attributes"]["runs"]
    assert runs[-1]["interrupted"] is True and runs[-1]["signal"] == "SIGTERM"
    assert runs[-1]["written"] == 2


#: Slides that outlast the test: one worker, in the command's own process.
LONG = """
name = "long"
plates = ["finger7/flat", "finger7/ridges-2"]
sensor = "grid3x3"
slides_per_plate = 400
[protocol]
duration_s = 1.5
"""
#: (signal, delay [s] after the first slide is in the store): SIGTERM at two points of a
#: slide's kernels, and Ctrl-C; the first run alone, the others side by side
#: How long the first slide may take to reach the store [s] (a cold cache builds the
#: plates and skins first; generous for a machine shared with other work).
FIRST_SLIDE_S = 600.0
SENDS = [(signal.SIGTERM, 0.05), (signal.SIGTERM, 0.4), (signal.SIGINT, 0.2)]


#: starts a command with SIGINT at its default, as a terminal starts it: a suite run as a
#: background job (``make test &``) hands its children SIGINT ignored, which Python keeps
#: (no KeyboardInterrupt), and exec keeps a default disposition
_DEFAULT_SIGINT = (
    sys.executable,
    "-c",
    "import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
    "os.execv(sys.argv[1], sys.argv[1:])",
)


def _stop_generate(cfg: Path, out: Path, env: dict, signum: int, delay_s: float):
    p = subprocess.Popen(
        [*_DEFAULT_SIGINT, EXE, "generate", str(cfg), "--out", str(out), "--workers", "1"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    err: list[str] = []
    reader = threading.Thread(target=lambda: err.extend(p.stderr), daemon=True)
    reader.start()
    t0 = time.monotonic()
    chunks = out / "data"
    while not (chunks.is_dir() and any(chunks.glob("c*"))):  # the slides run now
        assert p.poll() is None and time.monotonic() - t0 < FIRST_SLIDE_S, "".join(err)[-2000:]
        time.sleep(0.01)
    time.sleep(delay_s)
    p.send_signal(signum)
    status = p.wait(60)
    reader.join(10)
    return status, "".join(err).replace("\r", "\n").splitlines()


@pytest.mark.slow
def test_a_signal_during_the_kernels_of_one_worker_is_reported_and_recorded(tmp_path, cli_env):
    cfg = tmp_path / "long.toml"
    cfg.write_text(LONG)
    got: dict = {}

    def one(k: int) -> None:  # generate writes no slide to the cache: the session's serves
        got[k] = _stop_generate(cfg, tmp_path / f"run{k}.zarr", cli_env, *SENDS[k])

    one(0)  # alone: it builds the plates and skins into the cache that the others read
    threads = [threading.Thread(target=one, args=(k,)) for k in range(1, len(SENDS))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k, (signum, delay_s) in enumerate(SENDS):
        status, err = got[k]
        case = f"{signal.Signals(signum).name} after {delay_s} s: {err[-3:]}"
        term = signum == signal.SIGTERM
        assert status == (143 if term else 130), case
        last = "sim-tactile: stopped by signal SIGTERM" if term else "sim-tactile: interrupted"
        assert err[-1] == last, case
        assert not any("internal error" in line or "Traceback" in line for line in err), case
        runs = json.loads((tmp_path / f"run{k}.zarr" / "zarr.json").read_text())["attributes"]
        assert runs["runs"][-1]["interrupted"] is True, case
        assert runs["runs"][-1]["signal"] == ("SIGTERM" if term else None), case


def test_an_interrupted_commands_unawaited_coroutines_say_nothing_after_its_line():
    """A signal that cuts a store's write short leaves zarr's coroutines never awaited; their
    warnings at exit would follow the one line (seen on SIGINT during a write)."""
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        assert cli._stopped(KeyboardInterrupt()) == 130
        warnings.warn("coroutine '_runner' was never awaited", RuntimeWarning, stacklevel=1)
        warnings.warn("another warning", RuntimeWarning, stacklevel=1)
    assert [str(w.message) for w in got] == ["another warning"]
