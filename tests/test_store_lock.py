"""The store's lock file cannot be turned against its owner (sim_tactile/datasets/lock.py).

Whoever can create a file beside a store can put anything at ``.NAME.lock``. Each case here
failed before the lock was hardened: a symbolic link there had its target truncated (a
dangling one had it created), a FIFO hung ``generate`` forever, a folder was blamed on the
store, a dead writer's lock of another user blocked everyone with "is read-only", a hard
link had the other name's file truncated, and a second path to one store took a second
lock."""

from __future__ import annotations

import errno
import json
import os
import socket
import stat
import tempfile
from pathlib import Path

import pytest
from _stores import quiet_generate, within, write_config

from sim_tactile.datasets import lock as lock_mod
from sim_tactile.datasets.lock import StoreLock, lock_path
from sim_tactile.errors import StoreError

#: How long a lock may take to be taken or refused [s]: it never waits on anything, so this
#: is only the slowest machine's scheduling (a hang is forever).
HANG_S = 20.0
VICTIM = b"someone's precious file\n"


def _refused(call, *words: str) -> str:
    hung, box = within(call, HANG_S)
    assert not hung, "the lock hung"
    exc = box.get("exc")
    assert isinstance(exc, StoreError), box
    msg = str(exc)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg
    return msg


def test_a_symbolic_link_at_the_lock_is_refused_and_its_target_left_alone(tmp_path):
    out = tmp_path / "x.zarr"
    victim = tmp_path / "victim.txt"
    victim.write_bytes(VICTIM)
    lock_path(out).symlink_to(victim)
    for call in (StoreLock(out).acquire, lambda: StoreLock.probe(out)):
        _refused(call, str(lock_path(out)), "is a symbolic link")
    assert victim.read_bytes() == VICTIM
    with pytest.raises(StoreError, match="symbolic link"):
        quiet_generate(write_config(tmp_path), out)
    assert victim.read_bytes() == VICTIM and not out.exists()


def test_a_dangling_link_at_the_lock_creates_nothing(tmp_path):
    out = tmp_path / "x.zarr"
    target = tmp_path / "elsewhere" / "created-by-the-lock"
    target.parent.mkdir()
    lock_path(out).symlink_to(target)
    _refused(StoreLock(out).acquire, "is a symbolic link")
    assert not target.exists() and os.listdir(target.parent) == []


def test_a_fifo_at_the_lock_is_refused_without_hanging(tmp_path):
    out = tmp_path / "x.zarr"
    fifo = lock_path(out)
    os.mkfifo(fifo)
    try:
        for call in (
            lambda: StoreLock.probe(out),
            StoreLock(out).acquire,
            lambda: quiet_generate(write_config(tmp_path), out),
        ):
            _refused(call, str(fifo), "is a FIFO")
    finally:  # a reader still blocked in open() (the old code) gets its writer and returns
        try:
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        except OSError:
            pass
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and not out.exists()


def test_a_folder_at_the_lock_is_named_not_the_store(tmp_path):
    out = tmp_path / "x.zarr"
    lock_path(out).mkdir()
    for call in (StoreLock(out).acquire, lambda: StoreLock.probe(out)):
        msg = _refused(call, str(lock_path(out)), "is a folder")
        assert not msg.startswith(str(out))


def test_a_hard_link_at_the_lock_leaves_the_other_names_file_whole(tmp_path):
    """A regular file at the lock's path that this process did not create is locked, never
    written: here it is another name of someone's file."""
    out = tmp_path / "x.zarr"
    victim = tmp_path / "victim.txt"
    victim.write_bytes(VICTIM)
    os.link(victim, lock_path(out))
    with StoreLock(out):
        assert victim.read_bytes() == VICTIM
    assert victim.read_bytes() == VICTIM and not lock_path(out).exists()


def _permission_bits_bind(monkeypatch):
    """``os.open`` as for a user other than the file's owner: asking to write a file that
    nobody may write fails with EACCES (root is exempt from permission bits, so the test
    makes them bind for it too)."""
    real_open = os.open
    asked: list[int] = []

    def guarded(path, flags, *args, **kw):
        if flags & (os.O_WRONLY | os.O_RDWR):
            try:
                mode = os.stat(path, follow_symlinks=False).st_mode
            except OSError:
                mode = None
            if mode is not None:
                asked.append(flags)
                if not mode & 0o222:
                    raise PermissionError(errno.EACCES, "Permission denied", str(path))
        return real_open(path, flags, *args, **kw)

    monkeypatch.setattr(os, "open", guarded)
    return asked


def test_a_dead_writers_read_only_lock_does_not_block(tmp_path, monkeypatch):
    out = tmp_path / "x.zarr"
    stale = lock_path(out)
    stale.write_text(json.dumps({"pid": 1, "host": "elsewhere", "since": "then"}))
    stale.chmod(0o444)  # another user's lock file, as this user sees it
    asked = _permission_bits_bind(monkeypatch)
    with StoreLock(out) as lock:
        held = json.loads(stale.read_text())
        assert held["pid"] == os.getpid() and held["host"] == socket.gethostname()
        _refused(StoreLock(out).acquire, f"pid {os.getpid()}")
        assert lock.fd is not None
    assert asked == [], "an existing lock file was opened for writing"
    assert not stale.exists()
    quiet_generate(write_config(tmp_path), out)


def test_a_stale_lock_that_cannot_be_removed_is_locked_as_it_is(tmp_path, monkeypatch):
    """Another user's file in a sticky folder (``/tmp``): it cannot be removed, so it is
    locked in place, read-only, and left as it was."""
    out = tmp_path / "x.zarr"
    stale = lock_path(out)
    text = json.dumps({"pid": 1, "host": "elsewhere", "since": "then"})
    stale.write_text(text)
    stale.chmod(0o444)
    _permission_bits_bind(monkeypatch)
    real_unlink = os.unlink

    def sticky(path, *a, **k):
        if Path(path) == stale:
            raise PermissionError(errno.EPERM, "Operation not permitted", str(path))
        return real_unlink(path, *a, **k)

    monkeypatch.setattr(os, "unlink", sticky)
    with StoreLock(out):
        _refused(StoreLock(out).acquire, "being written by another process")
        _refused(lambda: StoreLock.probe(out), "being written by another process")
    assert stale.read_text() == text


def _as_nobody(call) -> tuple[int, str]:
    """Run ``call`` in a child process as the user ``nobody``: its exit status and what it
    printed (root only)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        status = 1
        try:
            os.close(r)
            os.setgroups([])
            os.setgid(65534)
            os.setuid(65534)
            call()
            status = 0
        except BaseException as exc:  # noqa: BLE001 - reported to the parent
            os.write(w, f"{type(exc).__name__}: {exc}".encode())
        finally:
            os._exit(status)
    os.close(w)
    with os.fdopen(r) as f:
        said = f.read()
    return os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]), said


@pytest.mark.skipif(os.name != "posix" or os.geteuid() != 0, reason="needs root to be nobody")
@pytest.mark.parametrize("folder_mode", [0o777, 0o1777], ids=["shared", "sticky"])
def test_another_users_dead_lock_does_not_block(folder_mode):
    """A real other user: root's lock file (0644, no lock held) in a shared folder, and in a
    sticky one like /tmp; the user ``nobody`` takes the store's lock all the same."""
    folder = Path(tempfile.mkdtemp(prefix="sim-tactile-lock-", dir="/tmp"))
    try:
        folder.chmod(folder_mode)
        out = folder / "x.zarr"
        stale = lock_path(out)
        stale.write_text(json.dumps({"pid": 1, "host": "elsewhere", "since": "then"}))
        stale.chmod(0o644)

        def take():
            with StoreLock(out):
                pass

        status, said = _as_nobody(take)
        assert status == 0, said
    finally:
        for p in sorted(folder.iterdir()):
            p.unlink()
        folder.rmdir()


def test_a_new_lock_file_is_readable_by_the_group(tmp_path):
    out = tmp_path / "x.zarr"
    old = os.umask(0o002)  # a group-shared project folder's usual umask
    try:
        with StoreLock(out):
            mode = stat.S_IMODE(os.stat(lock_path(out)).st_mode)
    finally:
        os.umask(old)
    assert mode == lock_mod.LOCK_MODE == 0o664


@pytest.mark.parametrize("through", ["store", "folder"])
def test_a_second_path_to_one_store_is_refused_while_the_first_holds_it(tmp_path, through):
    real = tmp_path / "real"
    real.mkdir()
    (real / "x.zarr").mkdir()
    if through == "store":  # link.zarr -> real/x.zarr
        first, second = real / "x.zarr", tmp_path / "link.zarr"
        second.symlink_to(first)
    else:  # linked/x.zarr, where linked -> real
        (tmp_path / "linked").symlink_to(real)
        first, second = real / "x.zarr", tmp_path / "linked" / "x.zarr"
    assert lock_path(first) == lock_path(second)
    for a, b in ((first, second), (second, first)):
        with StoreLock(a):
            _refused(StoreLock(b).acquire, str(b), "being written by another process")
            _refused(lambda b=b: StoreLock.probe(b), "being written by another process")
        with StoreLock(b):  # free again, by either name
            pass


def test_a_link_to_a_store_not_made_yet_shares_its_lock(tmp_path):
    out = tmp_path / "new.zarr"
    link = tmp_path / "link.zarr"
    link.symlink_to(out)  # dangling until the store is made
    with StoreLock(link):
        _refused(StoreLock(out).acquire, "being written by another process")
    assert lock_path(link) == lock_path(out) == tmp_path / ".new.zarr.lock"
