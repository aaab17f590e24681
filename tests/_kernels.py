"""A small real kernel for the kernel folder's tests: ``rect_entry`` of sim/skin/clipped.py
(Love's rectangle, a scalar function), compiled afresh through :func:`sim_tactile._jit.njit`
into the folder that ``SIM_TACTILE_KERNELS`` names."""

from __future__ import annotations

import warnings
from pathlib import Path

from sim_tactile._jit import kernel_stamp, njit
from sim_tactile.errors import CacheWarning
from sim_tactile.sim.skin import clipped

ARGS = (1.0e-3, 2.0e-3, 0.5e-3, 0.7e-3)
MODULE = "sim_tactile.sim.skin.clipped"


def fresh():
    """A new dispatcher of the kernel, its cache in ``$SIM_TACTILE_KERNELS``."""
    return njit(clipped.rect_entry.py_func)


def run() -> tuple[float, int, int, list[str]]:
    """The kernel's value at :data:`ARGS`, its cache hits and misses, and the warnings."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        disp = fresh()
        value = disp(*ARGS)
    hits = sum(disp.stats.cache_hits.values())
    misses = sum(disp.stats.cache_misses.values())
    return value, hits, misses, [str(w.message) for w in caught if w.category is CacheWarning]


def kernel_file(folder: Path, ext: str) -> Path:
    """The kernel's index (``nbi``) or its data file (``nbc``), of this code version."""
    (hit,) = (folder / MODULE / kernel_stamp(MODULE)).glob(f"clipped.rect_entry-*.{ext}")
    return hit


def compile_into(folder: Path) -> float:
    """Compile the kernel (and its callee ``_F``, another kernel) into the kernel folder
    ``folder``; the kernel's value."""
    import pytest

    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SIM_TACTILE_KERNELS", str(folder))
        value, hits, misses, said = run()
        njit(clipped._F.py_func)(1.0, 2.0)
    assert (hits, misses, said) == (0, 1, [])
    return value
