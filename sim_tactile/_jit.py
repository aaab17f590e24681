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
``__pycache__`` beside the source), with the same versioned stamp.

This subclasses numba's cache machinery (``FunctionCache`` and its locators, as numba's own
``enable_caching`` uses them); ``tests/test_jit_cache.py`` edits a callee in another file of
a copy of the package and checks that the kernel, and a slide, move with it.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numba
from numba.core import caching

from .hashing import PACKAGE, code_version

#: The libraries whose versions change what a kernel compiles to (numba checks its own too).
KERNEL_LIBRARIES = ("numba", "numpy")


def kernel_stamp(module: str) -> str:
    """What a cached kernel of ``module`` must have been compiled from: the code version of
    the module's import closure and of :data:`KERNEL_LIBRARIES`."""
    return code_version(module, libraries=KERNEL_LIBRARIES)


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
        if py_func.__module__.split(".")[0] != PACKAGE:
            return None
        self = super().from_function(py_func, py_file)
        if self is not None:
            _prune(Path(self._cache_path))
        return self


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
    _locator_classes = [_ContentLocator] + [
        _versioned(c) if issubclass(c, caching._SourceFileBackedLocatorMixin) else c
        for c in caching.CompileResultCacheImpl._locator_classes
    ]


class VersionedFunctionCache(caching.FunctionCache):
    """numba's per-function cache, its entries stamped with :func:`kernel_stamp`."""

    _impl_class = _Impl


def njit(fn: Callable | None = None, **options):
    """``numba.njit(**options)`` with the versioned on-disk cache; use as ``@njit`` or
    ``@njit(inline="always")`` (``cache`` is always on: it may not be given)."""
    if "cache" in options:
        raise TypeError("njit caches always (with a versioned stamp); do not pass cache=")

    def wrap(f: Callable):
        disp = numba.njit(**options)(f)
        disp._cache = VersionedFunctionCache(f)  # what numba's enable_caching() does
        return disp

    return wrap if fn is None else wrap(fn)


__all__ = ["KERNEL_LIBRARIES", "VersionedFunctionCache", "kernel_root", "kernel_stamp", "njit"]
