"""The CI mode of ``sim-tactile run``: a run's rows against a saved report, row by row.

``--save-baseline PATH`` writes the run's rows, protocol and environment (a ``report.json``
serves as well);
``--baseline PATH [--tolerance 0.02]`` compares this run's rows with it. A row is the same
row when its task, label, classifier and features agree (a user's method: its name). The run
fails (exit 1) when a row's mean accuracy falls below the lower end of its baseline's 95%
interval (:mod:`.intervals`, from the baseline's repeats) by more than the tolerance, or when
a baseline row is missing from the run; a baseline row without an interval (fewer than
:data:`~.intervals.MIN_REPEATS` repeats) is compared by its mean. Rows the baseline does not
have are listed as new and do not fail it. A baseline of another task or of the other mode (quick
or full) is refused before anything runs.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from ..errors import ConfigError
from ..tables import text_table
from .intervals import interval_list, interval_text

#: The default tolerance [accuracy] of ``--tolerance``.
TOLERANCE = 0.02


def _rows(report: dict) -> dict[tuple, dict]:
    """A report's rows by key (a suite's rows carry their part in the label)."""
    out = {}
    for r in report["results"]:
        out[(report["task"], r["label"], r["classifier"], r["features"])] = r
    return out


def load_baseline(path: str | Path, task: str, quick: bool) -> dict:
    """Read a baseline (a report's JSON) and check that it is one of ``task`` in this mode;
    the errors name the file and what does not match."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError as exc:
        raise ConfigError(f"--baseline {path}: no such file") from exc
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ConfigError(f"--baseline {path}: not a JSON report ({exc})") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("results"), list) or "task" not in doc:
        raise ConfigError(
            f"--baseline {path}: not a report (no task and results); valid: a report.json or "
            "a file written by --save-baseline"
        )
    for r in doc["results"]:
        if not isinstance(r, dict) or not all(
            k in r for k in ("label", "classifier", "features", "accuracy_mean")
        ):
            raise ConfigError(
                f"--baseline {path}: a row lacks label, classifier, features or accuracy_mean"
            )
    if doc["task"] != task:
        raise ConfigError(
            f"--baseline {path} is a baseline of {doc['task']}, not of {task}; valid: a "
            f"baseline saved from 'sim-tactile run {task}'"
        )
    if bool(doc.get("quick")) != bool(quick):
        mode = "--quick" if doc.get("quick") else "full"
        raise ConfigError(
            f"--baseline {path} was saved from a {mode} run of {task}; this run is "
            f"{'--quick' if quick else 'full'}: valid: a baseline of the same mode"
        )
    return doc


def check_tolerance(tolerance: float) -> float:
    t = float(tolerance)
    if not math.isfinite(t) or not 0.0 <= t <= 1.0:
        raise ConfigError(f"--tolerance = {tolerance!r}; valid: an accuracy in [0, 1]")
    return t


@dataclass(frozen=True)
class BaselineCheck:
    """The comparison: one row per key of either report (``status`` ``ok``, ``below``,
    ``missing`` or ``new``), and whether the run fails."""

    rows: list[dict]
    tolerance: float
    baseline: str

    @property
    def failed(self) -> bool:
        return any(r["status"] in ("below", "missing") for r in self.rows)

    def to_json(self) -> dict:
        return {
            "baseline": self.baseline,
            "tolerance": self.tolerance,
            "failed": self.failed,
            "rows": self.rows,
        }

    def table(self) -> list[str]:
        head = ["row", "baseline", "its 95% interval", "now", "change", "status"]

        def f(v):
            return "-" if v is None else f"{v:.4f}"

        rows = [
            [
                r["label"],
                f(r["baseline"]),
                interval_text(r["baseline_ci95"], 4),
                f(r["now"]),
                f(r["change"]),
                r["status"],
            ]
            for r in self.rows
        ]
        verdict = (
            f"FAILED: {sum(r['status'] in ('below', 'missing') for r in self.rows)} row(s) "
            f"below the baseline's interval by more than {self.tolerance:g}, or missing"
            if self.failed
            else f"passed: no row below the baseline's interval by more than {self.tolerance:g}"
        )
        return [f"against {self.baseline}:", *text_table(head, rows, right=(1, 3, 4)), verdict]


def compare_baseline(report: dict, baseline: dict, tolerance: float, name: str) -> BaselineCheck:
    """This run's ``report`` against ``baseline``, row by row."""
    tol = check_tolerance(tolerance)
    now, base = _rows(report), _rows(baseline)
    rows = []
    for key, b in base.items():
        r = now.get(key)
        bm, ci = float(b["accuracy_mean"]), baseline_interval(b)
        if r is None:
            rows.append(_row(key, bm, ci, None, "missing"))
            continue
        m = float(r["accuracy_mean"])
        low = bm if ci is None else min(bm, ci[0])
        status = "below" if m < low - tol - 1e-12 else "ok"
        rows.append(_row(key, bm, ci, m, status))
    rows += [
        _row(k, None, None, float(r["accuracy_mean"]), "new")
        for k, r in now.items()
        if k not in base
    ]
    return BaselineCheck(rows, tol, name)


def baseline_interval(row: dict) -> list[float] | None:
    """A baseline row's 95% interval: the one it holds, or the one of its repeats (a
    ``report.json`` of an older version holds the repeats only); None where it has neither
    (or fewer repeats than an interval needs)."""
    ci = row.get("accuracy_ci95")
    if isinstance(ci, list) and len(ci) == 2 and all(isinstance(v, int | float) for v in ci):
        return [float(ci[0]), float(ci[1])]
    reps = row.get("accuracies")
    if isinstance(reps, list) and reps and all(isinstance(v, int | float) for v in reps):
        return interval_list(reps)
    return None


def _row(key: tuple, base: float | None, ci, now: float | None, status: str) -> dict:
    change = None if base is None or now is None else now - base
    return {
        "task": key[0],
        "label": key[1],
        "classifier": key[2],
        "features": key[3],
        "baseline": base,
        "baseline_ci95": ci,
        "now": now,
        "change": change,
        "status": status,
    }


#: The keys of a row that a baseline keeps (the per-repeat details stay in report.json).
BASELINE_ROW_KEYS = (
    "label",
    "classifier",
    "features",
    "accuracy_mean",
    "accuracy_std",
    "accuracy_ci95",
    "repeats",
    "split",
    "channels",
)


def save_baseline(report: dict, path: str | Path) -> Path:
    """Write ``report`` as a baseline: its task, mode, protocol and environment, and each
    row's keys (:data:`BASELINE_ROW_KEYS`), small enough to commit beside a user's code (a
    whole ``report.json`` is a baseline too)."""
    path = Path(path)
    doc = {
        "task": report["task"],
        "quick": report.get("quick", False),
        "protocol": report.get("protocol", {}),
        "environment": report.get("environment", {}),
        "results": [
            {k: r[k] for k in BASELINE_ROW_KEYS if k in r} | _part(r) for r in report["results"]
        ],
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc, indent=1) + "\n")
    return path


def _part(row: dict) -> dict:
    return {"part": row["part"]} if "part" in row else {}
