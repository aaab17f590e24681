"""A content-addressed artefact cache with atomic writes.

An artefact's key is the SHA-256 of its canonical description: what it is made from (e.g. a
plate's canonical parameters), its kind and settings, and the version of the code that makes
it. Files are written to a temporary name in the same directory, flushed and renamed, so a
reader sees a whole file or none, and an interrupted build leaves nothing behind.

Location: ``$SIM_TACTILE_CACHE`` if set, else ``~/.cache/sim_tactile``.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

from .errors import CacheError


def default_root() -> Path:
    env = os.environ.get("SIM_TACTILE_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "sim_tactile"


def source_version(*modules: object) -> str:
    """A short hash of the source files of the given modules (the 'code version')."""
    h = hashlib.sha256()
    for mod in modules:
        path = Path(getattr(mod, "__file__", "") or "")
        h.update(path.name.encode())
        h.update(path.read_bytes() if path.is_file() else b"")
    return h.hexdigest()[:16]


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
        try:
            blob = json.dumps(description, sort_keys=True, separators=(",", ":"))
        except TypeError as exc:
            raise CacheError(f"cache key description is not JSON data: {exc}") from None
        return hashlib.sha256(blob.encode()).hexdigest()

    def path(self, key: str, ext: str) -> Path:
        return Path(self.root) / key[:2] / f"{key}.{ext}"

    def get(self, key: str, ext: str) -> Path | None:
        p = self.path(key, ext)
        return p if p.is_file() else None

    def put(self, key: str, ext: str, data: bytes) -> Path:
        p = self.path(key, ext)
        atomic_write(p, data)
        return p
