"""The file system under a store: folders built under a temporary name and renamed when
whole (:func:`building`, :func:`take`; a killed builder's folder removed by the next,
:func:`remove_dead_builds`), a store written through its open folder, so that a move is
noticed and never writes the old path again (:class:`FolderHold`), no empty folder left by a
failed command (:func:`no_empty_folders_left`), and the operating system's faults as one
line each (:func:`io_error`, :func:`fs_errors`, :func:`write_faults`). One writer at a time:
:mod:`.lock`.
"""

from __future__ import annotations

import errno
import glob
import os
import shutil
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from ..errors import StoreError

_NO_SPACE = (errno.ENOSPC, errno.EDQUOT)
_READ_ONLY = (errno.EROFS, errno.EACCES, errno.EPERM)


def io_error(exc: OSError, path: str | Path, hint: str = "") -> StoreError:
    """``exc`` (raised writing under ``path``) as one line naming ``path`` (and ``hint``)."""
    if exc.errno in _NO_SPACE:
        msg = f"no space left on device writing {path}"
    elif exc.errno in _READ_ONLY:
        msg = f"{path} is read-only (cannot write there)"
    else:
        msg = f"cannot write {path}: {exc.strerror or exc}"
    return StoreError(f"{msg}; {hint}" if hint else msg)


@contextmanager
def fs_errors(path: str | Path, hint: str = "") -> Iterator[None]:
    """Turn an :class:`OSError` from the file system into a :class:`StoreError` naming
    ``path`` (the user's name for the store or folder being written)."""
    try:
        yield
    except OSError as exc:
        raise io_error(exc, path, hint) from None


@contextmanager
def write_faults(folder: Path) -> Iterator[None]:
    """A full disk or a read-only file system met writing under ``folder`` as one
    :class:`StoreError` naming ``folder``; every other error passes unchanged."""
    try:
        yield
    except OSError as exc:
        name = exc.filename
        inside = name is None or Path(os.path.abspath(name)).is_relative_to(folder.absolute())
        if exc.errno in _NO_SPACE + _READ_ONLY and inside:
            raise io_error(exc, folder) from None
        raise


def temp_name(path: Path, what: str) -> Path:
    """A fresh hidden name beside ``path`` (same folder, so a rename is atomic)."""
    return path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.{what}")


def take(tmp: Path, out: Path) -> None:
    """Rename the folder ``tmp`` to ``out`` (atomic; ``out`` may be an empty folder, which
    it replaces); refused if ``out`` appeared meanwhile as anything else."""
    try:
        os.rename(tmp, out)
    except OSError as exc:
        if exc.errno in (errno.ENOTEMPTY, errno.EEXIST, errno.ENOTDIR, errno.EISDIR):
            raise StoreError(
                f"{out} appeared while this was written (another process?); it was left as "
                "it is: choose another path"
            ) from None
        raise


@contextmanager
def no_empty_folders_left(path: Path) -> Iterator[None]:
    """On any failure inside the block, remove ``path`` and its parents that the block made,
    where they are empty (innermost first): a failed command leaves no empty folder it
    created. Folders holding files are kept."""
    made = [p for p in (path, *path.parents) if not p.exists()]
    try:
        yield
    except BaseException:
        for p in made:
            try:
                p.rmdir()
            except FileNotFoundError:
                continue
            except OSError:  # not empty: it, and every folder above it, is kept
                break
        raise


@contextmanager
def building(out: Path, log: Callable[[str], None] | None = None) -> Iterator[Path]:
    """A temporary folder beside ``out`` to write into; renamed to ``out`` when the block
    ends without an error (``out`` may exist only as an empty folder). On any failure the
    temporary folder, and every parent folder this call made, is removed: nothing is left
    behind. The builder holds a ``flock`` on its temporary folder while it writes, so a
    folder of this name that nobody holds is a killed builder's: it is removed first, with
    a note to ``log`` (:func:`remove_dead_builds`). OS faults become one-line
    :class:`StoreError` naming ``out``."""
    tmp = temp_name(out, "partial")
    with no_empty_folders_left(out.parent):
        try:
            with fs_errors(out):
                out.parent.mkdir(parents=True, exist_ok=True)
                remove_dead_builds(out, log)
                tmp.mkdir()
                # (another export to the same --out between these two lines could take it
                # for a killed one's: two exports to one --out fail one way or another)
                held = _hold_folder(tmp)
                try:
                    yield tmp
                    take(tmp, out)
                finally:
                    if held is not None:
                        os.close(held)  # (releases the flock)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise


def _hold_folder(folder: Path) -> int | None:
    """An open descriptor of ``folder`` holding an exclusive ``flock`` on it (the kernel drops
    it when this process dies, however it dies), or None where locks are not supported."""
    import fcntl

    fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        return None
    return fd


def remove_dead_builds(out: Path, log: Callable[[str], None] | None = None) -> list[Path]:
    """Remove the temporary folders of killed builds of ``out`` (:func:`building`'s
    ``.NAME.<hex>.partial`` beside it) that no live builder holds, each with a note to
    ``log``; returns them. One a live builder holds (its ``flock``), or that cannot be
    locked to tell, is left alone."""
    import fcntl

    removed = []
    for stale in sorted(out.parent.glob(f".{glob.escape(out.name)}.*.partial")):
        if stale.is_symlink() or not stale.is_dir():
            continue
        try:
            fd = os.open(stale, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # a live builder's (or no locks here: then nothing is known)
            continue
        else:
            shutil.rmtree(stale, ignore_errors=True)
            removed.append(stale)
            if log is not None:
                log(f"removed {stale}: the temporary folder of a killed export to {out}")
        finally:
            os.close(fd)
    return removed


class StoreMoved(StoreError):
    """The store was moved or removed while this process wrote it."""


class FolderHold:
    """A store's folder held open while it is written (a context manager): ``root`` is the
    path to write it through, :meth:`check` raises :class:`StoreMoved` once ``path`` is no
    longer the folder that was opened (moved, renamed, removed or replaced).

    On Linux ``root`` is ``/proc/self/fd/N``, the open folder itself wherever it now lies:
    a writer never re-creates the old path, and what it wrote before it noticed is in the
    moved store. Elsewhere ``root`` is the path, and :meth:`check` before each write is
    what keeps it from writing after a move."""

    #: where this process's open files are named (Linux)
    PROC_FD = "/proc/self/fd"

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        with fs_errors(self.path):
            self.fd = os.open(self.path, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        self.stat = os.fstat(self.fd)
        here = f"{self.PROC_FD}/{self.fd}"
        try:
            follows = os.path.samestat(os.stat(here), self.stat)
        except OSError:
            follows = False
        #: True where ``root`` follows the folder (``/proc/self/fd``)
        self.follows = follows
        self.root = here if follows else str(self.path)

    def where_now(self) -> str | None:
        """Where the folder lies now (None: removed, or not known here)."""
        if not self.follows:
            return None
        try:
            now = os.readlink(self.root)
        except OSError:
            return None
        return None if now.endswith(" (deleted)") else now

    def moved(self) -> bool:
        try:
            return not os.path.samestat(os.stat(self.path), self.stat)
        except OSError:
            return True

    def check(self) -> None:
        """Raise :class:`StoreMoved` if ``path`` is no longer the folder that was opened."""
        if self.moved():
            now = self.where_now()
            where = f"it is now at {now}" if now else "it is gone"
            raise StoreMoved(
                f"{self.path} was moved or removed while it was written ({where}); nothing "
                f"more was written and nothing was made at {self.path}: run the same command "
                "with --resume and --out at the store's new place to continue"
            )

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None

    def __enter__(self) -> FolderHold:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
