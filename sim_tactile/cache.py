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

from .hashing import content_hash


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
