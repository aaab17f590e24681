"""The slide engine: slide jobs, sets of them, and running them (serially, on a process pool
or on Ray) through a cache keyed by content.

- :mod:`.jobs`: :class:`SlideJob` (one slide: plate, sensor, protocol, seed, fidelity; its
  content key) and the worker that simulates one through the cache;
- :mod:`.slide_set`: :class:`SlideSet`, the simulated data of a task or a configuration;
- :mod:`.run`: the backends, :func:`default_workers` and :func:`run_slides`;
- :mod:`.plan` and :mod:`.config`: a set as a store's plan, and configuration files
  (imported where they are used: they bring the store's code).

Both ``sim-tactile run`` (a task's ``get_data``) and ``sim-tactile generate`` stand on it.
"""

from __future__ import annotations

from .jobs import SlideJob, SlideOutcome, SlideWorker, slide_code_version
from .run import default_workers, make_backend, run_slides, stream
from .slide_set import SlideSet, class_name

__all__ = [
    "SlideJob",
    "SlideOutcome",
    "SlideSet",
    "SlideWorker",
    "class_name",
    "default_workers",
    "make_backend",
    "run_slides",
    "slide_code_version",
    "stream",
]
