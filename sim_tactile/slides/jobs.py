"""One slide to simulate, and its key: everything that determines its recording.

A :class:`SlideJob` holds the plate itself (its parameters, not a name), the whole sensor, the
nominal protocol with its jitters, the slide's own seed, the fidelity, whether to record the
ideal loads, and the pad when it replaces the sensor's. Its :meth:`~SlideJob.key` is the
content hash of all of that and of :func:`slide_code_version`, so a cached slide is never
served after any of it, or any code that makes a slide, has changed.
"""

from __future__ import annotations

import time
import warnings
import zipfile
from dataclasses import dataclass, field

import numpy as np

from ..cache import ArtefactCache
from ..errors import CacheWarning, SimTactileError
from ..hashing import code_version, content_hash, file_digest
from ..plates import Plate
from ..records import Recording
from ..sensors import Finger, Sensor
from ..sim.plan import measured_errors
from ..sim.plan.protocol import Protocol, SlideWindow
from ..sim.plan.rig import ProbeRig

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
    the data files of :data:`SLIDE_DATA`."""
    return content_hash(
        {
            "code": code_version(*SLIDE_MODULES, libraries=SLIDE_LIBRARIES),
            "data": [file_digest(p) for p in SLIDE_DATA],
        }
    )[:16]


@dataclass(frozen=True)
class SlideJob:
    """One slide (see the module docstring). ``protocol`` is nominal, its rate and window
    set; :meth:`drawn` is the protocol the slide runs."""

    plate: Plate
    sensor: Sensor
    protocol: Protocol
    seed: int
    fidelity: str = "auto"
    ideal: bool = False
    finger: Finger | None = None
    #: the node pitch along the slide [m] when the set fixes it (None: the fidelity's)
    pitch_m: float | None = None
    #: the skin solved at every n-th step of the slide (:class:`~sim_tactile.sim.StepOptions`;
    #: 1: every step)
    solve_every: int = 1
    #: the spectral solve's tolerance (:class:`~sim_tactile.sim.StepOptions`; None: its
    #: reference)
    solve_tol: float | None = None
    #: the probe rig that makes the slide (:mod:`~sim_tactile.sim.plan.rig`), else the finger scene
    rig: ProbeRig | None = None
    #: what the job is called in messages (its plate's name and place in a set)
    label: str = field(default="", compare=False)

    def drawn(self) -> Protocol:
        """The slide's own speed, force and offset, as the simulation draws them."""
        return self.protocol.drawn(self.seed)

    def n_samples(self) -> int:
        """Samples the slide records (its window, :class:`~sim_tactile.sim.plan.protocol.SlideWindow`;
        on the rig, ``duration_s``)."""
        if self.rig is not None:
            proto = self.protocol.at_rate(self.sensor.rate_hz)
            return max(1, round(proto.duration_s * proto.rate_hz))
        pad = (self.finger or self.sensor.finger).patch_m[0]
        return SlideWindow.of(self.plate, pad, self.protocol.at_rate(self.sensor.rate_hz)).n_samples

    def describe(self) -> dict:
        """Everything that determines the slide, as JSON data (``rig`` and ``pitch_m`` only
        where they are set, so the keys of the other slides are unchanged)."""
        d = {
            "kind": "slide",
            "plate": self.plate.params(),
            "sensor": self.sensor.to_json(),
            "protocol": self.protocol.to_json(),
            "seed": int(self.seed),
            "fidelity": self.fidelity,
            "ideal": bool(self.ideal),
            "finger": None if self.finger is None else self.finger.to_json(),
        }
        if self.rig is not None:
            d["rig"] = self.rig.to_json()
        if self.pitch_m is not None:
            d["pitch_m"] = self.pitch_m
        if self.solve_every != 1:
            d["solve_every"] = int(self.solve_every)
        if self.solve_tol is not None:
            d["solve_tol"] = float(self.solve_tol)
        return d

    def key(self) -> str:
        """The slide's cache key: the content hash of :meth:`describe` and the code version."""
        return content_hash({**self.describe(), "code": slide_code_version()})

    def simulate(self, cache: ArtefactCache | None = None):
        """Simulate the slide; a :class:`~sim_tactile.sim.slide.SimResult`. An error names
        the plate and the seed."""
        from ..sim.slide import simulate
        from ..sim.step.runner import StepOptions

        try:
            if self.rig is not None:
                from ..sim.rig_sim import simulate_rig

                return simulate_rig(
                    self.plate,
                    self.sensor,
                    rig=self.rig,
                    protocol=self.protocol,
                    finger=self.finger,
                    seed=self.seed,
                    ideal=self.ideal,
                )
            return simulate(
                self.plate,
                self.sensor,
                protocol=self.protocol,
                finger=self.finger,
                fidelity=self.fidelity,
                seed=self.seed,
                ideal=self.ideal,
                pitch_m=self.pitch_m,
                options=StepOptions(solve_every=self.solve_every, solve_tol=self.solve_tol),
                cache=cache,
            )
        except SimTactileError as exc:
            what = self.label or self.plate.name or self.plate.hash
            raise type(exc)(f"slide of {what} (seed {self.seed}): {exc}") from exc


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

    def __call__(self, job: SlideJob) -> SlideOutcome:
        t0 = time.perf_counter()
        cache = ArtefactCache(self.cache_root)
        key = job.key()
        rec = cached_slide(cache, job, key)
        if rec is not None:  # with the warnings its simulation gave (kept in its meta)
            warns = tuple(str(w) for w in rec.meta.get("warnings") or ())
            return SlideOutcome(rec, warns, time.perf_counter() - t0, True)
        res = job.simulate(cache)
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


def cached_slide(cache: ArtefactCache, job: SlideJob, key: str | None = None) -> Recording | None:
    """The slide of ``job`` (its key: ``key``, else :meth:`SlideJob.key`) from the cache, or
    None: absent, or damaged and discarded with a warning naming the file (the slide is
    then simulated again). The entry is checked against its key and checksum
    (:meth:`~sim_tactile.cache.ArtefactCache.get`), then what it holds against the job: its
    own key, plate and seed (a checksum file forged for an entry copied under another key
    passes the first check, never this one)."""
    key = key or job.key()
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


def _not_the_jobs(meta: dict, job: SlideJob, key: str) -> str | None:
    """None if a cached slide's meta names ``job``'s key, plate and seed, else how not."""
    if meta.get("slide_key") != key:
        return f"holds the slide of another key ({str(meta.get('slide_key'))[:16]}...)"
    if meta.get("plate_hash") != job.plate.hash:
        return f"holds a slide of another plate ({meta.get('plate')!r})"
    if meta.get("seed") != job.seed:
        return f"holds the slide of seed {meta.get('seed')!r}, not {job.seed}"
    return None
