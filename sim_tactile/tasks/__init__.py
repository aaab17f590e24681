"""Versioned benchmark tasks and their runner.

``get_task(id)`` / ``task_ids()`` look tasks up; :func:`run_task` runs one and writes its
report. Real-data tasks: ``biotac20-real``, ``icub20-real`` (seed paper 000, Table I).
Synthetic tasks register in the same way with a ``get_data`` that simulates.
"""

from __future__ import annotations

from . import real  # noqa: F401  (registers the real-data tasks)
from .registry import DataRequest, PaperCell, Settings, TaskSpec, get_task, register, task_ids
from .runner import run_task

__all__ = [
    "DataRequest",
    "PaperCell",
    "Settings",
    "TaskSpec",
    "get_task",
    "register",
    "run_task",
    "task_ids",
]
