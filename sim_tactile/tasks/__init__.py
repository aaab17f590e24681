"""Versioned benchmark tasks and their runner.

:func:`get_task` and :func:`task_ids` look tasks up; :func:`run_task` runs one and writes its
report. :func:`load` gives a task's data and protocol (its splits) to a user's own framework;
:func:`evaluate` scores a user's methods under the task's protocol beside its built-in rows.
The tasks are defined in :mod:`.defs`, one module per paper: the simulated tasks
(``finger7-v1``, ``multilayer3-v1``, ..., whose ``get_data`` is a
:class:`~sim_tactile.slides.SlideSet`) and the real-data tasks ``biotac20-real-v1`` and
``icub20-real-v1`` (seed paper 000, Table I; ``biotac20-real`` and ``icub20-real`` stay as
their aliases). ``sim-tactile tasks`` lists them.
"""

from __future__ import annotations

from . import defs  # noqa: F401  (register the tasks)
from .api import TaskData, TaskProtocol, evaluate, load
from .registry import (
    DataRequest,
    PaperCell,
    Run,
    Settings,
    TaskSpec,
    get_task,
    register,
    task_ids,
)
from .runner import run_task

__all__ = [
    "DataRequest",
    "PaperCell",
    "Run",
    "Settings",
    "TaskData",
    "TaskProtocol",
    "TaskSpec",
    "evaluate",
    "get_task",
    "load",
    "register",
    "run_task",
    "task_ids",
]
