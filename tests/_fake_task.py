"""A registered task whose slides are made without physics: each plate a tone of its own
frequency on every taxel, with a per-slide phase, gain and noise drawn from the slide's seed.
For the format bridges' tests, which need a task's splits and a learnable signal, not the
simulation (quick: 3 plates x 8 slides of 0.5 s on grid3x3 at 100 Hz)."""

from __future__ import annotations

import contextlib

import numpy as np

from sim_tactile.records import Recording
from sim_tactile.slides import SlideOutcome

TASK = "formats-tones-v1"
PLATES = ("finger7/flat", "finger7/ridges-2", "finger7/ridges-4")


def tone_slide(job):
    """The slide of ``job`` as a tone: ``(T, 9)`` float32, frequency by plate."""
    taxels = job.sensor.layout.positions
    n = job.n_samples()
    rng = np.random.default_rng(int(job.seed) % (2**32))
    k = PLATES.index(job.plate.name)
    t = np.arange(n) / job.protocol.rate_hz
    f = 4.0 * (1 + k) ** 1.3 + rng.normal(0, 0.2)
    gain = 1.0 + 0.3 * np.arange(len(taxels)) / len(taxels)
    x = gain[None] * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))[:, None]
    x = (x + rng.normal(0, 0.15, x.shape) + 2.0).astype(np.float32)
    return SlideOutcome(Recording(x, t + 0.5 / job.protocol.rate_hz, taxels), (), 0.0, False)


@contextlib.contextmanager
def tones_task(classifiers=("svm-raw",), snn=None):
    """Register the task (removed again afterwards); ``snn``: the snn row's parameters."""
    from sim_tactile.encoders.encodings import threshold_encoding
    from sim_tactile.sim.protocol import Protocol
    from sim_tactile.slides import SlideSet
    from sim_tactile.tasks import Settings, TaskSpec, register
    from sim_tactile.tasks.registry import unregister

    params = {"snn": snn} if snn else {}
    spec = TaskSpec(
        id=TASK,
        title="three tones on grid3x3 (no physics)",
        get_data=SlideSet(
            plates=PLATES,
            sensor="grid3x3",
            protocol=Protocol(duration_s=0.5),
            slides=8,
            quick_slides=8,
        ),
        classifiers=tuple(classifiers),
        split="6/2",
        quick=Settings(repeats=1, split="6/2", params=params),
        encoder=threshold_encoding,
    )
    register(spec)
    try:
        yield spec
    finally:
        unregister(spec.id)


def tones_store(path, seed: int = 0):
    """Generate the task's quick store at ``path`` with :func:`tone_slide` (no physics)."""
    from sim_tactile.generate import generate

    return generate(
        TASK,
        path,
        quick=True,
        workers=1,
        seed=seed,
        progress=False,
        log=lambda m: None,
        _worker=tone_slide,
    )
