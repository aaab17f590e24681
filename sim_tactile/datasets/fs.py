"""The file system under a store: folders built under a temporary name and renamed when
whole (:func:`building`, :func:`take`), no empty folder left by a failed command
(:func:`no_empty_folders_left`), and the operating system's faults as one line each
(:func:`io_error`, :func:`fs_errors`, :func:`write_faults`). One writer at a time:
:mod:`.lock`.
"""

from __future__ import annotations

import errno
import os
import shutil
import uuid
from collections.abc import Iterator
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
def building(out: Path) -> Iterator[Path]:
    """A temporary folder beside ``out`` to write into; renamed to ``out`` when the block
    ends without an error (``out`` may exist only as an empty folder). On any failure the
    temporary folder, and every parent folder this call made, is removed: nothing is left
    behind. OS faults become one-line :class:`StoreError` naming ``out``."""
    tmp = temp_name(out, "partial")
    with no_empty_folders_left(out.parent):
        try:
            with fs_errors(out):
                out.parent.mkdir(parents=True, exist_ok=True)
                tmp.mkdir()
                yield tmp
                take(tmp, out)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
