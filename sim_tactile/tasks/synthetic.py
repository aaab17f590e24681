"""Simulated data of a task: plates x slides -> cached recordings -> one :class:`TactileDataset`.

A :class:`SlideSet` says which plates (the classes), which sensor, the slide protocol (its
nominal speed and force, how much they vary from slide to slide, and the window length) and
how many slides per plate. Slide ``k`` of plate ``i`` is seeded by ``(seed, i, k)``, so the
quick run's slides are the first slides of the full run and a re-run with the same seed gives
the same recordings bit for bit. Every slide is cached as an ``.npz`` recording under a key
made of everything that determines it (plate parameters, sensor, protocol, seed, fidelity and
the source of the simulating modules): a second run, ``ablate`` and a run with other
classifiers read them instead of simulating again.

Slides run in worker processes (``SIM_TACTILE_WORKERS``, default: up to 2 or the number of
cores); a slide that fails stops the run with the plate and the slide named.
"""

from __future__ import annotations

import math
import os
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, replace
from multiprocessing import get_all_start_methods, get_context

import numpy as np

from .. import _validate as v
from ..cache import ArtefactCache
from ..errors import ConfigError, SimTactileError
from ..hashing import code_version, derive_seed
from ..records import Recording, TactileDataset
from .registry import DataRequest

#: margin [m] between the pad and the textured area at the start and end of a crossing
_MARGIN_M = 2e-3


def _code_version() -> str:
    return code_version("sim_tactile.sim.simulate", libraries=("mujoco", "numba", "numpy"))


def crossing_s(plate_name: str, sensor: str, speed_m_s: float) -> float:
    """Time [s] for the sensor's pad to cross the plate's textured area at ``speed_m_s``,
    starting and ending on flat ground (the window of one slide)."""
    from ..plates import get_plate
    from ..sensors import get_sensor

    plate = get_plate(plate_name)
    pad_x = get_sensor(sensor).finger.patch_m[0]
    return (plate.area_length_m + pad_x + 2 * _MARGIN_M) / speed_m_s


@dataclass(frozen=True)
class SlideSet:
    """The simulated data of a task (see the module docstring).

    plates: preset plate names, one class each (class names: the part after ``/``).
    sensor: a sensor name of :mod:`sim_tactile.sensors` (its layout, pad and transducer).
    protocol: nominal protocol with its per-slide jitters; ``duration_s`` None = the time to
        cross the largest textured area at the nominal speed (every slide gets that window).
    slides / quick_slides: slides per plate in the full and the quick run.
    quick_plates: the plates of the quick run (a subset of ``plates``; None: all).
    ideal: record the noise-free normal loads [N] instead of the sensor's output.
    """

    plates: tuple[str, ...]
    sensor: str
    protocol: object  # sim.simulate.Protocol (imported lazily: mujoco is heavy)
    slides: int
    quick_slides: int
    fidelity: str = "auto"
    ideal: bool = False
    quick_plates: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        from ..plates import preset_names
        from ..sensors import sensor_names

        if len(self.plates) < 2:
            raise ConfigError(f"a task needs at least 2 plates, got {len(self.plates)}")
        for p in self.plates:
            if p not in preset_names():
                raise ConfigError(f"plate {p!r} is not a preset; valid: {preset_names()}")
        if self.sensor not in sensor_names():
            raise ConfigError(f"sensor {self.sensor!r} is not known; valid: {sensor_names()}")
        v.integer("slides", self.slides, 2, 100_000)
        v.integer("quick_slides", self.quick_slides, 2, self.slides)
        if self.quick_plates is not None:
            extra = [p for p in self.quick_plates if p not in self.plates]
            if extra or len(self.quick_plates) < 2:
                raise ConfigError(
                    f"quick_plates must be at least 2 of the task's plates; not among them: {extra}"
                )

    @property
    def class_names(self) -> tuple[str, ...]:
        return tuple(_class_name(p) for p in self.plates)

    def window_protocol(self):
        """The protocol with its rate (the sensor's unless it has its own) and window fixed."""
        from ..sensors import get_sensor

        proto = self.protocol.at_rate(get_sensor(self.sensor).rate_hz)
        if proto.duration_s is None:
            t = max(crossing_s(p, self.sensor, proto.speed_m_s) for p in self.plates)
            proto = replace(proto, duration_s=math.ceil(t * proto.rate_hz) / proto.rate_hz)
        return proto

    def describe(self) -> dict:
        return {
            "plates": list(self.plates),
            "sensor": self.sensor,
            "protocol": asdict(self.window_protocol()),
            "slides": self.slides,
            "quick_slides": self.quick_slides,
            "fidelity": self.fidelity,
            "ideal": self.ideal,
        }

    def plates_for(self, quick: bool) -> tuple[str, ...]:
        if quick and self.quick_plates is not None:
            return tuple(self.quick_plates)
        return self.plates

    def jobs(self, n_slides: int, seed: int, quick: bool = False) -> list[dict]:
        proto = asdict(self.window_protocol())
        code = _code_version()
        out = []
        for plate in self.plates_for(quick):
            i = self.plates.index(plate)  # a plate's slides keep their seeds in quick runs
            for k in range(n_slides):
                s = derive_seed(seed, i, k, bits=63)
                out.append(
                    {
                        "kind": "slide",
                        "plate": plate,
                        "sensor": self.sensor,
                        "protocol": proto,
                        "seed": s,
                        "fidelity": self.fidelity,
                        "ideal": self.ideal,
                        "code": code,
                    }
                )
        return out

    def __call__(self, req: DataRequest) -> TactileDataset:
        n = self.quick_slides if req.quick else self.slides
        plates = self.plates_for(req.quick)
        jobs = self.jobs(n, req.seed, req.quick)
        recs, stats = simulate_slides(jobs, log=req.log)
        labels = np.repeat(np.arange(len(plates)), n)
        first = recs[0]
        meta = {
            "source": f"simulated: {len(plates)} plates x {n} slides, {self.sensor}",
            "sensor": self.sensor,
            "slides_per_class": n,
            "window_s": float(first.data.shape[0] / first.rate_hz),
            "setup": {**self.describe(), "plates": list(plates)},
            **stats,
        }
        from ..sensors import get_sensor

        layout = get_sensor(self.sensor).layout
        if layout.grid_shape is not None:
            meta["grid_shape"] = list(layout.grid_shape)
        return TactileDataset(
            np.stack([r.data for r in recs]),
            labels,
            first.rate_hz,
            tuple(layout.names),
            tuple(_class_name(p) for p in plates),
            first.taxels,
            first.units,
            meta,
        )


def _class_name(plate: str) -> str:
    return plate.split("/", 1)[-1]


def simulate_job(job: dict, cache: ArtefactCache):
    """Simulate the slide of one job (:meth:`SlideSet.jobs`; a ``finger`` key, the fields of
    a :class:`~sim_tactile.sensors.pad.Finger`, replaces the sensor's pad); a
    :class:`~sim_tactile.sim.simulate.SimResult`. An error names the plate and the seed."""
    from ..plates import get_plate
    from ..sensors import Finger
    from ..sim.protocol import Protocol
    from ..sim.simulate import simulate

    finger = job.get("finger")
    if finger is not None:
        finger = Finger(**{k: tuple(x) if isinstance(x, list) else x for k, x in finger.items()})
    try:
        return simulate(
            get_plate(job["plate"]),
            job["sensor"],
            protocol=Protocol(**job["protocol"]),
            finger=finger,
            fidelity=job["fidelity"],
            seed=job["seed"],
            ideal=job["ideal"],
            cache=cache,
        )
    except SimTactileError as exc:
        raise type(exc)(f"slide of {job['plate']} (seed {job['seed']}): {exc}") from exc


def _run_job(job: dict, cache_root: str) -> list[str]:
    """Simulate one slide into the cache; returns its warnings."""
    cache = ArtefactCache(cache_root)
    res = simulate_job(job, cache)
    res.recording.save(cache.path(ArtefactCache.key(job), "slide.npz"))
    return list(res.warnings)


def default_workers() -> int:
    env = os.environ.get("SIM_TACTILE_WORKERS")
    if env:
        return v.integer("SIM_TACTILE_WORKERS", int(env) if env.isdigit() else env, 1, 256)
    return max(1, min(2, os.cpu_count() or 1))


def simulate_slides(
    jobs: list[dict],
    *,
    cache: ArtefactCache | None = None,
    workers: int | None = None,
    log=None,
) -> tuple[list[Recording], dict]:
    """The recordings of ``jobs`` (from :meth:`SlideSet.jobs`), simulating the ones not cached.

    Returns the recordings in job order and statistics: ``simulate_s`` (wall time of the
    simulation, 0 when everything was cached), ``slides_simulated``, ``slides_cached``,
    ``sim_warnings`` (each distinct warning with its count)."""
    cache = cache or ArtefactCache.default()
    workers = default_workers() if workers is None else v.integer("workers", workers, 1, 256)
    keys = [ArtefactCache.key(j) for j in jobs]
    todo = [i for i, k in enumerate(keys) if cache.get(k, "slide.npz") is None]
    warns: Counter[str] = Counter()
    t0 = time.perf_counter()
    if todo:
        if log:
            log(
                f"simulating {len(todo)} slides ({len(jobs) - len(todo)} cached), {workers} worker(s)"
            )
        step = max(1, len(todo) // 10)
        if workers == 1 or len(todo) == 1:
            for n, i in enumerate(todo):
                w = _run_job(jobs[i], str(cache.root))
                warns.update(w)
                if log and (n + 1) % step == 0:
                    log(f"  {n + 1}/{len(todo)} slides ({time.perf_counter() - t0:.0f} s)")
        else:
            # fork where there is one: spawn would re-import the caller's __main__, which
            # breaks scripts without a main guard; the parent runs no threads of its own here
            ctx = get_context("fork" if "fork" in get_all_start_methods() else "spawn")
            with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
                futs = [pool.submit(_run_job, jobs[i], str(cache.root)) for i in todo]
                for n, f in enumerate(futs):
                    w = f.result()
                    warns.update(w)
                    if log and (n + 1) % step == 0:
                        log(f"  {n + 1}/{len(todo)} slides ({time.perf_counter() - t0:.0f} s)")
    sim_s = time.perf_counter() - t0 if todo else 0.0
    recs = [Recording.load(cache.get(k, "slide.npz")) for k in keys]
    shapes = Counter(r.data.shape for r in recs)
    if len(shapes) > 1:
        raise ConfigError(f"simulated slides differ in shape: {dict(shapes)}")
    return recs, {
        "simulate_s": sim_s,
        "slides_simulated": len(todo),
        "slides_cached": len(jobs) - len(todo),
        "sim_warnings": [f"{w} (x{c})" for w, c in warns.most_common()],
    }
