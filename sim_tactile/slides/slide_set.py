"""Simulated data of a task or a configuration: plates x slides -> one :class:`TactileDataset`.

A :class:`SlideSet` says which plates (the classes), which sensor (and optionally another pad
for it), the slide protocol (its nominal speed and force, how much they vary from slide to
slide, and the window length) and how many slides per plate. Slide ``k`` of plate ``i`` is
seeded by ``derive_seed(seed, i, k)``, so the quick run's slides are the first slides of the
full run and a re-run with the same seed gives the same recordings bit for bit. Every slide
is cached under its job's content key (:meth:`~.jobs.SlideJob.key`): a second run,
``ablate`` and a run with other classifiers read them instead of simulating again.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .. import _validate as v
from .._names import did_you_mean
from ..errors import ConfigError
from ..hashing import derive_seed
from ..plates import get_plate, is_plate_file, preset_names
from ..plates.parts.user import is_user_plate, parse_ref
from ..records import TactileDataset
from ..sensors import Finger, Sensor, get_sensor, sensor_names
from ..sensors.calibration import Calibration, calibrated
from ..sim.plan.options import StepOptions, check_forced, keyed
from ..sim.plan.protocol import Protocol, SlideWindow
from ..sim.plan.rig import ProbeRig
from .jobs import SlideJob
from .run import run_slides

#: Slides per plate a set may ask for (per plate and class).
SLIDES_RANGE = (2, 100_000)


def plate_label(plate: str) -> str:
    """How a set's configuration records a plate: a preset by its name, a file by its name
    without its folder (a part's or height map's with its options). A data set's identity is
    its content (each plate's parameters, a height map's samples by their SHA-256, are in the
    configuration beside it), so a folder of configuration, files and store runs and resumes
    wherever it is copied."""
    if not is_plate_file(plate):
        return plate
    if is_user_plate(plate):
        src = parse_ref(plate)
        return replace(src, path=Path(src.path).name).ref()
    return Path(plate).name


def class_name(plate: str) -> str:
    """A plate's class name: the part of its name after the family (a plate file's name is
    its ``name`` key, else the file's name; a part's or height map's, its file's name or its
    ``name`` option)."""
    if is_plate_file(plate):
        plate = get_plate(plate).name
    return plate.split("/", 1)[-1]


@dataclass(frozen=True)
class SlideSet:
    """The simulated data of a task (see the module docstring).

    plates: preset plate names, one class each (class names: the part after ``/``).
    sensor: a sensor name of :mod:`sim_tactile.sensors` (its layout, pad, transducer, rate),
        or the name of ``sensor_spec``.
    protocol: nominal protocol with its per-slide jitters; ``duration_s`` None = the time to
        cross the largest textured area at the nominal speed (every slide gets that window);
        ``rate_hz`` None = the sensor's.
    slides / quick_slides: slides per plate in the full and the quick run.
    quick_plates: the plates of the quick run (a subset of ``plates``; None: all).
    ideal: record the noise-free normal loads [N] instead of the sensor's output.
    finger: a pad that replaces the sensor's (None: the sensor's own).
    calibration: a sensor calibration (``sim-tactile calibrate``) applied to the sensor.
    pitch_m: the skin's node pitch [m] along the slide, fixed for every slide (None: the
        fidelity's choice; the level's pitch across the slide follows it as in ``simulate``).
    dt_s: the time step [s] of every slide, at most this (None: the fidelity's choice; a
        piezoelectric sensor on a rough plate resolves its vibration at about 8 steps a
        sample: :mod:`~sim_tactile.sim.plan.vibration`).
    options: how every slide is computed (:class:`~sim_tactile.sim.plan.options.StepOptions`:
        ``solve_every``, ``solve_tol``, ``path``, ...; the defaults: the fast paths whose
        measured error is within target).
    rig: the slides are made on this probe rig (:mod:`~sim_tactile.sim.plan.rig`: the plate's
        texture on a probe sliding over the sensor, which lies on a bed; ``finger`` is then the
        sensor's skin and ``protocol.duration_s`` the window), not by the finger scene.
    sensor_spec: the sensor's whole definition where it is not a preset (a sensor file's,
        :mod:`~sim_tactile.sensors.files`); :meth:`describe` records it whole either way.
    """

    plates: tuple[str, ...]
    sensor: str
    protocol: Protocol
    slides: int
    quick_slides: int
    fidelity: str = "auto"
    ideal: bool = False
    quick_plates: tuple[str, ...] | None = None
    finger: Finger | None = None
    calibration: Calibration | None = None
    rig: ProbeRig | None = None
    pitch_m: float | None = None
    dt_s: float | None = None
    options: StepOptions = field(default_factory=StepOptions)
    sensor_spec: Sensor | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        check_forced(self.pitch_m, self.dt_s)
        if self.rig is not None and self.protocol.duration_s is None:
            raise ConfigError("a slide set on the probe rig needs protocol.duration_s (its window)")
        if len(self.plates) < 2:
            raise ConfigError(f"a task needs at least 2 plates, got {len(self.plates)}")
        for p in self.plates:
            if is_plate_file(p):
                get_plate(p)  # a plate file, a part or a height map: it must read
            elif p not in preset_names():
                raise ConfigError(
                    f"plate {p!r} is not a preset{did_you_mean(p, preset_names())}; valid: "
                    f"{preset_names()}"
                )
        names = [class_name(p) for p in self.plates]
        if len(set(names)) != len(names):
            raise ConfigError(f"two plates share a class name: {names}; valid: distinct names")
        if self.sensor_spec is not None:
            if self.sensor_spec.name != self.sensor:
                raise ConfigError(
                    f"sensor {self.sensor!r} names another sensor than its definition's "
                    f"({self.sensor_spec.name!r})"
                )
        elif self.sensor not in sensor_names():
            raise ConfigError(
                f"sensor {self.sensor!r} is not known{did_you_mean(self.sensor, sensor_names())}; "
                f"valid: {sensor_names()}"
            )
        if self.calibration is not None:
            calibrated(self.base_sensor(), self.calibration)  # fits this sensor
        v.integer("slides", self.slides, *SLIDES_RANGE)
        v.integer("quick_slides", self.quick_slides, SLIDES_RANGE[0], self.slides)
        if self.quick_plates is not None:
            extra = [p for p in self.quick_plates if p not in self.plates]
            if extra or len(self.quick_plates) < 2:
                raise ConfigError(
                    f"quick_plates must be at least 2 of the task's plates; not among them: {extra}"
                )

    @property
    def class_names(self) -> tuple[str, ...]:
        return tuple(class_name(p) for p in self.plates)

    def base_sensor(self) -> Sensor:
        """The sensor before a calibration: ``sensor_spec`` (a sensor file's), else the
        preset named ``sensor``."""
        return self.sensor_spec if self.sensor_spec is not None else get_sensor(self.sensor)

    def sensor_def(self) -> Sensor:
        sensor = self.base_sensor()
        return sensor if self.calibration is None else calibrated(sensor, self.calibration)

    def pad(self) -> Finger:
        """The pad the slides are made with: ``finger``, else the sensor's."""
        return self.finger or self.sensor_def().finger

    def window_protocol(self) -> Protocol:
        """The protocol with its rate (the sensor's unless it has its own) and its window
        (crossing the longest textured area with this set's pad, in whole samples) fixed."""
        proto = self.protocol.at_rate(self.sensor_def().rate_hz)
        if proto.duration_s is None:
            areas = [get_plate(p).area_length_m for p in self.plates]
            t = SlideWindow.window_s(areas, self.pad().patch_m[0], proto.speed_m_s, proto.rate_hz)
            proto = replace(proto, duration_s=t)
        return proto

    def n_time(self) -> int:
        """Samples in every slide's window."""
        if self.rig is not None:
            proto = self.window_protocol()
            return max(1, round(proto.duration_s * proto.rate_hz))
        plate = get_plate(self.plates[0])
        return SlideWindow.of(plate, self.pad().patch_m[0], self.window_protocol()).n_samples

    def describe(self) -> dict:
        """The set's configuration as JSON data, each plate with its parameters (so a data
        set records its plates whole, and a changed preset is another configuration)."""
        d = {
            "plates": [plate_label(p) for p in self.plates],
            "plate_params": [get_plate(p).params() for p in self.plates],
            "sensor": self.sensor,
            "sensor_definition": self.sensor_def().to_json(),
            "protocol": self.window_protocol().to_json(),
            "slides": self.slides,
            "quick_slides": self.quick_slides,
            "quick_plates": None if self.quick_plates is None else list(self.quick_plates),
            "fidelity": self.fidelity,
            "ideal": self.ideal,
            "finger": None if self.finger is None else self.finger.to_json(),
        }
        if self.rig is not None:
            d["rig"] = self.rig.to_json()
        if self.pitch_m is not None:
            d["pitch_m"] = self.pitch_m
        if self.dt_s is not None:
            d["dt_s"] = self.dt_s
        return {**d, **keyed(self.options)}

    def setup(self, quick: bool) -> dict:
        """:meth:`describe` with the plates of the quick or the full run."""
        d = self.describe()
        keep = [self.plates.index(p) for p in self.plates_for(quick)]
        d["plates"] = [d["plates"][i] for i in keep]
        d["plate_params"] = [d["plate_params"][i] for i in keep]
        return d

    def plates_for(self, quick: bool) -> tuple[str, ...]:
        if quick and self.quick_plates is not None:
            return tuple(self.quick_plates)
        return self.plates

    def slides_for(self, quick: bool) -> int:
        return self.quick_slides if quick else self.slides

    def jobs(self, seed: int, quick: bool = False) -> list[SlideJob]:
        """The set's slides, plate after plate; slide ``k`` of plate ``i`` has the seed
        ``derive_seed(seed, i, k)`` (``i`` its index among all the plates, so a quick run's
        slides are the full run's first ones: each knows the full run's slides a plate, on
        which ``path = auto`` takes a table that pays over many:
        ``plate_slides`` of :class:`~sim_tactile.sim.plan.slide.Slide`)."""
        proto = self.window_protocol()
        sensor = self.sensor_def()
        n = self.slides_for(quick)
        out = []
        for name in self.plates_for(quick):
            i = self.plates.index(name)
            plate = get_plate(name)
            for k in range(n):
                out.append(
                    SlideJob(
                        plate,
                        sensor,
                        proto,
                        derive_seed(seed, i, k, bits=63),
                        self.fidelity,
                        self.ideal,
                        self.finger,
                        pitch_m=self.pitch_m,
                        dt_s=self.dt_s,
                        rig=self.rig,
                        options=self.options,
                        label=f"{name} slide {k}",
                        plate_slides=self.slides,
                    )
                )
        return out

    def dataset_meta(self, quick: bool) -> dict:
        """The metadata of the set's data set (what a run or a store records of it)."""
        plates = self.plates_for(quick)
        n = self.slides_for(quick)
        proto = self.window_protocol()
        sensor = self.sensor_def()
        meta = {
            "source": f"simulated: {len(plates)} plates x {n} slides, {self.sensor}",
            "sensor": self.sensor,
            "slides_per_class": n,
            "window_s": self.n_time() / proto.rate_hz,
            "setup": self.setup(quick),
        }
        if sensor.grid_shape is not None:
            meta["grid_shape"] = list(sensor.grid_shape)
        return meta

    def __call__(self, req) -> TactileDataset:
        """The set's data set (a task's ``get_data``), simulating what is not cached."""
        jobs = self.jobs(req.seed, req.quick)
        recs, stats = run_slides(jobs, log=req.log)
        plates = self.plates_for(req.quick)
        return TactileDataset.from_recordings(
            recs,
            np.repeat(np.arange(len(plates)), self.slides_for(req.quick)),
            tuple(class_name(p) for p in plates),
            meta={**self.dataset_meta(req.quick), **stats},
        )
