"""Tables a data set shares: the line between the tables of two force levels, and the cache.

The slides of a set whose tables do not depend on their offset share them at force levels
(:func:`~sim_tactile.sim.plan.phase.force_levels`) and read the line between the two levels' tables (:class:`Blend`).
A table is kept under its content key in this process and in the artefact cache
(:func:`kept_table`), checked as every entry is; workers that share a cache solve a table
once, the first holding a lock on it while it solves.
"""

from __future__ import annotations

import fcntl
import math
import os
import warnings
import zipfile
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from ...cache import SETUP, npz_bytes
from ...errors import CacheWarning
from ..plan.phase import PhasePlan
from .phase_table import PhaseTable

#: The table cache's file kind.
TABLE_EXT = "phase.npz"


@dataclass(frozen=True)
class Blend:
    """Tables of one plan at other forces, read as the line between them in the force:
    ``at(x)`` is ``sum(weight * table.at(x))`` (the interface of :class:`PhaseTable` that the
    tabled slide reads)."""

    tables: tuple[PhaseTable, ...]
    weights: tuple[float, ...]
    levels: tuple[float, ...]

    @property
    def plan(self) -> PhasePlan:
        return self.tables[0].plan

    @property
    def n_taxels(self) -> int:
        return self.tables[0].loads.shape[1]

    @property
    def top(self) -> np.ndarray:
        return np.concatenate([t.top for t in self.tables])

    @property
    def solves(self) -> int:
        return sum(t.solves for t in self.tables)

    def at(self, x: np.ndarray):
        parts = [t.at(x) for t in self.tables]
        return tuple(
            sum(w * p[k] for w, p in zip(self.weights, parts, strict=True)) for k in range(4)
        )

    def describe(self) -> str:
        forces = " and ".join(f"{f:.4g} N" for f in self.levels)
        phases = " and ".join(str(len(t.phases)) for t in self.tables)
        kind, unit = self.plan.units
        return (
            f"{kind} tables at {forces} (shared force levels): {self.plan.describe()}, "
            f"{phases} {unit}, interpolation error below "
            f"{max(max(t.error for t in self.tables), 1e-6):.2g} of the loads"
        )


def kept_table(key: str, build, cache) -> tuple[PhaseTable, bool]:
    """``(table, made)``: the table under ``key`` from this process's memo or ``cache`` (an
    :class:`~sim_tactile.cache.ArtefactCache`, checked as every entry is), else
    ``build()`` kept in both. ``key`` holds everything the table depends on, and a table
    is the same bit for bit whoever builds it, so a slide does not depend on where its
    table came from. Workers that share ``cache`` build a table once: the first holds a
    lock on it (:func:`_building`) while it builds, and the others wait and read it."""
    kept = SETUP.get(key)
    if kept is not None:
        return _from_arrays(kept), False
    if cache is None:
        table = build()
        SETUP.put(key, _to_arrays(table))
        return table, True
    found = _read(key, cache)
    if found is not None:
        return found, False
    with _building(cache, key):
        found = _read(key, cache)  # made by another worker while this one waited
        if found is not None:
            return found, False
        table = build()
        arrays = _to_arrays(table)
        cache.put(key, TABLE_EXT, npz_bytes(dict(zip(_FIELDS, arrays, strict=True))))
    SETUP.put(key, arrays)
    return table, True


def _read(key: str, cache) -> PhaseTable | None:
    """The table under ``key`` in ``cache`` (kept in this process too), or None: absent, or
    damaged and discarded with a warning naming the file."""
    hit = cache.get(key, TABLE_EXT)
    if hit is None:
        return None
    try:
        with np.load(hit, allow_pickle=False) as z:
            arrays = tuple(z[f] for f in _FIELDS)
        if arrays[1].ndim != 2 or any(len(a) != len(arrays[0]) for a in arrays[1:5]):
            raise ValueError("its arrays disagree in length")
        return _from_arrays(SETUP.put(key, arrays))
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        warnings.warn(
            f"cache entry {hit} cannot be read as a phase table "
            f"({type(exc).__name__}: {exc}); it is solved again",
            CacheWarning,
            stacklevel=2,
        )
        cache.discard(key, TABLE_EXT)
        return None


@contextmanager
def _building(cache, key: str):
    """Hold an exclusive ``flock`` on the lock file of table ``key`` beside its cache entry
    while it is built (the kernel drops it when its holder dies, however it dies); where the
    cache's folder takes no lock file, build without one (two workers may then build the
    same table, which is the same bits)."""
    folder = cache.entry(key, TABLE_EXT).parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd = os.open(
            folder / f".{key}.{TABLE_EXT}.lock",
            os.O_RDONLY | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC,
            0o664,
        )
    except OSError:
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


_FIELDS = ("phases", "loads", "force", "top", "z", "plan", "stats")


def _to_arrays(t: PhaseTable) -> tuple:
    p = t.plan
    period = np.nan if p.period_m is None else p.period_m
    plan = np.array([period, p.x_lo, p.x_hi, p.x_ref, p.y_m, float(p.span)])
    return (t.phases, t.loads, t.force, t.top, t.z, plan, np.array([t.solves, t.error]))


def _from_arrays(a: tuple) -> PhaseTable:
    period, lo, hi, ref, y, span = (float(v) for v in a[5])
    plan = PhasePlan(None if math.isnan(period) else period, lo, hi, ref, y, span=bool(span))
    return PhaseTable(plan, a[0], a[1], a[2], a[3], a[4], int(a[6][0]), float(a[6][1]))
