"""A data set to write into a store: its layout and, per slide, the job that makes it.

:func:`slide_plan` turns a :class:`~.slide_set.SlideSet` (a task's, or a configuration
file's) into a :class:`Plan`: the store's layout
(:class:`~sim_tactile.datasets.store.StoreSpec`: labels, seeds, the drawn speed, force and offset of every slide, names, rate,
units, the configuration and its hash, the slide code's version) and the slide jobs. The
drawn values come from the jobs themselves (:meth:`~.jobs.SlideJob.drawn`), the same draw the
simulation makes. :func:`task_slide_config` is what a task reading a store checks it against.
"""

from __future__ import annotations

import numpy as np

from ..datasets.store import PARAM_NAMES, StoreSpec, config_hash
from ..plates.define.surface import surface_of
from ..records import TactileDataset
from .jobs import SlideJob, slide_code_version
from .slide_set import SlideSet, class_name


class Plan:
    """One data set to write: its store layout and, for simulated data, a job per slide
    (``jobs``) or, for recorded data, the recordings (``dataset``). ``group``: the store's
    group it goes to (``""``: the root)."""

    def __init__(
        self,
        group: str,
        spec: StoreSpec,
        jobs: list[SlideJob] | None = None,
        dataset: TactileDataset | None = None,
    ) -> None:
        self.group = group
        self.spec = spec
        self.jobs = jobs
        self.dataset = dataset


def slide_plan(
    slides: SlideSet,
    *,
    quick: bool,
    seed: int,
    task: str | None,
    name: str,
    source: dict | None = None,
) -> Plan:
    """The plan of ``slides`` for ``task`` (None: a configuration file, ``source`` its
    content, kept in the store's metadata)."""
    n = slides.slides_for(quick)
    plates = slides.plates_for(quick)
    jobs = slides.jobs(seed, quick)
    params = np.empty((len(jobs), len(PARAM_NAMES)))
    for r, job in enumerate(jobs):
        p = job.drawn()
        params[r] = (p.speed_m_s, p.force_n, p.offset_y_m)
    sensor = slides.sensor_def()
    proto = slides.window_protocol()
    config = _config(slides, task, quick, seed)
    meta = slides.dataset_meta(quick)
    if source is not None:
        meta["config_file"] = source
    spec = StoreSpec(
        name=name,
        config=config,
        labels=np.repeat(np.arange(len(plates)), n),
        slide=np.tile(np.arange(n), len(plates)),
        seeds=np.array([j.seed for j in jobs], dtype=np.uint64),
        params=params,
        lengths=np.full(len(jobs), slides.n_time(), np.int64),
        channel_names=tuple(sensor.layout.names),
        class_names=tuple(class_name(p) for p in plates),
        rate_hz=proto.rate_hz,
        units="N" if slides.ideal else sensor.units,
        taxel_positions=np.asarray(sensor.layout.positions),
        dataset_meta=meta,
        code_version=slide_code_version(),
        plate_maps={k: z for j in jobs for k, z in surface_of(j.plate).map_samples().items()},
    )
    return Plan("", spec, jobs=jobs)


def _config(slides: SlideSet, task: str | None, quick: bool, seed: int) -> dict:
    """The configuration a store of ``slides`` records (and is found again by, its hash)."""
    return {
        "kind": "simulated",
        "task": task,
        "quick": bool(quick),
        "seed": int(seed),
        "slides_per_plate": int(slides.slides_for(quick)),
        **slides.setup(quick),
    }


def task_slide_config(slides: SlideSet, task: str, quick: bool, seed: int) -> tuple[str, str]:
    """``(configuration hash, slide code version)`` that ``generate`` writes for ``task``'s
    ``slides`` (what ``run --store`` checks a store against)."""
    return config_hash(_config(slides, task, quick, seed)), slide_code_version()
