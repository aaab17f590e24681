"""A store stays where it is or says so, holds only what it can, and leaves nothing behind:
a store moved or removed while ``generate`` writes it ends the run in one line, and the old
path is never made again; a protocol too large for a store, or a default window past the
600 s cap, is refused before anything is made; a killed export's temporary folder is
removed by the next export and is no obstacle to ``--resume``; a store claiming more slides
than it holds is refused in one line, before any of its arrays is read. Fake workers: no
physics (:mod:`_stores`)."""

from __future__ import annotations

import fcntl
import json
import os
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import _stores
import pytest
from _stores import TINY, assert_same, fake_slide, make_store, quiet_generate, read_back
from _stores import write_config as _config
from sim_tactile.plates.presets import get_plate

from sim_tactile import datasets
from sim_tactile.datasets import export
from sim_tactile.datasets.fs import FolderHold, remove_dead_builds
from sim_tactile.datasets.integrity import file_digest, sealed
from sim_tactile.errors import ConfigError, StoreError
from sim_tactile.generate import resolve
from sim_tactile.sim.plan.protocol import MAX_DURATION_S, Protocol, SlideWindow

#: Longest a refusal of a crafted store may take [s] (it read for minutes before).
CRAFTED_REFUSAL_S = 60


# ----------------------------------------------------------------------- a store moved
def _move_at_third_slide(out: Path, how: str, moved: Path):
    """A fake worker that moves (or removes) ``out`` while it simulates the third slide."""
    seen = []

    def worker(job):
        seen.append(job.seed)
        if len(seen) == 3:
            if how == "removed":
                shutil.rmtree(out)
            else:
                os.rename(out, moved)
        return fake_slide(job)

    return worker


@pytest.mark.parametrize("how", ["moved", "removed", "moved, no /proc"])
def test_a_store_moved_while_written_ends_the_run_and_is_never_made_again(
    tmp_path, monkeypatch, how
):
    """The writer wrote by path: it made the old path again as loose chunks, and said every
    slide was written while the moved store held two of them. Now it writes through the
    folder it opened and checks before each slide that the path is still that folder."""
    if how.endswith("no /proc"):  # where there is no /proc, the checks alone keep it
        monkeypatch.setattr(FolderHold, "PROC_FD", str(tmp_path / "no-proc"))
    cfg = _config(tmp_path)
    out, moved = tmp_path / "s.zarr", tmp_path / "elsewhere" / "moved.zarr"
    moved.parent.mkdir()
    with pytest.raises(StoreError, match="s.zarr was moved or removed while it was written") as e:
        quiet_generate(cfg, out, _worker=_move_at_third_slide(out, how, moved))
    msg = str(e.value)
    assert "\n" not in msg and "--resume" in msg
    assert not out.exists()  # never made again, not even as an empty folder
    if how == "removed":
        assert "it is gone" in msg
        return
    if how == "moved":
        assert f"it is now at {moved}" in msg
    # the moved store holds the slides written before the move, and resumes where it is
    res = quiet_generate(cfg, moved, resume=True)
    assert (res["reused"], res["written"]) == (2, 4)
    assert_same(read_back(moved), read_back(make_store(tmp_path, "ref.zarr")))


# ----------------------------------------------------------------------- sizes
def test_a_protocol_too_large_for_a_store_is_refused_before_anything_is_made(tmp_path):
    """600 s at 100 kHz, each within its range, is 540 million values a slide: the store was
    made, then called its own attributes damaged, and was left at --out."""
    big = {**TINY, "protocol": {"duration_s": 600.0, "rate_hz": 100_000.0}}
    out = tmp_path / "new" / "big.zarr"
    with pytest.raises(ConfigError) as e:
        quiet_generate(_config(tmp_path, big), out)
    msg = str(e.value)
    assert "\n" not in msg
    for words in ("60,000,000 samples (600 s at 100000 Hz) x 9 channels", "at most 100,000,000"):
        assert words in msg, msg
    assert "duration_s" in msg and "rate_hz" in msg and "nothing was created" in msg
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiny.json"]


@pytest.mark.parametrize("speed", [1e-6, 1e-9])
def test_a_slow_default_duration_obeys_the_cap_of_an_explicit_one(speed):
    """The default window (the time to cross the texture) escaped duration_s's 600 s cap:
    1e-6 m/s ran for minutes, 1e-9 m/s asked for billions of samples."""
    plate = get_plate("finger7/flat")
    proto = Protocol(speed_m_s=speed, rate_hz=100.0)
    with pytest.raises(ConfigError) as e:
        SlideWindow.of(plate, 0.02, proto)
    msg = str(e.value)
    assert f"speed_m_s = {speed:g} m/s" in msg and f"at most {MAX_DURATION_S:g} s" in msg
    seconds = float(msg.split(" takes ")[1].split(" s ")[0])
    assert seconds > MAX_DURATION_S
    with pytest.raises(ConfigError, match=r"duration_s = 601 s is out of range"):
        Protocol(duration_s=601.0)  # the cap an explicit one has


def test_a_slow_default_duration_of_a_configuration_names_the_speed(tmp_path):
    cfg = _config(tmp_path, {**TINY, "protocol": {"speed_m_s": 1e-6}})
    with pytest.raises(ConfigError, match=r"speed_m_s = 1e-06 m/s takes .* at most 600 s"):
        resolve(str(cfg), quick=False, seed=None)
    # under the cap, a configuration's default window is as it was
    ok = _config(tmp_path, {**TINY, "protocol": {"speed_m_s": 1e-3}}, "ok.json")
    (plan,), _ = resolve(str(ok), quick=False, seed=None)
    assert plan.spec.n_time / plan.spec.rate_hz <= MAX_DURATION_S


# ----------------------------------------------------------------------- leftovers
#: An export killed (SIGKILL) while it writes: ``export(argv[1], argv[2])``.
_KILLED_EXPORT = """
import importlib, os, signal, sys
mod = importlib.import_module("sim_tactile.datasets.export")

def killed(st, folder):
    (folder / "data.npy").write_bytes(b"half of it")
    os.kill(os.getpid(), signal.SIGKILL)

mod.FORMATS["numpy"] = killed
mod.export(sys.argv[1], sys.argv[2])
"""


def test_a_killed_exports_folder_is_no_obstacle_and_the_next_export_removes_it(tmp_path):
    """A killed export left its temporary folder for good; inside a store, --resume then
    failed (its clean-up of Zarr's half-written chunk files unlinked a folder)."""
    store = make_store(tmp_path)
    out = store / "exported"
    p = subprocess.run([sys.executable, "-c", _KILLED_EXPORT, str(store), str(out)], timeout=120)
    assert p.returncode == -signal.SIGKILL
    (left,) = store.glob(".exported.*.partial")
    (left / "0.0123456789abcdef0123456789abcdef.partial").write_bytes(b"not the store's")
    res = quiet_generate(tmp_path / "tiny.json", store, resume=True)
    assert res["reused"] == 6 and left.is_dir() and len(list(left.iterdir())) == 2
    notes: list[str] = []
    doc = export(store, out, log=notes.append)
    assert doc["slides"] == 6 and (out / "data.npy").stat().st_size > 100
    assert not left.exists() and notes == [
        f"removed {left}: the temporary folder of a killed export to {out}"
    ]


def test_a_live_exports_folder_is_left_alone(tmp_path):
    out = tmp_path / "x"
    live, dead = (tmp_path / f".x.{k}.partial" for k in ("0123456789ab", "ba9876543210"))
    live.mkdir()
    dead.mkdir()
    fd = os.open(live, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # a builder writing now
        assert remove_dead_builds(out) == [dead]
        assert live.is_dir() and not dead.exists()
    finally:
        os.close(fd)


def test_resume_removes_zarrs_half_written_files_only(tmp_path):
    """The clean-up takes the files Zarr writes before its rename, and nothing else: never a
    folder, nothing in a hidden folder, no other file that ends in .partial."""
    store = make_store(tmp_path)
    zarrs = _stores.sample_chunk(store, 0).with_suffix(".0123456789abcdef0123456789abcdef.partial")
    zarrs.write_bytes(b"a killed writer's chunk")
    theirs = [store / "notes.partial", store / "folder.0123456789abcdef0123456789abcdef.partial"]
    theirs[0].write_text("a user's file")
    theirs[1].mkdir()
    res = quiet_generate(tmp_path / "tiny.json", store, resume=True)
    assert res["reused"] == 6 and not zarrs.exists() and all(p.exists() for p in theirs)


# ----------------------------------------------------------------------- crafted claims
def _claim_slides(store: Path, n: int) -> None:
    """Make the store claim ``n`` slides, every array's shape and every digest to match, as a
    forger would (the chunk grid and the chunk files left as they are)."""
    doc = json.loads((store / "zarr.json").read_text())
    attrs = doc["attributes"]
    files = dict(attrs["integrity"]["files"])
    for name in ("data", "checksum", "lengths", "labels", "slide", "seed", "params"):
        meta = store / name / "zarr.json"
        arr = json.loads(meta.read_text())
        arr["shape"][0] = n
        meta.write_text(json.dumps(arr))
        files[f"{name}/zarr.json"] = file_digest(meta)
    attrs["n_slides"] = n
    attrs["integrity"] = {**attrs["integrity"], "files": files}
    doc["attributes"] = sealed(attrs)
    (store / "zarr.json").write_text(json.dumps(doc))


def test_a_store_claiming_10_to_the_8_slides_is_refused_before_a_read(tmp_path):
    """It read for minutes (16 million chunks of 6 slides), or printed its one clear line and
    then thousands of lines of asyncio tracebacks from Zarr's pending reads: the claim is
    checked against the chunk files the store recorded before any array is read."""
    store = make_store(tmp_path)
    _claim_slides(store, 10**8)
    for call in (
        lambda: datasets.open(store),
        lambda: quiet_generate(tmp_path / "tiny.json", store, resume=True),
    ):
        with pytest.raises(StoreError, match=_CLAIM) as e:
            call()
        assert "\n" not in str(e.value)
    with pytest.raises(StoreError, match=f"already exists .*{_CLAIM}"):
        quiet_generate(tmp_path / "tiny.json", store)


#: The refusal of a store whose 6 slides claim to be 10^8.
_CLAIM = r"n_slides = 100000000 is not valid \(1 chunk file\(s\) of lengths recorded, for 1526"


@pytest.mark.slow
def test_a_store_claiming_10_to_the_8_slides_is_one_line_on_the_command_line(tmp_path, cli):
    """What the user sees: one line on stderr, nothing after it (3 commands, 7 s each)."""
    store = make_store(tmp_path)
    _claim_slides(store, 10**8)
    runs = (
        ["export", store, "--out", tmp_path / "out"],
        ["generate", tmp_path / "tiny.json", "--out", store, "--resume", "--workers", "1"],
        ["generate", tmp_path / "tiny.json", "--out", store, "--workers", "1"],
    )
    for args in runs:
        p = cli(args, check=False, timeout=CRAFTED_REFUSAL_S)
        lines = p.stderr.splitlines()
        assert p.returncode == 2 and len(lines) == 1, p.stderr[-3000:]
        assert re.search(_CLAIM, lines[0]), lines[0]
    assert not (tmp_path / "out").exists()
