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
compiles again (and overwrites the stale entry) instead of loading. The cache stays where
numba puts it (``__pycache__`` beside the source, or ``$NUMBA_CACHE_DIR``).

This subclasses numba's cache machinery (``FunctionCache`` and its locators, as numba's own
``enable_caching`` uses them); ``tests/test_jit_cache.py`` edits a callee in another file of
a copy of the package and checks that the kernel, and a slide, move with it.
"""

from __future__ import annotations

from collections.abc import Callable

import numba
from numba.core import caching

from .hashing import PACKAGE, code_version

#: The libraries whose versions change what a kernel compiles to (numba checks its own too).
KERNEL_LIBRARIES = ("numba", "numpy")


def kernel_stamp(module: str) -> str:
    """What a cached kernel of ``module`` must have been compiled from: the code version of
    the module's import closure and of :data:`KERNEL_LIBRARIES`."""
    return code_version(module, libraries=KERNEL_LIBRARIES)


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


__all__ = ["KERNEL_LIBRARIES", "VersionedFunctionCache", "kernel_stamp", "njit"]
