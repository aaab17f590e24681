"""One writer per store: :class:`StoreLock`, an advisory ``flock`` on a file beside the store.

The lock file is ``.NAME.lock`` beside the store's *resolved* path (:func:`lock_path`), so a
symbolic link to a store, or a path through a linked folder, takes the store's one lock. It
exists before the store does, so one lock covers creating, resuming and finishing a store.
The kernel drops a ``flock`` when its holder dies, however it dies, so a lock file left
behind by ``kill -9`` is no lock. A second writer is refused at once, told who holds it.

Whoever can create a file beside a store (a shared project folder, ``/tmp``) can put
anything at the lock's path, so the path is trusted for nothing:

- it is opened without following a symbolic link (``O_NOFOLLOW``), without blocking
  (``O_NONBLOCK``: a FIFO there cannot hang a writer) and read-only (all that ``flock``
  needs), and anything but a regular file is refused in one line naming the lock file and
  what lies there; a link, a FIFO, a folder or a device is never written, followed or
  created through;
- a new lock file is created exclusively (``O_CREAT | O_EXCL``, which never follows a link)
  and only a file that this process created is written (the holder's pid, host and start
  time): no other file is ever truncated or rewritten;
- it is created group-readable (mode 0o664 less the umask), and an existing one is opened
  read-only: a dead writer's lock file of another user in a shared folder does not block.
  No one holds it, so it is removed and replaced by one naming the new holder (where it
  cannot be removed, e.g. another user's file in a sticky folder such as ``/tmp``, it is
  locked as it is).
"""

from __future__ import annotations

import errno
import json
import os
import socket
import stat
from datetime import UTC, datetime
from pathlib import Path

from ..errors import StoreError
from .fs import fs_errors, io_error

#: How an existing lock file is opened: never through a link, never blocking, read-only.
_OPEN_EXISTING = os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC
#: How a new one is made: only where nothing is (a link, even a dangling one, counts).
_CREATE = os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC
#: A new lock file's mode before the umask: readable by the group and others, so that
#: another user's writer can take the lock once this one is gone.
LOCK_MODE = 0o664
_KINDS = (
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISLNK, "a symbolic link"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
)


def lock_path(store: str | Path) -> Path:
    """The lock file of ``store``: ``.NAME.lock`` beside its resolved path."""
    real = Path(os.path.realpath(store))
    return real.with_name(f".{real.name}.lock")


def _kind(mode: int) -> str:
    return next((what for test, what in _KINDS if test(mode)), "not a regular file")


def _not_a_file(path: Path, what: str) -> StoreError:
    return StoreError(
        f"the store's lock file {path} is {what}, not a regular file: remove it (a writer "
        "makes its own there), then run again"
    )


def _open_existing(path: Path) -> int | None:
    """A read-only descriptor of the regular file at ``path``; None if nothing is there.
    Anything else there is refused (never opened through a link, never waited on)."""
    try:
        before = os.lstat(path)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise _unusable(path, exc) from None
    if not stat.S_ISREG(before.st_mode):
        raise _not_a_file(path, _kind(before.st_mode))
    try:
        fd = os.open(path, _OPEN_EXISTING)
    except FileNotFoundError:
        return None  # removed meanwhile (its holder released it)
    except OSError as exc:
        if exc.errno == errno.ELOOP:  # replaced by a link meanwhile
            raise _not_a_file(path, "a symbolic link") from None
        raise _unusable(path, exc) from None
    now = os.fstat(fd)
    if not stat.S_ISREG(now.st_mode):
        os.close(fd)
        raise _not_a_file(path, _kind(now.st_mode))
    return fd


def _unusable(path: Path, exc: OSError) -> StoreError:
    if exc.errno in (errno.EACCES, errno.EPERM):
        return StoreError(
            f"the store's lock file {path} cannot be read ({exc.strerror}): another user's "
            "writer may hold it; ask them, or remove the file if no writer runs"
        )
    return StoreError(f"the store's lock file {path} cannot be opened: {exc.strerror or exc}")


def _create(path: Path, store: Path) -> int | None:
    """A new lock file at ``path`` (created by this call, so this process may write it);
    None if something appeared there first. A folder that cannot be written is named as
    the store's (``store``: the user's name for it)."""
    try:
        return os.open(path, _CREATE, LOCK_MODE)
    except FileExistsError:
        return None
    except OSError as exc:
        raise io_error(exc, store) from None


def _same_file(fd: int, path: Path) -> bool:
    try:
        return os.path.samestat(os.fstat(fd), os.lstat(path))
    except OSError:
        return False


def _alive_here(doc: dict) -> bool:
    """False when the holder named in ``doc`` was a process of this host that is gone."""
    if doc.get("host") != socket.gethostname():
        return True
    try:
        os.kill(int(doc["pid"]), 0)
    except ProcessLookupError:
        return False
    except (OSError, ValueError, TypeError):
        return True
    return True


def _holder(fd: int) -> str:
    try:
        doc = json.loads(os.pread(fd, 4096, 0) or b"{}")
        if _alive_here(doc):
            return f"pid {doc['pid']} on {doc['host']}, since {doc['since']}"
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        pass
    return "another process"


def _refused(store: Path, fd: int) -> StoreError:
    return StoreError(
        f"{store} is being written by another process ({_holder(fd)}); one writer at a time: "
        "wait for it to finish (or stop it), then run again"
    )


def _try_lock(store: Path, fd: int) -> None:
    """Take the lock on ``fd`` without waiting; raises (``fd`` closed) when it is held."""
    import fcntl

    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        err = _refused(store, fd)
        os.close(fd)
        raise err from None
    except OSError as exc:
        os.close(fd)
        raise StoreError(
            f"cannot lock {store} ({exc.strerror}): its file system does not support file "
            "locks; write the store on a local disk"
        ) from None


class StoreLock:
    """The lock of the store at ``store`` (a context manager): held for a whole write."""

    def __init__(self, store: str | Path) -> None:
        self.store = Path(store)
        self.path = lock_path(self.store)
        self.fd: int | None = None

    @staticmethod
    def probe(store: str | Path) -> None:
        """Raise if another process holds the lock of ``store`` now, or if something other
        than a lock file lies at its path (a quick early check before slow set-up;
        :meth:`acquire` is what counts)."""
        import fcntl

        fd = _open_existing(lock_path(store))
        if fd is None:
            return  # no lock file: nobody holds it
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise _refused(Path(store), fd) from None
        except OSError:
            pass  # a file system without locks: acquire() says so
        finally:
            os.close(fd)

    def acquire(self) -> StoreLock:
        with fs_errors(self.store):
            self.path.parent.mkdir(parents=True, exist_ok=True)
        while True:
            fd = _open_existing(self.path)
            mine = fd is None
            if mine:
                fd = _create(self.path, self.store)
                if fd is None:
                    continue  # another writer made it first: lock theirs (or be refused)
            _try_lock(self.store, fd)
            # the file may have been removed by the holder we waited on, or replaced: lock
            # the one at the path now
            if not _same_file(fd, self.path):
                os.close(fd)
                continue
            if mine:
                _write_holder(fd)
                break
            # nobody held it: a dead writer's. Replace it by one that names this writer,
            # removing it while holding it, as release() does
            try:
                os.unlink(self.path)
            except OSError:
                break  # not ours to remove: it is locked as it is
            os.close(fd)
        self.fd = fd
        return self

    def release(self) -> None:
        if self.fd is None:
            return
        import fcntl

        if _same_file(self.fd, self.path):
            try:
                os.unlink(self.path)  # while still held: a waiter then finds it gone
            except OSError:
                pass
        fcntl.flock(self.fd, fcntl.LOCK_UN)
        os.close(self.fd)
        self.fd = None

    def __enter__(self) -> StoreLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()


def _write_holder(fd: int) -> None:
    """Who holds the lock, into the lock file this process created (a courtesy: the lock
    itself is taken already)."""
    doc = {
        "pid": os.getpid(),
        "host": socket.gethostname(),
        "since": datetime.now(UTC).isoformat(timespec="seconds"),
    }
    try:
        os.pwrite(fd, json.dumps(doc).encode(), 0)
    except OSError:
        pass
