"""What cached and stored results are keyed by: content hashes, code versions, derived seeds.

- :func:`content_hash`: the SHA-256 of an object's canonical JSON (sorted keys, no spaces),
  the one way a description becomes a key (cache keys, plate hashes, store configurations).
- :func:`code_version`: a hash of the source of every module of this package that a given
  module imports, directly or through others (found from the import statements of the source
  itself, those inside functions included), and of the versions of the libraries that
  compute with it. A cached result keyed by it is never served after any of that code
  changes, and no hand-written list of modules can fall behind.
- :func:`derive_seed`: an independent seed for a part of a run (a slide, a split, a model)
  from the run's seed and the part's keys (integers or names).
"""

from __future__ import annotations

import ast
import hashlib
import json
import re
from functools import cache, lru_cache
from importlib import metadata
from pathlib import Path

import numpy as np

from .errors import ConfigError

#: The package whose modules :func:`code_version` follows, and its folder.
PACKAGE = __name__.rpartition(".")[0]
_ROOT = Path(__file__).resolve().parent


def canonical_json(obj: object) -> str:
    """``obj`` as JSON with sorted keys and no spaces: equal data, equal text."""
    try:
        return json.dumps(obj, sort_keys=True, separators=(",", ":"))
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"the description to hash is not JSON data: {exc}") from None


def content_hash(obj: object, digits: int = 64) -> str:
    """The SHA-256 of :func:`canonical_json` of ``obj``, as ``digits`` hex digits."""
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:digits]


def _key_int(key: int | str) -> int:
    if isinstance(key, str):  # a name: its own stable integer (SeedSequence takes any size)
        return int.from_bytes(hashlib.sha256(key.encode()).digest()[:8], "little")
    if isinstance(key, bool) or not isinstance(key, int | np.integer) or key < 0:
        raise ConfigError(f"a seed key must be an integer >= 0 or a name, got {key!r}")
    return int(key)


def derive_seed(seed: int, *keys: int | str, bits: int = 32) -> int:
    """A seed for the part of a run named by ``keys``, independent of every other part's.

    ``bits`` 32: an unsigned 32-bit seed (what scikit-learn and torch take); 63: a seed below
    2**63 (the slides' seeds, stored as int64). Names key a part by what it is, not by its
    position in a list, so adding a classifier never re-seeds the others."""
    if bits not in (32, 63):
        raise ConfigError(f"bits = {bits!r} is not valid; valid: 32, 63")
    ss = np.random.SeedSequence([_key_int(seed), *(_key_int(k) for k in keys)])
    if bits == 32:
        return int(ss.generate_state(1)[0])
    return int(ss.generate_state(1, np.uint64)[0] >> 1)


# ------------------------------------------------------------------------------ code version
@cache
def module_file(name: str) -> Path | None:
    """The source file of the package's module ``name`` (``a.b``: ``a/b.py`` or
    ``a/b/__init__.py``), or None if it is not one of the package's modules."""
    parts = name.split(".")
    if parts[0] != PACKAGE:
        return None
    base = _ROOT.joinpath(*parts[1:])
    for p in (base.with_suffix(".py"), base / "__init__.py"):
        if p.is_file():
            return p
    return None


def _is_package(name: str) -> bool:
    f = module_file(name)
    return f is not None and f.name == "__init__.py"


def _resolve(name: str, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    package = name if _is_package(name) else name.rpartition(".")[0]
    base = package.split(".")
    if node.level > 1:
        base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(name: str) -> frozenset[str]:
    """The package's modules that module ``name`` imports anywhere in its source (at the top,
    inside functions, or under ``TYPE_CHECKING``), with the packages they sit in. Read once a
    process, as :func:`code_version` is."""
    return _imports_of(name)


#: A line that starts an import statement (at any indent: inside functions too).
_IMPORT_START = re.compile(rb"^[ \t]*(?:from[ \t]+[.\w]+[ \t]+import|import)[ \t(\\]", re.M)


def import_statements(source: bytes) -> list[ast.stmt]:
    """The import statements of a module's ``source``, each parsed on its own: the lines that
    start one are found by a scan (parentheses and backslashes followed), so that a module is
    not parsed whole (a tenth of the time; the same set as ``ast.walk`` of the whole module,
    tested on every module of the package). A line of a string that reads like an import is
    parsed too and, if it names a module of the package, counted: more, never fewer."""
    out = []
    for m in _IMPORT_START.finditer(source):
        end = source.find(b"\n", m.start())
        end = len(source) if end < 0 else end
        stmt = source[m.start() : end]
        while (stmt.count(b"(") > stmt.count(b")") or stmt.rstrip().endswith(b"\\")) and end < len(
            source
        ):
            nxt = source.find(b"\n", end + 1)
            end = len(source) if nxt < 0 else nxt
            stmt = source[m.start() : end]
        try:
            out += ast.parse(stmt.strip().replace(b"\\\n", b" ")).body
        except SyntaxError:  # prose that reads like an import
            continue
    return out


@cache
def _source(name: str) -> bytes:
    """The source of the package's module ``name``, read once a process: the module as this
    process imported it, whose code versions (:func:`code_version`) each read it again (a
    command's kernel modules read some 40 files each, 700 reads)."""
    return module_file(name).read_bytes()


@cache
def _imports_of(name: str) -> frozenset[str]:
    f = module_file(name)
    if f is None:
        return frozenset()
    out: set[str] = set()
    for node in import_statements(_source(name)):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            mod = _resolve(name, node)
            targets = [mod] + [f"{mod}.{a.name}" for a in node.names if a.name != "*"]
        else:
            continue
        for t in targets:
            if module_file(t) is not None:
                out.add(t)
    # importing a module runs the packages it sits in
    for t in list(out):
        parts = t.split(".")
        out.update(".".join(parts[:k]) for k in range(1, len(parts)))
    out.discard(name)
    return frozenset(out)


def import_closure(*roots: str) -> tuple[str, ...]:
    """Every module of the package that importing ``roots`` can run, sorted: the roots, the
    packages they sit in and, transitively, what each of those imports."""
    todo = []
    for r in roots:
        if module_file(r) is None:
            raise ConfigError(f"{r!r} is not a module of {PACKAGE}")
        parts = r.split(".")
        todo += [".".join(parts[:k]) for k in range(1, len(parts) + 1)]
    seen: set[str] = set()
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        seen.add(m)
        todo.extend(imports_of(m) - seen)
    return tuple(sorted(seen))


@cache
def _library_version(dist: str) -> str:
    """An installed distribution's version, looked up once per process (importlib.metadata
    scans the environment's dist-info folders: 40 look-ups cost some 0.1 s of a command's
    start-up)."""
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "absent"


@lru_cache(maxsize=1)
def blas_controller():
    """threadpoolctl's view of this process's BLAS thread pools, numpy's and scipy's, taken
    once (a fresh look scans the loaded libraries, 2-3 ms: a slide of roughness8 took two).
    scipy's library is loaded for it without importing scipy.linalg
    (:func:`_load_scipy_blas`; that import took 0.14-0.16 s of every command's start-up,
    where most slides never call it): scipy.linalg, imported later, runs on that library,
    under the same limits."""
    import numpy  # noqa: F401
    from threadpoolctl import ThreadpoolController

    _load_scipy_blas()
    return ThreadpoolController()


def one_blas_thread():
    """A context manager: the BLAS libraries run on one thread inside it (a worker process
    simulates on one core; BLAS's own threads would only contend)."""
    return blas_controller().limit(limits=1, user_api="blas")


@lru_cache(maxsize=1)
def blas_kernel() -> str:
    """The BLAS kernel of numpy's and scipy's libraries (OpenBLAS picks one by CPU:
    ``Haswell``, ``SkylakeX``, ...; ``"unknown"`` when threadpoolctl cannot tell). Arrays a
    BLAS call makes on one kernel differ from another's in their last bits, so what is
    cached on disk from them is keyed by it. The same whatever this process has imported
    (:func:`blas_controller` loads scipy's library)."""
    found = {i.get("architecture") for i in blas_controller().info() if i.get("user_api") == "blas"}
    found.discard(None)
    return "+".join(sorted(found)) or "unknown"


def _load_scipy_blas() -> None:
    """Load scipy's BLAS library (without scipy.linalg's import): the one a wheel bundles
    (``scipy.libs`` beside the package on Linux, ``scipy/.dylibs`` on macOS), else import
    scipy.linalg, which loads whichever it links to."""
    import ctypes
    import importlib.util
    import sys

    if "scipy.linalg" in sys.modules:
        return
    spec = importlib.util.find_spec("scipy")
    where = [Path(p) for p in (spec.submodule_search_locations or [])] if spec else []
    libs = [
        lib
        for w in where
        for folder in (w.parent / "scipy.libs", w / ".dylibs")
        for lib in sorted(folder.glob("*openblas*"))
    ]
    loaded = 0
    for lib in libs:
        try:
            ctypes.CDLL(str(lib))
            loaded += 1
        except OSError:
            continue
    if not loaded:
        import scipy.linalg  # noqa: F401


def array_digest(*arrays, header: bool = True) -> str:
    """The SHA-256 (hex) of arrays' bytes in C order, each preceded by its dtype and shape
    where ``header`` (an array's part of a content key: equal bytes of another dtype or shape
    key apart); without it, the bytes alone (a height map's recorded ``sha256``, an exported
    data set's name)."""
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        if header:
            h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def file_digest(path: Path) -> str:
    """The sha256 of a file's bytes ("absent" when it does not exist)."""
    path = Path(path)
    return hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else "absent"


@lru_cache(maxsize=64)
def code_version(*roots: str, libraries: tuple[str, ...] = ()) -> str:
    """A 16-hex-digit hash of the source of :func:`import_closure` of ``roots`` and of the
    installed versions of ``libraries`` (distribution names). Computed once per process."""
    h = hashlib.sha256()
    for m in import_closure(*roots):
        h.update(m.encode() + b"\0")
        h.update(_source(m))
        h.update(b"\0")
    for lib in sorted(libraries):
        h.update(f"{lib}=={_library_version(lib)}\0".encode())
    return h.hexdigest()[:16]
