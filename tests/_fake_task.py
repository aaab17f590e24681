"""A registered task whose slides are made without physics: each plate a tone of its own
frequency on every taxel, with a per-slide phase, gain and noise drawn from the slide's seed.
For the format bridges' tests, which need a task's splits and a learnable signal, not the
simulation (quick: 3 plates x 12 slides of 0.5 s on grid3x3 at 100 Hz, split 8/4 per class).

The fixture body :func:`tones_fixture` registers the task for one test module (never longer: the
registry's own tests list every registered task) and generates its quick store."""

from __future__ import annotations

import contextlib
from types import SimpleNamespace

import numpy as np
import pytest

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
def tones_task(classifiers=("svm-raw",), snn=None, repeats=1):
    """Register the task (removed again afterwards); ``snn``: the snn row's parameters;
    ``repeats``: the quick protocol's."""
    from sim_tactile.encoders.encodings import threshold_encoding
    from sim_tactile.sim.plan.protocol import Protocol
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
            slides=12,
            quick_slides=12,
        ),
        classifiers=tuple(classifiers),
        split="8/4",
        quick=Settings(repeats=repeats, split="8/4", params=params),
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


#: The snn row's parameters in the tests (a small, quickly trained network).
SNN = {"hidden": 16, "epochs": 40, "target_true": 20, "target_false": 3, "lr": 0.03}
SNN.update(batch_size=6, num_threads=1)


def tones_fixture(tmp_path_factory, cache_dir):
    """The task (its snn row small) and its quick store: the body of a test module's
    ``tones`` fixture (module scope)."""
    path = tmp_path_factory.mktemp("tones") / "tones.zarr"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SIM_TACTILE_CACHE", str(cache_dir))
        with tones_task(classifiers=("snn", "svm-spike", "svm-raw"), snn=SNN) as spec:
            tones_store(path)
            yield SimpleNamespace(spec=spec, store=path, task=TASK)
