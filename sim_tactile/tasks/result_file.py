"""Result files: one JSON document per method and task version, for others to check.

``run`` and :func:`~sim_tactile.tasks.evaluate` write one per row of a report into
``OUT/results/<task>--<method>.json``; ``sim-tactile check`` validates one against the
registered task (:mod:`.check`); the leaderboard is a folder of them (:mod:`.leaderboard`).
The shape is the one Hugging Face's leaderboards read, a ``config`` block (who and how) and a
``results`` block (task -> metric -> number), with each metric's SD, 95% interval and
repeats beside it as lm-evaluation-harness puts ``acc_stderr`` beside ``acc``::

    {"schema": {"name": "sim-tactile-result", "version": 1},
     "config": {"model_name", "model_sha", "method": {...}, "task", "family", "version",
                "task_sha256", "track", "reported", "protocol": {...}, "interval": {...},
                "environment": {...}, "date"},
     "results": {"<task>": {"accuracy": 0.99, "accuracy_sd": ..., "accuracy_ci95": [lo, hi],
                            "accuracy_repeats": [...], "fit_s": ..., ..., "neurobench": {...}}}}

The schema is documented in the manual's file-format reference (``docs/reference``); a
change of meaning is a new ``version``.
"""

from __future__ import annotations

import datetime
import hashlib
import json
import os
import platform
import re
import subprocess
from importlib import metadata
from pathlib import Path

import numpy as np

from .. import __version__
from ..learn.classifiers import get_classifier
from . import intervals
from .methods import TASK_ENCODER
from .registry import Run, TaskSpec, get_task
from .report import Report, ResultRow
from .splits import splits_digest, task_splits
from .versions import split_task_id

SCHEMA = {"name": "sim-tactile-result", "version": 1}
#: The metrics of a row, each with its repeats: the accuracy on each split, and the time to
#: fit and to predict on each [s] (wall-clock, on the machine in ``config.environment``).
METRICS = ("accuracy", "fit_s", "predict_s")
#: How a file's intervals are made (:mod:`.intervals`); ``check`` refuses another.
INTERVAL = {
    "kind": "percentile bootstrap of the mean over the repeats",
    "level": intervals.LEVEL,
    "resamples": intervals.RESAMPLES,
    "seed": intervals.SEED,
    "min_repeats": intervals.MIN_REPEATS,
}
#: ``config.method.encoder`` of a method that reads the recordings as they are (one that
#: reads the task's own encoding has :data:`~.methods.TASK_ENCODER`, ``"task"``)
NO_ENCODER = "none"


def task_sha256(spec: TaskSpec, quick: bool = False) -> str:
    """SHA-256 of a task's definition for a full run, or a quick one (``quick``)
    (:meth:`TaskSpec.describe`, without the settings of the other form: the quick form's
    settings change nothing of a full run): a file made with another definition (a
    calibrated sensor, a development version) does not match."""
    d = dict(spec.describe())
    d.pop("full" if quick else "quick", None)
    text = json.dumps(d, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def labels_sha256(labels) -> str:
    return hashlib.sha256(np.asarray(labels, dtype=np.int64).tobytes()).hexdigest()


def slug(text: str) -> str:
    """A file-name part: lower case, runs of other characters as one ``-``."""
    return re.sub(r"[^a-z0-9.+]+", "-", text.lower()).strip("-") or "method"


def _git(*args: str) -> str | None:
    here = Path(__file__).resolve().parent
    try:
        out = subprocess.run(
            ["git", "-C", str(here), *args], capture_output=True, text=True, timeout=10, check=True
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def _commit() -> str | None:
    """The package's commit (``git describe --always --dirty``) when it runs from a clone of
    its own repository (not an installed copy inside some other repository)."""
    top = _git("rev-parse", "--show-toplevel")
    if top is None or Path(top).resolve() != Path(__file__).resolve().parents[2]:
        return None
    return _git("describe", "--always", "--dirty", "--abbrev=10")


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _versions(*names: str) -> dict:
    out = {}
    for n in names:
        try:
            out[n] = metadata.version(n)
        except metadata.PackageNotFoundError:
            out[n] = None
    return out


def environment() -> dict:
    """The package version that made a file, and the machine it ran on."""
    return {
        "sim_tactile": __version__,
        "commit": _commit(),
        "python": platform.python_version(),
        **_versions("numpy", "scikit-learn", "torch"),
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cpu": _cpu(),
        "cores": os.cpu_count(),
    }


def reads_recordings(classifier: str) -> bool:
    """A built-in classifier that reads the recordings, not the task's encoding (``svm-raw``,
    ``lstm``)."""
    return get_classifier(classifier).features.startswith("raw")


def _builtin_method(row: ResultRow) -> dict:
    raw = reads_recordings(row.classifier)
    return {
        "name": row.label,
        "version": __version__,
        "link": None,
        "builtin": True,
        "classifier": row.classifier,
        "features": row.features,
        "channels": row.channels,
        "encoder": NO_ENCODER if raw else TASK_ENCODER,
        "description": f"the task's row {row.label!r}: {row.classifier} on {row.features}",
    }


def _user_method(row: ResultRow, about: dict) -> dict:
    return {
        "name": row.label,
        "version": about.get("version") or "unversioned",
        "link": about.get("link"),
        "builtin": False,
        "classifier": row.classifier,
        "features": row.features,
        "channels": row.channels,
        "encoder": row.extra.get("encoder", NO_ENCODER),
        "description": row.extra.get("method", ""),
    }


def track_of(method: dict, own_definition: bool) -> str:
    """``closed`` for the task's own data, encoder and protocol with only the classifier the
    method's (its built-in rows, or a user's estimator after the task's encoder); else
    ``open``."""
    if not own_definition:
        return "open"
    if method["builtin"] or method["encoder"] == TASK_ENCODER:
        return "closed"
    return "open"


def result_document(
    spec: TaskSpec,
    row: ResultRow,
    *,
    quick: bool,
    seed: int,
    labels,
    about: dict | None = None,
    env: dict | None = None,
) -> dict:
    """The result file of one report row (``labels``: the data set's, whose splits the row
    was scored on)."""
    method = (
        _user_method(row, about or {}) if row.extra.get("user_method") else _builtin_method(row)
    )
    registered = get_task(spec.id)
    family, version = split_task_id(spec.id)
    n = row.repeats
    labels = np.asarray(labels, dtype=np.int64)
    protocol = {
        "mode": "quick" if quick else "full",
        "split": row.split,
        "repeats": n,
        "seed": seed,
        "splits_sha256": splits_digest(task_splits(labels, row.split, n, seed)),
        "labels_sha256": labels_sha256(labels),
        "labels": labels.tolist(),
        "encoding": spec.encoding,
        "encode_once": spec.encode_once,
    }
    metrics: dict = {}
    for name, key in zip(METRICS, ("accuracies", "fit_s", "predict_s"), strict=True):
        if row.extra.get(key) is None:
            continue
        s = intervals.summary(row.extra[key])
        metrics[name] = s["mean"]
        metrics[f"{name}_sd"] = s["sd"]
        metrics[f"{name}_ci95"] = s["ci95"]
        metrics[f"{name}_repeats"] = s["repeats"]
    if row.extra.get("neuromorphic"):
        metrics["neurobench"] = row.extra["neuromorphic"]
    own = task_sha256(spec, quick) == task_sha256(registered, quick)
    return {
        "schema": dict(SCHEMA),
        "config": {
            "model_name": method["name"],
            "model_sha": method["version"],
            "method": method,
            "task": spec.id,
            "family": family,
            "version": version,
            "task_sha256": task_sha256(spec, quick),
            "track": track_of(method, own),
            "variant": None if own else variant_of(spec, registered),
            "reported": False,
            "protocol": protocol,
            "interval": dict(INTERVAL),
            "environment": env or environment(),
            "date": datetime.date.today().isoformat(),
        },
        "results": {spec.id: metrics},
    }


def variant_of(spec: TaskSpec, registered: TaskSpec) -> str:
    """How a run's definition differs from its registered task's: the remarks it adds (a
    calibrated sensor says so in one), else that the definition differs."""
    added = [r for r in spec.remarks if r not in registered.remarks]
    return " ".join(added) or f"another definition of {spec.id} than the registered one"


def write_result_files(
    spec: TaskSpec,
    report: Report,
    labels,
    out: Path,
    about: dict | None = None,
    env: dict | None = None,
) -> list[str]:
    """One result file per row of ``report`` into ``out/results``; returns their paths.
    ``about``: method name -> ``{version, link}`` of the user's methods; ``env``: the
    :func:`environment` taken when the run started (its commit is the code that ran)."""
    folder = out / "results"
    folder.mkdir(parents=True, exist_ok=True)
    env = env or environment()
    paths = []
    for row in report.results:
        doc = result_document(
            spec,
            row,
            quick=report.quick,
            seed=int(report.protocol["seed"]),
            labels=labels,
            about=(about or {}).get(row.label),
            env=env,
        )
        path = folder / f"{spec.id}--{slug(row.label)}.json"
        k = 1
        while str(path) in paths:  # two labels of one slug ("a b", "a-b"): both are kept
            k += 1
            path = folder / f"{spec.id}--{slug(row.label)}-{k}.json"
        path.write_text(dumps(doc))
        paths.append(str(path))
    return paths


#: a list of numbers as ``json.dumps(indent=1)`` writes it: a line break after its bracket
#: (never inside a JSON string, where a line break is escaped)
_NUMBERS = re.compile(r"\[\n\s*(-?[0-9][-+0-9.eE,\s]*?)\n\s*\]")


def dumps(doc: dict) -> str:
    """A result file's text: indented, each list of numbers on one line."""
    text = json.dumps(doc, indent=1)
    return _NUMBERS.sub(lambda m: "[" + " ".join(m[1].split()) + "]", text) + "\n"


def run_of(spec: TaskSpec, label: str) -> Run | None:
    """The task's row named ``label`` (a classifier's name stands for its own row)."""
    for r in spec.all_runs():
        if r.name == label:
            return r
    try:
        get_classifier(label)
    except Exception:  # noqa: BLE001 (not a classifier's name: no row)
        return None
    return Run(label, paper=spec.paper.get(label))


def reported_documents(task_id: str) -> list[dict]:
    """The paper's numbers of ``task_id`` as result files marked ``reported``: the cells of
    its rows (not re-run here; no repeats, so no interval)."""
    spec = get_task(task_id)
    family, version = split_task_id(spec.id)
    out = []
    for run in spec.all_runs():
        cell = run.paper
        if cell is None:
            continue
        method = {
            "name": f"paper: {run.name}",
            "version": cell.source,
            "link": None,
            "builtin": False,
            "row": run.name,
            "classifier": run.classifier,
            "features": get_classifier(run.classifier).features,
            "channels": run.channels,
            "encoder": "the paper's",
            "description": spec.reference,
        }
        out.append(
            {
                "schema": dict(SCHEMA),
                "config": {
                    "model_name": method["name"],
                    "model_sha": cell.source,
                    "method": method,
                    "task": spec.id,
                    "family": family,
                    "version": version,
                    "task_sha256": task_sha256(spec),
                    "track": "closed",
                    "variant": None,
                    "reported": True,
                    "protocol": {
                        "mode": "full",
                        "split": spec.split_for(run, False),
                        "repeats": spec.full.repeats_for(run.classifier),
                    },
                    "interval": dict(INTERVAL),
                    "environment": None,
                    "date": None,
                },
                "results": {
                    spec.id: {
                        "accuracy": cell.mean,
                        "accuracy_sd": cell.std,
                        "accuracy_ci95": None,
                        "accuracy_repeats": None,
                    }
                },
            }
        )
    return out
