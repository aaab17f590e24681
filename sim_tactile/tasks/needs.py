"""What a task's rows need beyond the core install: torch for the networks (the extra
``[learn]``), the real data set's folder (``--data``) for the real-data tasks. ``run`` checks
it before anything is loaded (:func:`check_torch`); ``sim-tactile tasks`` lists it
(:func:`task_needs`)."""

from __future__ import annotations

from ..errors import MissingDependencyError, require
from ..learn.classifiers import get_classifier
from .registry import Run, TaskSpec


def check_torch(spec: TaskSpec, runs: list[Run]) -> None:
    """torch, where a row needs it; else an error that names those rows, the install
    command and the option that runs the others alone."""
    rows = [r.name for r in runs if get_classifier(r.classifier).needs_torch]
    if not rows:
        return
    try:
        require("torch", "learn")
    except MissingDependencyError as exc:
        rest = [r.classifier for r in runs if not get_classifier(r.classifier).needs_torch]
        others = ",".join(dict.fromkeys(rest)) or "svm-raw,svm-spike"
        raise MissingDependencyError(
            f"task {spec.id}: the row(s) {', '.join(rows)} need torch: pip install "
            f"'sim-tactile[learn]', or run the others alone with --classifiers {others}"
        ) from exc


def task_needs(spec: TaskSpec) -> list[str]:
    """What the task's own rows need: ``"torch"`` (some row is a network), ``"--data"`` (it
    reads real recordings); a suite needs what its parts need."""
    from .registry import get_task

    specs = [get_task(p) for p in spec.parts] if spec.parts else [spec]
    out = []
    if any(get_classifier(r.classifier).needs_torch for s in specs for r in s.all_runs()):
        out.append("torch")
    if any(s.needs_data_path for s in specs):
        out.append("--data")
    return out
