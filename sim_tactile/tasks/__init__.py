"""Versioned benchmark tasks and their runner.

``get_task(id)`` / ``task_ids()`` look tasks up; :func:`run_task` runs one and writes its
report. :func:`load` gives a task's data and protocol (its splits) to a user's own framework;
:func:`evaluate` scores a user's methods under the task's protocol beside its built-in rows. Real-data tasks: ``biotac20-real``, ``icub20-real`` (seed paper 000, Table I).
Simulated tasks (:mod:`.sim_tasks`): ``finger7-v1``, ... with a ``get_data`` that
simulates (:class:`~sim_tactile.slides.SlideSet`).
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
