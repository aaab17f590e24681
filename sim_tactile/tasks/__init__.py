"""Versioned benchmark tasks and their runner.

:func:`get_task` and :func:`task_ids` look tasks up; :func:`run_task` runs one and writes its
report. :func:`load` gives a task's data and protocol (its splits) to a user's own framework;
:func:`evaluate` scores a user's methods under the task's protocol beside its built-in rows.
The tasks are defined in :mod:`.defs`, one module per paper: the simulated tasks
(``finger7-v1``, ``multilayer3-v1``, ..., whose ``get_data`` is a
:class:`~sim_tactile.slides.SlideSet`) and the real-data tasks ``biotac20-real-v1`` and
``icub20-real-v1`` (seed paper 000, Table I; ``biotac20-real`` and ``icub20-real`` stay as
their aliases). ``sim-tactile tasks`` lists them; :func:`suite` names the ids a paper
should report (``core-v1``), and a superseded id warns once (:class:`OutdatedTaskWarning`).

``run_task`` and :func:`evaluate` write one result file per row (:mod:`.result_file`),
which ``sim-tactile check`` validates (:mod:`.check`) and the leaderboard collects
(:mod:`.leaderboard`); a method ``(TASK_ENCODER, estimator)`` reads the task's own encoding
(the closed track).
"""

from __future__ import annotations

from . import defs  # noqa: F401  (register the tasks)
from .api import TaskData, TaskProtocol, evaluate, load
from .methods import TASK_ENCODER
from .registry import (
    DataRequest,
    OutdatedTaskWarning,
    PaperCell,
    Run,
    Settings,
    TaskSpec,
    get_task,
    register,
    suite,
    task_ids,
)
from .runner import run_task

__all__ = [
    "TASK_ENCODER",
    "DataRequest",
    "OutdatedTaskWarning",
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
    "suite",
    "task_ids",
]
