"""numba's cache files, each proving what it holds before numba reads a byte of it.

numba keeps a compiled kernel in two kinds of file: an index (``.nbi``: which data file holds
which signature, under a source stamp) and data files (``.nbc``: the compiled code). Both
are pickles, read as they lie: a truncated one raised ``UnpicklingError`` on every run, a
flipped bit could crash the interpreter, and a data file copied from another code version's
folder ran that version's physics.

:class:`ProvenCacheFile` writes each file as one line of digest, then numba's bytes:

    sim_tactile kernel file 1
    {"file": NAME, "sha256": HEX, "size": BYTES, "stamp": STAMP}
    <numba's pickle>

binding the bytes to their file name and to the kernel's code version (its stamp,
:func:`~sim_tactile._jit.kernel_stamp`), in the same file, replaced as one (numba writes a
temporary name and renames it), so two processes compiling one kernel never leave a digest
of one beside the bytes of the other. The digest is checked before numba unpickles
anything. A file that has none, whose bytes or size differ from it, that is another
kernel's, or that was compiled from another version of the code is not read: the kernel is
compiled again, with a :class:`~sim_tactile.errors.CacheWarning` naming the file.

The digest proves a file whole and in its place; it does not make it safe. numba's files
are pickles, and unpickling one that was crafted runs code: the kernel folder is trusted as
code is, and is not shared with anyone whose code one would not run.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import pickle
import uuid
import warnings

from numba.core import caching

from .errors import CacheWarning, os_error_message

#: The first line of every file this package's kernel cache writes.
MAGIC = b"sim_tactile kernel file 1\n"
#: The longest digest line read [bytes] (it is about 170).
_MAX_HEAD = 1024
_KEYS = {"file", "sha256", "size", "stamp"}

_warned: set[tuple[str, str]] = set()


def distrust(path: str, why: str, what: str = "the kernel is compiled again") -> None:
    """Warn, once per process for each file and reason, that ``path`` is not used."""
    if (path, why) in _warned:
        return
    _warned.add((path, why))
    warnings.warn(f"compiled kernel file {path} {why}; {what}", CacheWarning, stacklevel=3)


def _wrapped(payload: bytes, name: str, stamp: str) -> bytes:
    head = {
        "file": name,
        "sha256": hashlib.sha256(payload).hexdigest(),
        "size": len(payload),
        "stamp": stamp,
    }
    return MAGIC + json.dumps(head, sort_keys=True).encode() + b"\n" + payload


def unwrap(raw: bytes, name: str, stamp: str) -> tuple[bytes | None, str]:
    """numba's bytes from the file ``raw`` read as ``name``, if its digest line vouches for
    them under ``stamp``; else None and what is wrong."""
    if not raw:
        return None, "is empty"
    if not raw.startswith(MAGIC):
        return None, "has no digest (damaged, or not written by this package)"
    end = raw.find(b"\n", len(MAGIC), len(MAGIC) + _MAX_HEAD)
    if end < 0:
        return None, "is truncated in its digest line"
    try:
        head = json.loads(raw[len(MAGIC) : end])
    except ValueError:
        head = None
    if not isinstance(head, dict) or set(head) != _KEYS:
        return None, "has a damaged digest line"
    payload = raw[end + 1 :]
    if head["stamp"] != stamp:
        return None, (
            f"was compiled from another version of the code (stamp {head['stamp']!r}, this "
            f"code's {stamp!r}): copied from another version's folder?"
        )
    if head["file"] != name:
        return None, f"is a copy of another kernel file ({head['file']!r})"
    if len(payload) != head["size"]:
        return (
            None,
            f"is truncated or extended ({len(payload)} bytes, its digest says {head['size']})",
        )
    if hashlib.sha256(payload).hexdigest() != head["sha256"]:
        return None, "does not match its digest (altered or damaged)"
    return payload, ""


class ProvenCacheFile(caching.IndexDataCacheFile):
    """numba's index and data files of one kernel, each written with its digest and read
    only when the digest vouches for it (see the module's docstring).

    stamp: the kernel's code version, bound into every file.
    own_folder: the folder holds this code version's files only (the kernel folder, one
        per stamp): a file of another stamp was copied there, and is warned of. In numba's
        own places (``__pycache__``, shared by every version) an index of another stamp is
        merely stale, and is passed over in silence as numba does.
    """

    def __init__(
        self, cache_path: str, filename_base: str, source_stamp, stamp: str, own_folder: bool
    ) -> None:
        super().__init__(cache_path, filename_base, source_stamp)
        self._stamp = stamp
        self._own_folder = own_folder

    # writing: one file, digest and bytes, replaced whole -----------------------------------
    def _write(self, path: str, payload: bytes) -> None:
        with self._open_for_write(path) as f:
            f.write(_wrapped(payload, os.path.basename(path), self._stamp))

    def _save_index(self, overloads) -> None:
        payload = pickle.dumps(self._version, protocol=-1)
        self._write(self._index_path, payload + self._dump((self._source_stamp, overloads)))

    def _save_data(self, name, data) -> None:
        self._write(self._data_path(name), self._dump(data))

    def save(self, key, data) -> None:
        """Keep ``data`` under ``key``: the data file first, then the index naming it. A new
        entry's data file has a name of its own (numba numbers them from the index it read,
        so two processes compiling two signatures at once both wrote ``.1.nbc``, and the
        index could send one signature to the other's code)."""
        overloads = self._load_index()
        name = overloads.get(key) or f"{self._index_name[:-4]}.{uuid.uuid4().hex[:16]}.nbc"
        self._save_data(name, data)
        if overloads.get(key) != name:
            overloads[key] = name
            self._save_index(overloads)

    # reading: nothing is unpickled unless its digest vouches for it --------------------
    def _proven(self, path: str, quiet_if_stale: bool = False) -> bytes | None:
        """The bytes numba wrote to ``path``, proven; None when absent, or not proven (with
        a warning naming the file, except a stale index where ``quiet_if_stale``)."""
        try:
            with open(path, "rb") as f:
                raw = f.read()
        except FileNotFoundError:
            return None
        except OSError as exc:
            distrust(path, f"cannot be read ({os_error_message(exc, path, 'reading')})")
            return None
        payload, why = unwrap(raw, os.path.basename(path), self._stamp)
        if payload is None:
            stale = why.startswith(("was compiled from another version", "has no digest"))
            if not (quiet_if_stale and stale):
                distrust(path, why)
        return payload

    def _load_index(self) -> dict:
        payload = self._proven(self._index_path, quiet_if_stale=not self._own_folder)
        if payload is None:
            return {}
        try:
            f = io.BytesIO(payload)
            version = pickle.load(f)
            if version != self._version:  # another numba: stale, as numba has it
                return {}
            stamp, overloads = pickle.loads(f.read())
        except Exception as exc:  # vouched for, yet not numba's: written wrong
            distrust(self._index_path, f"cannot be read as numba's index ({type(exc).__name__})")
            return {}
        return overloads if stamp == self._source_stamp else {}

    def load(self, key):
        name = self._load_index().get(key)
        if name is None:
            return None
        path = self._data_path(name)
        payload = self._proven(path)
        if payload is None:
            return None
        try:
            return pickle.loads(payload)
        except Exception as exc:  # vouched for, yet not numba's: written wrong
            distrust(path, f"cannot be read as numba's data ({type(exc).__name__})")
            return None
