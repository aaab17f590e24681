"""Stability: hard cases that must end in a measured result or a named error.

Each case is a small function that returns a :class:`Measured` (a one-line detail, the
numbers it measured, and named sanity checks on them) or raises. :func:`run_case` turns it
into ``{name, outcome, detail, ...}``:

- ``ok``: it returned, every number is finite and every check holds;
- ``error``: it raised a :class:`~sim_tactile.errors.SimTactileError` (PhysicsError,
  ConfigError, ...): a clear, named stop; the detail is the message;
- ``wrong``: it returned a non-finite number or failed a check: a silently wrong result;
- ``crash``: any other exception.

Only ``ok`` and ``error`` pass; ``bench stability`` exits non-zero otherwise. Each case also
says what it expects (``ok``, ``error`` or ``either``); ``as_expected`` reports whether it
got it, without making the run fail (a case that learns to give a measured result where it
used to stop is not a regression).

The sanity checks of a slide: finite loads and forces, no negative load (the ideal output
is a compressive normal load), some contact, and a mean normal force within a tolerance of
the command over a whole crossing (the bone's momentum balance: the pad starts and ends at
rest on flat ground, so the skin's mean load equals the press force).
"""

from __future__ import annotations

import math
import time
import traceback
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SimTactileError, UnknownNameError

PASS = ("ok", "error")


@dataclass
class Measured:
    """What a case measured: ``detail`` (one line), ``values`` (numbers or arrays that must
    all be finite) and ``checks`` (name -> whether the sanity check holds)."""

    detail: str
    values: dict[str, object] = field(default_factory=dict)
    checks: dict[str, bool] = field(default_factory=dict)


@dataclass(frozen=True)
class Case:
    name: str
    func: Callable[[], Measured]
    expect: str = "either"  # "ok", "error" or "either"
    about: str = ""


def problems(m: Measured) -> list[str]:
    """The reasons a measured result is not trustworthy: non-finite values, failed checks."""
    out = []
    for name, val in m.values.items():
        parts = val if isinstance(val, list) else [val]  # a list: ragged arrays (spike trains)
        try:
            bad = any(not np.all(np.isfinite(np.asarray(a, dtype=float))) for a in parts)
        except (TypeError, ValueError):
            out.append(f"{name} is not a number")
            continue
        if bad:
            out.append(f"{name} is not finite")
    out += [f"check failed: {name}" for name, ok in m.checks.items() if not ok]
    return out


def short(msg: str, n: int = 220) -> str:
    msg = " ".join(str(msg).split())
    return msg if len(msg) <= n else msg[: n - 3] + "..."


def _json_value(v: object) -> object:
    if isinstance(v, int | float | np.floating | np.integer):
        f = float(v)
        return f if math.isfinite(f) else repr(f)
    return None


def run_case(case: Case) -> dict:
    """Run one case and classify its outcome (see the module docstring)."""
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            m = case.func()
        except SimTactileError as exc:
            outcome, detail, m = "error", f"{type(exc).__name__}: {exc}", None
        except Exception as exc:  # the bench's job: a crash is a result to report
            tb = traceback.extract_tb(exc.__traceback__)
            where = f" (at {Path(tb[-1].filename).name}:{tb[-1].lineno})" if tb else ""
            outcome, detail, m = "crash", f"{type(exc).__name__}: {exc}{where}", None
    row: dict = {"name": case.name, "about": case.about}
    if m is not None:
        bad = problems(m)
        outcome = "wrong" if bad else "ok"
        detail = m.detail + (f"; WRONG: {', '.join(bad)}" if bad else "")
        row["values"] = {
            k: _json_value(v) for k, v in m.values.items() if _json_value(v) is not None
        }
        row["checks"] = dict(m.checks)
    py_warnings = list(
        dict.fromkeys(f"{w.category.__name__}: {short(w.message, 160)}" for w in caught)
    )
    if py_warnings:
        detail += "; warnings: " + " | ".join(py_warnings)
    row.update(
        {
            "outcome": outcome,
            "detail": detail,
            "expected": case.expect,
            "as_expected": case.expect == "either" or case.expect == outcome,
            "wall_s": time.perf_counter() - t0,
        }
    )
    return row


def run_stability(
    cases: Sequence[Case],
    names: Sequence[str] | None = None,
    *,
    log: Callable[[str], None] = lambda msg: None,
) -> dict:
    """Run ``cases`` (the package's: :data:`~.stability_cases.CASES`), all or those named,
    and return ``{cases: [...], failures, wall_s}``; ``failures`` counts the cases whose
    outcome is neither ``ok`` nor ``error``."""
    pool = list(cases)
    if names is not None:
        known = {c.name: c for c in pool}
        bad = [n for n in names if n not in known]
        if bad:
            raise UnknownNameError(
                f"stability case {bad[0]!r} is not known; valid: {', '.join(known)}"
            )
        pool = [known[n] for n in names]
    t0 = time.perf_counter()
    rows = []
    for case in pool:
        log(f"stability: {case.name} ...")
        row = run_case(case)
        log(f"  -> {row['outcome']} in {row['wall_s']:.2f} s: {short(row['detail'], 200)}")
        rows.append(row)
    failed = [r["name"] for r in rows if r["outcome"] not in PASS]
    return {
        "cases": rows,
        "failures": len(failed),
        "failed": failed,
        "wall_s": time.perf_counter() - t0,
    }


def table(doc: dict) -> str:
    """A plain-text table of the cases (for people)."""
    lines = [f"{'case':30s} {'outcome':8s} {'expected':8s} detail"]
    for r in doc["cases"]:
        lines.append(f"{r['name']:30s} {r['outcome']:8s} {r['expected']:8s} {r['detail']}")
    lines.append(
        f"\n{len(doc['cases'])} cases in {doc['wall_s']:.1f} s; "
        + (
            "all ended in a measured result or a named error"
            if not doc["failures"]
            else f"FAILED: {', '.join(doc['failed'])}"
        )
    )
    return "\n".join(lines)
