"""A content-addressed artefact cache with atomic writes.

An artefact's key is the content hash (:func:`sim_tactile.hashing.content_hash`) of its whole
description: what it is made from (e.g. a plate's canonical parameters), its kind and
settings, and the version of the code that makes it (:func:`sim_tactile.hashing.code_version`).
Files are written to a temporary name in the same directory, flushed and renamed, so a reader
sees a whole file or none, and an interrupted build leaves nothing behind.

Location: ``$SIM_TACTILE_CACHE`` if set, else ``~/.cache/sim_tactile``.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

from .hashing import code_version, content_hash


def default_root() -> Path:
    env = os.environ.get("SIM_TACTILE_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "sim_tactile"


def atomic_write(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` so that readers see the old file, or the whole new one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


@dataclass(frozen=True)
class ArtefactCache:
    """Artefacts under ``root/<key[:2]>/<key>.<ext>``."""

    root: Path

    @classmethod
    def default(cls) -> ArtefactCache:
        return cls(default_root())

    @staticmethod
    def key(description: dict) -> str:
        """The key of an artefact: the content hash of its whole description."""
        return content_hash(description)

    def path(self, key: str, ext: str) -> Path:
        return Path(self.root) / key[:2] / f"{key}.{ext}"

    def get(self, key: str, ext: str) -> Path | None:
        p = self.path(key, ext)
        return p if p.is_file() else None

    def put(self, key: str, ext: str, data: bytes) -> Path:
        p = self.path(key, ext)
        atomic_write(p, data)
        return p


class ArrayMemo:
    """Read-only arrays kept in this process by their content key, the least recently used
    dropped past ``max_bytes``: a worker that makes many slides of one scene reads a skin's
    matrices from disk once. The key must hold everything the arrays depend on (as the disk
    cache's does), so an entry is never stale; the arrays are made read-only, so no slide can
    change what the next one reads."""

    def __init__(self, max_bytes: int) -> None:
        self.max_bytes = int(max_bytes)
        self._items: dict[str, tuple] = {}
        self._bytes: dict[str, int] = {}

    def get(self, key: str):
        item = self._items.pop(key, None)
        if item is not None:
            self._items[key] = item  # most recently used last
        return item

    def put(self, key: str, item: tuple) -> tuple:
        """Keep ``item`` (a tuple of arrays and plain values), its arrays made read-only."""
        import numpy as np

        size = 0
        for a in item:
            if isinstance(a, np.ndarray):
                a.flags.writeable = False
                size += a.nbytes
        if size > self.max_bytes:
            return item
        self._items.pop(key, None)
        self._items[key], self._bytes[key] = item, size
        while sum(self._bytes.values()) > self.max_bytes:
            old = next(iter(self._items))
            del self._items[old], self._bytes[old]
        return item

    def __len__(self) -> int:
        return len(self._items)


#: The set-up a worker keeps between slides (:func:`setup_memo`): a data set's worker makes
#: tens of slides of one scene, and each had built again what depends only on the sensor,
#: its skin and the grid (taxel weights, small compliance matrices and their inverses, the
#: spectral kernel, the mirror-halved skin): about half of a roughness8 slide's time.
SETUP_MEMO_BYTES = 512 * 2**20
SETUP = ArrayMemo(SETUP_MEMO_BYTES)


def array_digest(a) -> str:
    """The SHA-256 of an array's dtype, shape and bytes: its part of a content key."""
    import hashlib

    import numpy as np

    a = np.ascontiguousarray(a)
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()


def setup_memo(what: str, parts: dict, compute, modules: tuple[str, ...]) -> tuple:
    """``compute()`` (a tuple of arrays and plain values), kept in this process (:data:`SETUP`)
    under the content key of ``what``, ``parts`` (JSON data; arrays as :func:`array_digest`)
    and the source of ``modules`` (and what they import) with numpy's and scipy's versions:
    the key holds everything the value depends on, so it is never stale. The value is the
    computed one, its arrays read-only (tested: slides equal bit for bit either way)."""
    key = content_hash(
        {
            "what": what,
            "parts": parts,
            "code": code_version(*modules, libraries=("numpy", "scipy")),
        }
    )
    kept = SETUP.get(key)
    if kept is not None:
        return kept
    return SETUP.put(key, tuple(compute()))
