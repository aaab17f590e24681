"""Run a benchmark task: data -> protocol for each classifier -> report and figures.

:func:`run_task` returns the contract's report ``{task, results: [{classifier, features,
accuracy_mean, accuracy_std, paper}], timing: {simulate_s, encode_s, classify_s}, figures}``
(with more keys) and writes ``report.json``, ``report.md`` and PNG figures into ``out_dir``.
"""

from __future__ import annotations

import json
import platform
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from sklearn.pipeline import Pipeline

from .. import __version__
from .._validate import integer
from ..errors import ConfigError, require
from ..learn.classifiers import get_classifier, make_classifier
from ..learn.protocols import EvalResult, evaluate, repeated_splits
from .registry import DataRequest, TaskSpec, get_task
from .report import compare, write_figures, write_markdown


def _stderr(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _seed(seed: int, *keys: int) -> int:
    return int(np.random.SeedSequence([seed, *keys]).generate_state(1)[0])


def _classifier_list(spec: TaskSpec, classifiers: Sequence[str] | str | None) -> list[str]:
    if classifiers is None:
        return list(spec.classifiers)
    names = classifiers.split(",") if isinstance(classifiers, str) else list(classifiers)
    names = [n.strip() for n in names if n.strip()]
    if not names:
        raise ConfigError("--classifiers is empty; give names like svm-raw,snn")
    for n in names:
        get_classifier(n)
    if len(set(names)) != len(names):
        raise ConfigError(f"--classifiers names a classifier twice: {','.join(names)}")
    return names


def run_task(
    task_id: str,
    out_dir: str | Path,
    *,
    quick: bool = False,
    data: str | Path | None = None,
    classifiers: Sequence[str] | str | None = None,
    repeats: int | None = None,
    seed: int = 0,
    log: Callable[[str], None] | None = None,
) -> dict:
    """Run ``task_id`` and write its report into ``out_dir``; returns the report dict.

    Args:
        quick: the task's quick settings (fewer epochs, repeats and time points).
        data: folder of the real data set (tasks ``*-real``).
        classifiers: names (list or ``"a,b"``) instead of the task's default set.
        repeats: number of splits for every classifier instead of the task's numbers.
        seed: seeds the splits and every model.
    """
    log = log or _stderr
    spec = get_task(task_id)
    names = _classifier_list(spec, classifiers)
    seed = integer("seed", seed, 0, None)
    if repeats is not None:
        repeats = integer("repeats", repeats, 1, None)
    if any(get_classifier(n).needs_torch for n in names):
        require("torch", "learn")
    if spec.needs_data_path and data is None:
        raise ConfigError(
            f"task {task_id} runs on real recordings: pass --data PATH (the folder of the data "
            f"set, e.g. ../shared/datasets/biotac_slide_20_50)"
        )
    settings = spec.settings(quick)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    t0 = time.perf_counter()
    ds = spec.get_data(DataRequest(None if data is None else Path(data), quick, seed, log))
    load_s = time.perf_counter() - t0
    log(
        f"{task_id}: {ds.n_samples} samples x {ds.n_time} steps x {ds.n_channels} channels at "
        f"{ds.rate_hz:g} Hz, {len(ds.class_names)} classes (loaded in {load_s:.1f} s)"
    )
    ctx = spec.context(ds, quick)

    t0 = time.perf_counter()
    encoded = Pipeline(spec.encoder(ctx)).fit_transform(ds.data)
    encode_s = time.perf_counter() - t0

    n_rep = {n: repeats or settings.repeats_for(n) for n in names}
    splits = repeated_splits(ds.labels, spec.split, max(n_rep.values()), _seed(seed, 0))
    results: dict[str, EvalResult] = {}
    wall: dict[str, float] = {}
    t_cls = time.perf_counter()
    for k, name in enumerate(names):
        cs = get_classifier(name)
        log(f"{task_id}: {name} on {cs.features}, split {spec.split}, {n_rep[name]} repeat(s)")
        t0 = time.perf_counter()
        results[name] = evaluate(
            lambda r, name=name, k=k: make_classifier(name, ctx, _seed(seed, 1 + k, r)),
            ds.data,
            ds.labels,
            splits[: n_rep[name]],
            times_s=settings.time_points_s,
            rate_hz=ds.rate_hz,
            anytime=cs.anytime,
            time_repeats=settings.time_repeats,
            log=log,
            name=name,
        )
        wall[name] = time.perf_counter() - t0
        r = results[name]
        log(f"{task_id}: {name} accuracy {r.mean:.3f} +- {r.std:.3f} ({wall[name]:.1f} s)")
    classify_s = time.perf_counter() - t_cls

    rows = []
    for name in names:
        r = results[name]
        cell = spec.paper.get(name)
        rows.append(
            {
                "classifier": name,
                "features": get_classifier(name).features,
                "accuracy_mean": round(r.mean, 4),
                "accuracy_std": round(r.std, 4),
                "paper": cell.to_json() if cell else None,
                "repeats": len(r.accuracies),
                "comparison": compare(r.mean, cell, spec.notes.get(name), quick=quick),
                "wall_s": round(wall[name], 2),
                **{
                    k: v
                    for k, v in r.to_json().items()
                    if k not in ("accuracy_mean", "accuracy_std")
                },
            }
        )
    report = {
        "task": task_id,
        "title": spec.title,
        "quick": quick,
        "results": rows,
        "timing": {
            "simulate_s": round(float(ds.meta.get("simulate_s", 0.0)), 3),
            "encode_s": round(encode_s, 3),
            "classify_s": round(classify_s, 3),
            "load_s": round(load_s, 3),
        },
        "figures": [],
        "protocol": {
            "split": spec.split,
            "repeats": n_rep,
            "time_points_s": list(settings.time_points_s),
            "time_repeats": settings.time_repeats,
            "seed": seed,
            "encoding": spec.encoding,
            "params": {n: dict(settings.params.get(n, {})) for n in names},
        },
        "dataset": ds.describe(),
        "remarks": list(spec.remarks),
        "reference": spec.reference,
        "environment": {
            "sim_tactile": __version__,
            "python": platform.python_version(),
            "machine": platform.machine(),
        },
    }
    report["figures"] = write_figures(out, spec, ds, encoded, results, names)
    report["timing"]["wall_s"] = round(time.perf_counter() - t_start, 2)
    (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
    write_markdown(out / "report.md", report, spec)
    return report
