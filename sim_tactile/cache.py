"""A content-addressed artefact cache with atomic writes.

An artefact's key is the content hash (:func:`sim_tactile.hashing.content_hash`) of its whole
description: what it is made from (e.g. a plate's canonical parameters), its kind and
settings, and the version of the code that makes it (:func:`sim_tactile.hashing.code_version`).

An entry is a folder, ``<key[:2]>/<key>.<ext>.d/``, holding the artefact ``<key>.<ext>`` and
its checksum ``<key>.<ext>.sum`` (the key it was stored under, the SHA-256 and size of its
bytes). Both are written into a fresh temporary folder beside it, which is then renamed into
place: a reader sees the whole entry, artefact and checksum of one writer, or none. Two
processes that make the same artefact at once each build their own folder; the first rename
wins and the second keeps the entry it finds whole (an artefact's bytes are a function of
its content: :func:`npz_bytes`), so neither warns of corruption. An interrupted writer
leaves its temporary folder, never a half entry.

:meth:`ArtefactCache.get` serves an entry only when its checksum agrees with the key asked
for and with the bytes on disk; an entry that was altered, truncated, moved under another
key, left without its checksum or cannot be read is discarded with a
:class:`~sim_tactile.errors.CacheWarning` naming the file, and made again. What an entry
holds is for its kind to check further (a cached slide names its own key, plate and seed:
:func:`~sim_tactile.slides.jobs.cached_slide`). A cache that cannot be written (a full disk,
a read-only folder) raises :class:`~sim_tactile.errors.CacheError` in one line; a read-only
cache whose entries are all there is read as usual.

Location: ``$SIM_TACTILE_CACHE`` if set, else ``~/.cache/sim_tactile``.
"""

from __future__ import annotations

import errno
import hashlib
import io
import json
import os
import shutil
import tempfile
import uuid
import warnings
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from .errors import CacheError, CacheWarning, os_error_message
from .hashing import blas_kernel, code_version, content_hash, one_blas_thread

#: The suffix of an entry's checksum file.
SUM_SUFFIX = ".sum"
#: The suffix of an entry's folder.
ENTRY_SUFFIX = ".d"
#: The time stamp of every member of an .npz written by :func:`npz_bytes` (the zip format's
#: earliest): its bytes then depend on its arrays only.
NPZ_DATE_TIME = (1980, 1, 1, 0, 0, 0)


def default_root() -> Path:
    """The cache's folder: ``$SIM_TACTILE_CACHE``, or ``~/.cache/sim_tactile``."""
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


def npz_bytes(arrays: dict) -> bytes:
    """The bytes of an uncompressed ``.npz`` of ``arrays`` (name -> array; what
    :func:`numpy.savez` writes and :func:`numpy.load` reads, without pickle), a function of
    the arrays alone: every member carries :data:`NPZ_DATE_TIME` (``numpy.savez`` stamps
    each with the wall clock, so two writes of the same arrays differed)."""
    import numpy as np

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name, value in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=NPZ_DATE_TIME)
            info.external_attr = 0o644 << 16
            with zf.open(info, "w", force_zip64=True) as f:
                np.lib.format.write_array(f, np.asanyarray(value), allow_pickle=False)
    return buf.getvalue()


@dataclass(frozen=True)
class ArtefactCache:
    """Artefacts under ``root/<key[:2]>/<key>.<ext>.d/<key>.<ext>`` (see the module
    docstring)."""

    root: Path

    @classmethod
    def default(cls) -> ArtefactCache:
        return cls(default_root())

    @staticmethod
    def key(description: dict) -> str:
        """The key of an artefact: the content hash of its whole description."""
        return content_hash(description)

    def entry(self, key: str, ext: str) -> Path:
        """The folder of the entry ``key``, ``ext``."""
        return Path(self.root) / key[:2] / f"{key}.{ext}{ENTRY_SUFFIX}"

    def path(self, key: str, ext: str) -> Path:
        """The artefact's file in its entry."""
        return self.entry(key, ext) / f"{key}.{ext}"

    def get(self, key: str, ext: str) -> Path | None:
        """The entry's path if it is there and proves to be the one stored under ``key``,
        else None (a damaged entry is discarded, with a warning naming it)."""
        p = self.path(key, ext)
        if not p.parent.is_dir():
            return None
        bad = _check_entry(p, key)
        if bad is None:
            return p
        warnings.warn(f"cache entry {p}: {bad}; it is made again", CacheWarning, stacklevel=2)
        self.discard(key, ext)
        return None

    def put(self, key: str, ext: str, data: bytes) -> Path:
        """Store ``data`` under ``key``: the bytes and their checksum, written into a
        temporary folder renamed into place as one. Where a whole entry of ``key`` is there
        already (another process made it meanwhile), it is kept and this one dropped.
        Returns the artefact's path; raises CacheError when the cache cannot be written."""
        p = self.path(key, ext)
        record = {"key": key, "sha256": hashlib.sha256(data).hexdigest(), "size": len(data)}
        try:
            p.parent.parent.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(dir=p.parent.parent, prefix=f".{p.name}.", suffix=".tmp"))
            try:
                atomic_write(tmp / p.name, data)
                atomic_write(_sum_path(tmp / p.name), json.dumps(record).encode())
                _install(tmp, p, key)
            finally:
                shutil.rmtree(tmp, ignore_errors=True)  # (gone where it was renamed)
        except OSError as exc:
            raise CacheError(
                f"the cache cannot be written: {os_error_message(exc, p)} (set "
                "SIM_TACTILE_CACHE to a writable folder with free space)"
            ) from None
        return p

    def discard(self, key: str, ext: str) -> None:
        """Remove an entry, its artefact and checksum as one (nothing if it is not there)."""
        _set_aside(self.entry(key, ext))


#: How often :func:`_install` tries to replace a damaged entry that others replace too.
_INSTALL_TRIES = 4


def _install(tmp: Path, p: Path, key: str) -> None:
    """Rename the entry folder ``tmp`` to ``p``'s folder. One already there is kept when it
    is whole (another writer's, of the same content), else set aside and replaced."""
    for _ in range(_INSTALL_TRIES):
        try:
            os.rename(tmp, p.parent)
            return
        except OSError as exc:
            if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                raise
        if _check_entry(p, key) is None:
            return
        _set_aside(p.parent)
    raise OSError(errno.EBUSY, "other writers kept replacing the entry", str(p.parent))


def _set_aside(entry: Path) -> None:
    """Remove the entry folder ``entry`` as one: renamed away first (a reader then finds
    the whole entry or none), then deleted."""
    gone = entry.with_name(f".{entry.name}.{uuid.uuid4().hex[:12]}.gone")
    try:
        os.rename(entry, gone)
    except OSError:  # not there, or a read-only cache: the entry is not served, nothing more
        return
    shutil.rmtree(gone, ignore_errors=True)


def _sum_path(p: Path) -> Path:
    return p.with_name(p.name + SUM_SUFFIX)


def _check_entry(p: Path, key: str) -> str | None:
    """None if the entry at ``p`` is the one stored under ``key``, else what is wrong."""
    try:
        record = json.loads(_sum_path(p).read_bytes())
    except FileNotFoundError:
        return "no checksum beside it"
    except (OSError, ValueError) as exc:
        return f"its checksum file cannot be read ({type(exc).__name__})"
    if not isinstance(record, dict) or record.get("key") != key:
        got = record.get("key") if isinstance(record, dict) else None
        return f"it was stored under another key ({str(got)[:16]}...)"
    h = hashlib.sha256()
    size = 0
    try:
        with open(p, "rb") as f:
            while chunk := f.read(1 << 20):
                h.update(chunk)
                size += len(chunk)
    except OSError as exc:
        return f"it cannot be read ({exc.strerror or exc})"
    if size != record.get("size") or h.hexdigest() != record.get("sha256"):
        return "its bytes do not match their checksum (altered or truncated)"
    return None


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
        """Keep ``item`` (a tuple of arrays and plain values), its arrays made read-only, and
        the arrays they are views of (an array read from a cache entry is a view of the
        buffer it was read into): no reference left elsewhere can change what is kept, so
        what is read once from a kept array holds for it
        (:func:`~sim_tactile.sim.skin.contact.active_set.skin_floor`)."""
        import numpy as np

        size = 0
        for a in item:
            if isinstance(a, np.ndarray):
                size += a.nbytes
                view = a
                while isinstance(view, np.ndarray):  # a and every array it is a view of
                    view.flags.writeable = False
                    view = view.base
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

    def clear(self) -> None:
        """Forget every array kept."""
        self._items.clear()
        self._bytes.clear()


#: The set-up a worker keeps between slides (:func:`setup_memo`): a data set's worker makes
#: tens of slides of one scene, and each had built again what depends only on the sensor,
#: its skin and the grid (taxel weights, small compliance matrices and their inverses, the
#: spectral kernel, the mirror-halved skin): about half of a roughness8 slide's time.
SETUP_MEMO_BYTES = 512 * 2**20
SETUP = ArrayMemo(SETUP_MEMO_BYTES)


def setup_memo(
    what: str, parts: dict, compute, modules: tuple[str, ...], cache: ArtefactCache | None = None
) -> tuple:
    """``compute()`` (a tuple of arrays and plain values), kept in this process (:data:`SETUP`)
    under the content key of ``what``, ``parts`` (JSON data; arrays as :func:`~sim_tactile.hashing.array_digest`)
    and the source of ``modules`` (and what they import) with numpy's and scipy's versions:
    the key holds everything the value depends on, so it is never stale. The value is the
    computed one, its arrays read-only (tested: slides equal bit for bit either way). It is
    computed on one BLAS thread, as a slide computes (:func:`~sim_tactile.hashing.one_blas_thread`):
    BLAS's threads sum in another order, and a value made outside a slide (a script's, a
    test's) differed in its last bits from the slide's own under the same key (the layered
    compliance table of finger7-v2's skin, 2e-27 m/Pa).

    With ``cache`` (an :class:`ArtefactCache`), a value of arrays alone is also kept on disk
    (:data:`SETUP_EXT`, its key then holding the BLAS kernel too, as another CPU's kernel
    makes arrays bit-different): the next process reads it instead of computing it again
    (the iCub's taxel weights: 0.2-0.25 s a grid for each worker of each data set). The
    arrays read are the computed ones, bit for bit."""
    description = {
        "what": what,
        "parts": parts,
        "code": code_version(*modules, libraries=("numpy", "scipy")),
    }
    if cache is not None:
        description["blas"] = blas_kernel()
    key = content_hash(description)
    kept = SETUP.get(key)
    if kept is not None:
        return kept
    if cache is not None:
        read = _read_setup(cache, key)
        if read is not None:
            return SETUP.put(key, read)
    with one_blas_thread():
        value = tuple(compute())
    if cache is not None:
        _write_setup(cache, key, value)
    return SETUP.put(key, value)


#: The file kind of a set-up value kept on disk (:func:`setup_memo` with a cache).
SETUP_EXT = "setup.npz"


def _read_setup(cache: ArtefactCache, key: str) -> tuple | None:
    """The arrays stored under ``key``, in order, or None."""
    z = read_arrays(cache, key, SETUP_EXT, "set-up arrays", ("a0",))
    return None if z is None else tuple(z[f"a{i}"] for i in range(len(z)))


def read_arrays(
    cache: ArtefactCache, key: str, ext: str, what: str, names: tuple[str, ...] = ()
) -> dict | None:
    """The arrays of the ``.npz`` entry ``key``, ``ext`` (name -> array, read without pickle),
    or None where it is not there, or cannot be read as such or lacks one of ``names``:
    then it is discarded with a warning that it is not ``what`` and is made again."""
    import numpy as np

    hit = cache.get(key, ext)
    if hit is None:
        return None
    try:
        with np.load(hit, allow_pickle=False) as z:
            got = {name.removesuffix(".npy"): z[name] for name in z.files}
        if missing := set(names) - got.keys():
            raise KeyError(sorted(missing))
        return got
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        warnings.warn(
            f"cache entry {hit} cannot be read as {what} ({type(exc).__name__}); it is made again",
            CacheWarning,
            stacklevel=3,
        )
        cache.discard(key, ext)
        return None


def _write_setup(cache: ArtefactCache, key: str, value: tuple) -> None:
    import numpy as np

    if not all(isinstance(a, np.ndarray) for a in value):
        raise TypeError("a set-up value kept on disk is a tuple of arrays")
    cache.put(key, SETUP_EXT, npz_bytes({f"a{i}": a for i, a in enumerate(value)}))


# ------------------------------------------------------------------------- in-process memos
#: How to forget each of the package's in-process memos, by name: what a module keeps in the
#: process (:data:`SETUP`, the compiled scene models, users' plates, a height map's scales,
#: the functions of :func:`memoized`) registers here (:func:`register_memo`), and
#: :func:`forget_process_memos` forgets them all.
_MEMOS: dict[str, Callable[[], None]] = {"set-up arrays": SETUP.clear}


def register_memo(name: str, forget: Callable[[], None]) -> None:
    """Register an in-process memo: ``forget()`` empties it. ``name`` says what it keeps."""
    _MEMOS[name] = forget


def memoized(name: str, maxsize: int | None = 128):
    """``functools.lru_cache(maxsize)``, registered as the in-process memo ``name`` (the
    decorated function's values must depend on its arguments alone)."""

    def wrap(f):
        kept = lru_cache(maxsize=maxsize)(f)
        register_memo(name, kept.cache_clear)
        return kept

    return wrap


def forget_process_memos() -> tuple[str, ...]:
    """Forget everything this package keeps in the process: the registered memos (those of
    modules not imported yet hold nothing) and the source and asset reads of
    :mod:`~sim_tactile.hashing` and :mod:`~sim_tactile.toml_text`, which sit below this
    module. The next call of each computes afresh. Returns the names of the memos."""
    from . import hashing, toml_text

    for f in (
        hashing.module_file,
        hashing._imports_of,
        hashing.code_version,
        hashing.blas_kernel,
        toml_text.asset_data,
    ):
        f.cache_clear()
    for forget in _MEMOS.values():
        forget()
    return tuple(sorted(_MEMOS))


__all__ = [
    "ArtefactCache",
    "default_root",
    "forget_process_memos",
]
