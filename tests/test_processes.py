"""Processes stop: SIGTERM stops ``generate`` and ``run`` as Ctrl-C does (their workers end,
the store records the stop), and a parent killed outright (SIGKILL, the OOM killer) takes its
workers with it. Each command runs in its own session, so that every process it started can
be found afterwards by its session id."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest
from conftest import EXE

#: A configuration whose slides outlast the test's patience (2 workers stay busy): solved
#: step by step at the finest level, some 0.5 s a slide (``auto`` reads a set of 40 slides a
#: plate off tables: the 80 slides took under 2 s).
LONG = """
name = "long"
plates = ["finger7/flat", "finger7/ridges-2"]
sensor = "grid3x3"
slides_per_plate = 40
path = "per-step"
fidelity = "L2"
[protocol]
duration_s = 1.2
"""
#: How long the processes of a stopped command may take to go [s].
GRACE_S = 15.0


def _session(sid: int) -> list[int]:
    """The pids of the live processes in session ``sid`` (zombies excluded)."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        if fields[0] != "Z" and int(fields[3]) == sid:
            out.append(int(d.name))
    return out


def _start(args: list, env: dict, marker: str) -> tuple[subprocess.Popen, list[str]]:
    """Start the command in its own session; return once its stderr shows ``marker``."""
    p = subprocess.Popen(
        [EXE, *map(str, args)],
        env=env,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        start_new_session=True,
    )
    lines: list[str] = []
    seen = threading.Event()

    def read() -> None:
        for line in p.stderr:
            lines.append(line)
            if marker in line:
                seen.set()

    threading.Thread(target=read, daemon=True).start()
    assert seen.wait(240), "".join(lines)[-2000:]
    time.sleep(2.0)  # the workers are simulating now
    return p, lines


def _gone(sid: int) -> list[int]:
    t0 = time.monotonic()
    while _session(sid) and time.monotonic() - t0 < GRACE_S:
        time.sleep(0.2)
    return _session(sid)


def _env(cli_env: dict, tmp_path: Path) -> dict:
    return {**cli_env, "SIM_TACTILE_CACHE": str(tmp_path / "cache"), "SIM_TACTILE_WORKERS": "2"}


@pytest.mark.slow
def test_sigterm_stops_generate_and_its_workers_and_the_store_records_it(tmp_path, cli_env):
    cfg = tmp_path / "long.toml"
    cfg.write_text(LONG)
    out = tmp_path / "long.zarr"
    p, lines = _start(
        ["generate", cfg, "--out", out, "--workers", 2], _env(cli_env, tmp_path), "2 worker(s)"
    )
    assert len(_session(p.pid)) >= 3  # the command and its two workers
    p.send_signal(signal.SIGTERM)
    assert p.wait(60) == 128 + signal.SIGTERM
    assert _gone(p.pid) == []
    text = "".join(lines)
    assert "stopped by SIGTERM" in text and "--resume" in text and "Traceback" not in text
    runs = json.loads((out / "zarr.json").read_text())["attributes"]["runs"]
    assert runs[-1]["interrupted"] and runs[-1]["signal"] == "SIGTERM"


@pytest.mark.slow
def test_sigterm_stops_run_and_its_workers(tmp_path, cli_env):
    cfg = tmp_path / "long.toml"
    cfg.write_text(LONG)
    p, lines = _start(
        ["run", cfg, "--out", tmp_path / "report"], _env(cli_env, tmp_path), "2 worker(s)"
    )
    p.send_signal(signal.SIGTERM)
    assert p.wait(60) == 128 + signal.SIGTERM
    assert _gone(p.pid) == []
    assert "Traceback" not in "".join(lines)


@pytest.mark.slow
def test_workers_end_when_their_parent_is_killed_outright(tmp_path, cli_env):
    cfg = tmp_path / "long.toml"
    cfg.write_text(LONG)
    p, _ = _start(
        ["generate", cfg, "--out", tmp_path / "k.zarr", "--workers", 2],
        _env(cli_env, tmp_path),
        "2 worker(s)",
    )
    workers = [q for q in _session(p.pid) if q != p.pid]
    assert len(workers) >= 2
    os.kill(p.pid, signal.SIGKILL)  # no handler runs: the OOM killer's way
    p.wait(30)
    assert _gone(p.pid) == []
