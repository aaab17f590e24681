"""Compiled kernels whose on-disk cache is never older than their source.

numba's ``cache=True`` keys a cached kernel by its *own* file only. A kernel that calls a
jitted function of another module, or reads a constant from one, has that code compiled into
it; edit the other module (or check out another commit, or upgrade a package that moves it)
and numba serves the old machine code, so an edited simulator would store its old physics
under its new key.

:func:`njit` is ``numba.njit`` with a cache whose freshness stamp is the source of the
kernel's file *and* :func:`~sim_tactile.hashing.code_version` of its module: the source of
every module of this package that it imports, directly or through others, with numba's and
numpy's versions. Any edit that could change the compiled code changes the stamp, and numba
compiles again instead of loading.

Where: a kernel is kept by its content, not by where the package lies, in
:func:`kernel_root` (``$SIM_TACTILE_KERNELS``, else under ``$NUMBA_CACHE_DIR``, else
``~/.cache/sim_tactile-kernels``), one
folder per module and stamp (``<module>/<stamp>/``). So the kernels compile once per code
version on a machine, whatever checkout, worktree, clone or installed wheel runs them (a CI
clone's test of its own wheel reads what its suite compiled), two versions side by side
never overwrite each other, and a read-only site-packages needs no ``__pycache__``. Where
that folder cannot be written, numba's own places serve (``$NUMBA_CACHE_DIR``, or
``__pycache__`` beside the source), with the same versioned stamp, and a warning says so;
where none can, the folder is read as it is. A kernel that cannot be kept (a full disk, a
read-only folder) is compiled and used all the same, with a warning that nothing was kept.

Every file is proven before numba reads it (:mod:`sim_tactile._kernel_files`): a digest
binds its bytes to its name and its stamp, and a damaged, truncated, unreadable or
misplaced file is compiled again, with a warning naming it. numba's files are pickles, so
the kernel folder is trusted as code is: share it only with people whose code you would run.

This subclasses numba's cache machinery (``FunctionCache`` and its locators, as numba's own
``enable_caching`` uses them); ``tests/test_jit_cache.py`` edits a callee in another file of
a copy of the package and checks that the kernel, and a slide, move with it.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from pathlib import Path

from . import _aot
from .errors import CacheWarning, os_error_message
from .hashing import PACKAGE, code_version

#: The libraries whose versions change what a kernel compiles to (numba checks its own too).
KERNEL_LIBRARIES = ("numba", "numpy")


def kernel_stamp(module: str) -> str:
    """What a cached kernel of ``module`` must have been compiled from: the code version of
    the module's import closure and of :data:`KERNEL_LIBRARIES`."""
    return code_version(module, libraries=KERNEL_LIBRARIES)


def _stamp_of(module: str) -> str:
    """:func:`kernel_stamp` for this package's modules; none for others (a test's kernel)."""
    return kernel_stamp(module) if module.split(".")[0] == PACKAGE else ""


def kernel_root() -> Path:
    """Where the package's compiled kernels are kept: ``$SIM_TACTILE_KERNELS``, else
    ``$NUMBA_CACHE_DIR/sim_tactile`` where numba's cache is set, else
    ``~/.cache/sim_tactile-kernels``."""
    env = os.environ.get("SIM_TACTILE_KERNELS")
    if env:
        return Path(env)
    numba_dir = os.environ.get("NUMBA_CACHE_DIR")
    if numba_dir:
        return Path(numba_dir) / "sim_tactile"
    return Path.home() / ".cache" / "sim_tactile-kernels"


_said: set[str] = set()


def _once(message: str) -> None:
    """A :class:`~sim_tactile.errors.CacheWarning`, once per process."""
    if message not in _said:
        _said.add(message)
        warnings.warn(message, CacheWarning, stacklevel=3)


#: Code versions of one module kept side by side (the most recently used; a checkout's edits
#: would otherwise pile up a folder of kernels each).
KEEP_VERSIONS = 8


def _prune(current: Path) -> None:
    """Remove the oldest code versions of ``current``'s module beyond :data:`KEEP_VERSIONS`
    (``current`` is marked used now). Best effort: a folder another process holds stays."""
    import shutil

    try:
        os.utime(current)
        versions = sorted(
            (d for d in current.parent.iterdir() if d.is_dir()),
            key=lambda d: d.stat().st_mtime,
            reverse=True,
        )
    except OSError:
        return
    for old in versions[KEEP_VERSIONS:]:
        if old != current:
            shutil.rmtree(old, ignore_errors=True)


def _content_locators(caching) -> tuple[type, type]:
    """The kernel folder's locators, subclassing numba's (``caching``, imported)."""

    class _ContentLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
        """A kernel of this package kept under :func:`kernel_root` by its module's name and
        :func:`kernel_stamp` (not by its file's path); None for other modules, or where the
        folder cannot be written (numba's own locators then serve)."""

        def __init__(self, py_func, py_file) -> None:
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._module = py_func.__module__
            stamp = kernel_stamp(self._module)
            self._stamp = stamp
            self._cache_path = str(kernel_root() / self._module / stamp)

        def get_cache_path(self) -> str:
            return self._cache_path

        def get_source_stamp(self):
            return (super().get_source_stamp(), self._stamp)

        @classmethod
        def from_function(cls, py_func, py_file):
            if py_func.__module__.split(".")[0] != PACKAGE or not os.path.exists(py_file):
                return None
            self = cls(py_func, py_file)
            try:
                self.ensure_cache_path()
            except OSError as exc:  # numba's own places serve, where they can be written
                _once(
                    f"the kernel folder cannot be written ({os_error_message(exc, kernel_root())}): "
                    "the kernels are kept in numba's own cache folders where one can be written "
                    "(set SIM_TACTILE_KERNELS to a writable folder)"
                )
                return None
            _prune(Path(self._cache_path))
            return self

    class _ReadOnlyContentLocator(_ContentLocator):
        """The kernel folder as it is, where no folder can be written: what it holds is read
        (proven), and what is compiled is not kept (:meth:`VersionedFunctionCache.save_overload`
        says so)."""

        @classmethod
        def from_function(cls, py_func, py_file):
            if py_func.__module__.split(".")[0] != PACKAGE or not os.path.exists(py_file):
                return None
            return cls(py_func, py_file)

    return _ContentLocator, _ReadOnlyContentLocator


#: numba's cache machinery subclassed, once numba is imported (code, as numba's dispatchers
#: are: not a memo of values)
_CACHE_CLASS: list[type] = []


def _cache_classes():
    """numba's cache machinery, subclassed (on first need: numba is imported only where a
    kernel is compiled or loaded by numba, :func:`numba_module`); returns
    :class:`VersionedFunctionCache`."""
    if _CACHE_CLASS:
        return _CACHE_CLASS[0]
    from numba.core import caching

    from ._kernel_files import ProvenCacheFile

    _ContentLocator, _ReadOnlyContentLocator = _content_locators(caching)

    def _versioned(base: type) -> type:
        """A numba cache locator like ``base`` whose source stamp also holds the kernel's
        module's :func:`kernel_stamp` (for this package's modules; others as ``base``)."""

        class Locator(base):
            def __init__(self, py_func, py_file) -> None:
                super().__init__(py_func, py_file)
                self._module = py_func.__module__

            def get_source_stamp(self):
                stamp = super().get_source_stamp()
                if self._module.split(".")[0] != PACKAGE:
                    return stamp
                return (stamp, kernel_stamp(self._module))

        Locator.__name__ = Locator.__qualname__ = f"Versioned{base.__name__}"
        return Locator

    class _Impl(caching.CompileResultCacheImpl):
        _locator_classes = [
            _ContentLocator,
            *(
                _versioned(c) if issubclass(c, caching._SourceFileBackedLocatorMixin) else c
                for c in caching.CompileResultCacheImpl._locator_classes
            ),
            _ReadOnlyContentLocator,
        ]

    class VersionedFunctionCache(caching.FunctionCache):
        """numba's per-function cache, its entries stamped with :func:`kernel_stamp` and each
        of its files proven before it is read (:class:`~._kernel_files.ProvenCacheFile`)."""

        _impl_class = _Impl

        def __init__(self, py_func) -> None:
            super().__init__(py_func)
            locator = self._impl.locator
            self._cache_file = ProvenCacheFile(
                self._cache_path,
                self._impl.filename_base,
                locator.get_source_stamp(),
                stamp=_stamp_of(py_func.__module__),
                own_folder=isinstance(locator, _ContentLocator),
            )

        def save_overload(self, sig, data) -> None:
            """Keep a compiled kernel; where it cannot be kept (a full disk, a read-only
            folder), the run goes on with it, and a warning says that nothing was kept."""
            try:
                super().save_overload(sig, data)
            except OSError as exc:
                root = kernel_root()
                where = root if Path(self._cache_path).is_relative_to(root) else self._cache_path
                _once(
                    f"compiled kernels cannot be kept: {os_error_message(exc, where)}; this run "
                    "compiles them and keeps nothing (set SIM_TACTILE_KERNELS to a writable "
                    "folder with free space)"
                )

    _CACHE_CLASS.append(VersionedFunctionCache)
    return VersionedFunctionCache


_numba = None
_hooks: list[Callable] = []


def when_numba(fn: Callable) -> Callable:
    """Run ``fn(numba)`` once numba is imported for the package's kernels
    (:func:`numba_module`), or now if it is: what a module registers with numba (an
    ``overload``) costs nothing to a process that numba never serves."""
    if _numba is not None:
        fn(_numba)
    else:
        _hooks.append(fn)
    return fn


def numba_module():
    """numba, imported (once) with what the package registers with it: the hooks of
    :func:`when_numba`, and the type of an ahead-of-time kernel referred to from a compiled
    one (numba's dispatcher's)."""
    global _numba
    if _numba is None:
        import numba
        from numba.core import types
        from numba.extending import typeof_impl

        @typeof_impl.register(_aot.Kernel)
        def _typeof_kernel(val, c):
            return types.Dispatcher(val.dispatcher)

        _numba = numba
        while _hooks:
            _hooks.pop(0)(numba)
    return _numba


#: The modules through which numba's compiled ``np.linalg`` calls and matrix products find
#: BLAS and LAPACK.
BLAS_MODULES = ("scipy.linalg.cython_blas", "scipy.linalg.cython_lapack")


def blas_alone() -> None:
    """Make scipy's BLAS and LAPACK tables (:data:`BLAS_MODULES`) importable without
    scipy.linalg.

    A compiled kernel that multiplies matrices or calls ``np.linalg`` (``inv``, ``solve``: a
    dense contact set's inverse) finds its BLAS and LAPACK routines, at its first call, by
    importing those modules, whether numba or an extension built ahead of time serves it.
    Imported by name, a module runs its package's ``__init__`` first: all of scipy.linalg,
    with its array-API layer and numpy's f2py, some 0.1 s of CPU of a command that solves a
    dense skin, for two tables of function pointers. Here each extension is loaded from its
    file on its own, under its own name, and the kernels' imports find it; a later ``import
    scipy.linalg`` runs as ever and takes the same modules (the same loaded libraries).
    Where scipy.linalg is imported already, or a file is not where a scipy install puts it,
    nothing more is done and the import goes as it did. Call it before a kernel's first
    matrix product; once is enough."""
    import importlib.machinery
    import importlib.util
    import sys

    if "scipy.linalg" in sys.modules or all(m in sys.modules for m in BLAS_MODULES):
        return
    spec = importlib.util.find_spec("scipy")
    where = [Path(p) / "linalg" for p in (spec.submodule_search_locations or [])] if spec else []
    for name in BLAS_MODULES:
        if name in sys.modules:
            continue
        stem = name.rpartition(".")[2]
        files = [
            w / f"{stem}{sfx}" for w in where for sfx in importlib.machinery.EXTENSION_SUFFIXES
        ]
        for f in files:
            if not f.is_file():
                continue
            loader = importlib.machinery.ExtensionFileLoader(name, str(f))
            found = importlib.util.spec_from_file_location(name, f, loader=loader)
            try:
                module = importlib.util.module_from_spec(found)
                found.loader.exec_module(module)
            except ImportError:
                return
            sys.modules[name] = module
            break


def _dispatcher(f: Callable, options: dict):
    """numba's dispatcher of ``f``, with the versioned on-disk cache."""
    disp = numba_module().njit(**options)(f)
    disp._cache = _cache_classes()(f)  # what numba's enable_caching() does
    return disp


def stamp_folder(module: str) -> Path:
    """The kernel folder of ``module``'s current code version."""
    return kernel_root() / module / kernel_stamp(module)


#: The extensions loaded in this process, per kernel folder and setting (code, as numba's
#: dispatchers are: not a memo of values, and an extension cannot be unloaded): whether
#: kernels were built ahead of time there, and each module's entry points.
_LOADED: dict[tuple[str, bool], dict] = {}


def _marker(cpu: str | None) -> Path | None:
    """The file that says kernels were built ahead of time for the CPU ``cpu``
    (:func:`sim_tactile._aot.cpu_key`) in the kernel folder
    (:func:`sim_tactile._aot_build.build_ahead` writes it)."""
    return None if cpu is None else kernel_root() / f"aot-{cpu}"


def _state() -> dict:
    """This process's state for the kernel folder and setting: whether kernels were built
    ahead of time there, the CPU's key (read once) and the modules' entry points."""
    key = (str(kernel_root()), _aot.enabled())
    state = _LOADED.get(key)
    if state is None:
        cpu = _aot.cpu_key() if key[1] else None
        m = _marker(cpu)
        built = m is not None and m.exists()
        state = _LOADED[key] = {"built": built, "cpu": cpu, "modules": {}}
    return state


def built_ahead() -> bool:
    """Whether kernels were built ahead of time in the kernel folder (then every kernel
    waits for its first call to import numba, so that a process that the extensions serve
    never does)."""
    return _state()["built"]


def ahead_of_time(module: str) -> dict | None:
    """The entry points of ``module``'s ahead-of-time extension by kernel
    (:func:`sim_tactile._aot.load`), loaded once a process; None where there is none."""
    state = _state()
    modules = state["modules"]
    if module not in modules:
        found = None
        if module.split(".")[0] == PACKAGE and state["built"]:
            found = _aot.load(_aot.folder(stamp_folder(module), state["cpu"]), state["cpu"])
        modules[module] = found
    return modules[module]


def njit(fn: Callable | None = None, **options):
    """``numba.njit(**options)`` with the versioned on-disk cache; use as ``@njit`` or
    ``@njit(inline="always")`` (``cache`` is always on: it may not be given). Where the
    module has an ahead-of-time extension (:mod:`sim_tactile._aot`), an
    :class:`~sim_tactile._aot.Kernel` that calls it where it can, and numba (imported then)
    where it cannot."""
    if "cache" in options:
        raise TypeError("njit caches always (with a versioned stamp); do not pass cache=")

    def wrap(f: Callable):
        if not built_ahead():
            return _dispatcher(f, options)
        ahead = ahead_of_time(f.__module__)
        # a module with no extension, where others have one, waits for its first call to
        # import numba
        entries = () if ahead is None else ahead.get(f.__name__, ())
        return _aot.Kernel(f, lambda: _dispatcher(f, options), entries)

    return wrap if fn is None else wrap(fn)


def __getattr__(name: str):
    if name == "VersionedFunctionCache":
        return _cache_classes()
    raise AttributeError(name)


__all__ = [
    "KERNEL_LIBRARIES",
    "kernel_root",
    "kernel_stamp",
    "njit",
    "numba_module",
    "when_numba",
]
