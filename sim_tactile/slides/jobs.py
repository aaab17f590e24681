"""One slide to simulate, and its key: everything that determines its recording.

A job is a :class:`~sim_tactile.sim.plan.slide.Slide` (the plate itself, the whole sensor, the
nominal protocol with its jitters, the slide's own seed, the fidelity, whether to record the
ideal loads, the pad when it replaces the sensor's, how it is computed). Its key
(:func:`slide_key`) is the content hash of its description and of :func:`slide_code_version`,
so a cached slide is never served after any of it, or any code that makes a slide, has
changed. :class:`SlideJob` is a Slide with that key and :meth:`~SlideJob.simulate`.
"""

from __future__ import annotations

import time
import warnings
import zipfile
from dataclasses import dataclass, replace

import numpy as np

from ..cache import ArtefactCache, memoized
from ..errors import CacheWarning, SimTactileError
from ..hashing import code_version, content_hash, file_digest
from ..records import Recording
from ..sim.plan import measured_errors
from ..sim.plan.options import StepOptions
from ..sim.plan.slide import Slide

#: The module whose import closure makes a slide (with this one, which calls it), and the
#: libraries whose versions change what it computes.
SLIDE_MODULES = ("sim_tactile.sim.slide", "sim_tactile.sim.rig_sim", "sim_tactile.slides.jobs")
SLIDE_LIBRARIES = ("mujoco", "numba", "numpy", "scipy")
#: Data files the slide's code reads and whose content changes a slide: the measured errors
#: from which ``auto`` picks its node grid.
SLIDE_DATA = (measured_errors.TABLE,)


def slide_code_version() -> str:
    """The version of the code that makes a slide (:func:`~sim_tactile.hashing.code_version`
    of :data:`SLIDE_MODULES`): the source of every module they import, the libraries, and
    the data files of :data:`SLIDE_DATA`, each read once a process, as the code reads them
    (the measured errors are a process's memo too: both are read again after
    :func:`~sim_tactile.cache.forget_process_memos`)."""
    return _code_version(tuple(SLIDE_DATA))


@memoized("slide code version", maxsize=8)
def _code_version(data: tuple) -> str:
    return content_hash(
        {
            "code": code_version(*SLIDE_MODULES, libraries=SLIDE_LIBRARIES),
            "data": [file_digest(p) for p in data],
        }
    )[:16]


def slide_key(slide: Slide) -> str:
    """A slide's cache key: the content hash of its description
    (:meth:`~sim_tactile.sim.plan.slide.Slide.describe`) and the code version."""
    return content_hash({**slide.describe(), "code": slide_code_version()})


def simulate_slide(slide: Slide, cache: ArtefactCache | None = None):
    """Simulate ``slide`` on its scene (the finger's, or the probe rig's); a
    :class:`~sim_tactile.sim.step.sampling.SimResult`. An error names the slide and its
    seed."""
    try:
        if slide.rig is not None:
            from ..sim.rig_sim import run_rig

            return run_rig(slide)
        from ..sim.slide import run

        return run(slide, cache)
    except SimTactileError as exc:
        raise type(exc)(f"slide of {slide.named()} (seed {slide.seed}): {exc}") from exc


class SlideJob(Slide):
    """A :class:`~sim_tactile.sim.plan.slide.Slide` with its cache key (:meth:`key`) and
    :meth:`simulate`: what a data set's jobs are. It adds no field: a slide is described in
    one place. ``solve_every`` and ``solve_tol`` as keywords are the knobs of its
    ``options`` (one release; then pass ``options=StepOptions(...)``)."""

    def __init__(self, *args, solve_every=None, solve_tol=None, **kwargs) -> None:
        if solve_every is not None or solve_tol is not None:
            base = kwargs.pop("options", None) or StepOptions()
            knobs = {"solve_every": solve_every, "solve_tol": solve_tol}
            kwargs["options"] = replace(base, **{k: x for k, x in knobs.items() if x is not None})
        super().__init__(*args, **kwargs)

    def key(self) -> str:
        """:func:`slide_key`."""
        return slide_key(self)

    def simulate(self, cache: ArtefactCache | None = None):
        """:func:`simulate_slide`."""
        return simulate_slide(self, cache)


@dataclass(frozen=True)
class SlideOutcome:
    """What simulating (or reading) one slide gave: the recording, the simulation's warnings
    (a cached slide's, as its simulation gave them), the wall time [s] and whether it was
    cached."""

    recording: Recording
    warnings: tuple[str, ...]
    wall_s: float
    cached: bool

    @property
    def data(self) -> np.ndarray:
        return np.asarray(self.recording.data, np.float32)


@dataclass(frozen=True)
class SlideWorker:
    """Simulates a job in a worker, through the slide cache at ``cache_root``: a cached slide
    is read, else simulated and, with ``write``, saved there. Picklable, so any backend can
    send it to its workers."""

    cache_root: str
    write: bool = True

    def __call__(self, job: Slide) -> SlideOutcome:
        t0 = time.perf_counter()
        cache = ArtefactCache(self.cache_root)
        key = slide_key(job)
        rec = cached_slide(cache, job, key)
        if rec is not None:  # with the warnings its simulation gave (kept in its meta)
            warns = tuple(str(w) for w in rec.meta.get("warnings") or ())
            return SlideOutcome(rec, warns, time.perf_counter() - t0, True)
        res = simulate_slide(job, cache)
        if self.write:
            cache.put(key, SLIDE_EXT, entry_bytes(res.recording, key))
        return SlideOutcome(res.recording, tuple(res.warnings), time.perf_counter() - t0, False)


#: The slide cache's file kind.
SLIDE_EXT = "slide.npz"
#: The keys of a recording's meta that hold wall-clock times: left out of a cached slide
#: (two simulations of one slide differ in them alone, and an entry's bytes are its content)
TIMING_KEYS = ("wall_s", "slide_wall_s")


def entry_bytes(rec: Recording, key: str) -> bytes:
    """The bytes a slide is cached as: its recording without wall times
    (:data:`TIMING_KEYS`), its meta naming the slide's key (``slide_key``), as an .npz
    without time stamps: the same slide gives the same bytes in any process, at any time."""
    meta = {k: v for k, v in rec.meta.items() if k not in TIMING_KEYS}
    meta["slide_key"] = key
    return Recording(rec.data, rec.times, rec.taxels, rec.units, meta).to_npz()


def cached_slide(cache: ArtefactCache, job: Slide, key: str | None = None) -> Recording | None:
    """The slide of ``job`` (its key: ``key``, else :meth:`SlideJob.key`) from the cache, or
    None: absent, or damaged and discarded with a warning naming the file (the slide is
    then simulated again). The entry is checked against its key and checksum
    (:meth:`~sim_tactile.cache.ArtefactCache.get`), then what it holds against the job: its
    own key, plate and seed (a checksum file forged for an entry copied under another key
    passes the first check, never this one)."""
    key = key or slide_key(job)
    hit = cache.get(key, SLIDE_EXT)
    if hit is None:
        return None
    try:
        rec = Recording.load(hit)
        why = _not_the_jobs(rec.meta, job, key)
    except (SimTactileError, OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        why = f"cannot be read as a slide ({type(exc).__name__})"
    if why is None:
        return rec
    warnings.warn(f"cache entry {hit} {why}; it is simulated again", CacheWarning, stacklevel=2)
    cache.discard(key, SLIDE_EXT)
    return None


def _not_the_jobs(meta: dict, job: Slide, key: str) -> str | None:
    """None if a cached slide's meta names ``job``'s key, plate and seed, else how not."""
    if meta.get("slide_key") != key:
        return f"holds the slide of another key ({str(meta.get('slide_key'))[:16]}...)"
    if meta.get("plate_hash") != job.plate.hash:
        return f"holds a slide of another plate ({meta.get('plate')!r})"
    if meta.get("seed") != job.seed:
        return f"holds the slide of seed {meta.get('seed')!r}, not {job.seed}"
    return None
