"""Grid sweeps of encoder, neuron and classifier parameters over a task's cached recordings.

``ablate(task, {"gain": [5, 15, 30], "preset": ["RS", "FS"]})`` loads the task's data once
(simulated slides come from the cache: nothing is simulated again when the task has run
before), then for every point of the grid re-encodes and re-runs the task's protocol with the
changed parameters, and writes a table and one plot of accuracy over each swept parameter.

The parameters, each with what it changes, are :data:`PARAM_HELP`; ``sim-tactile tasks``
and the manual's task pages name the ones each task uses (:func:`used_params`).

A parameter that no step of the task uses is an error that names the parameter and the
valid ones, rather than a sweep that silently changes nothing.
"""

from __future__ import annotations

import itertools
import json
import re
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np
from sklearn.pipeline import Pipeline

from ..encoders import IzhikevichEncoder, ThresholdEncoder
from ..encoders.encodings import Steps
from ..encoders.neurons import izhikevich_preset
from ..encoders.scaling import RangeScaler
from ..errors import ConfigError
from ..tables import markdown_table
from .intervals import interval_text
from .registry import Run, TaskSpec, use_task
from .runner import evaluate_task, load_task, stderr_log, task_runs

#: What each ablation parameter (``--set NAME=v1,v2``) changes, with its unit and range.
PARAM_HELP = {
    "gain": "the Izhikevich or LIF input gain (> 0), replacing the task's max-rate calibration",
    "max_rate_hz": "the Izhikevich gain calibrated for this maximum firing rate [Hz] (> 0)",
    "preset": "the Izhikevich preset: RS, FS, SA (= RS) or RA (= FS)",
    "a": "the Izhikevich recovery time scale a (the others from the task's preset)",
    "b": "the Izhikevich recovery sensitivity b (the others from the task's preset)",
    "c": "the Izhikevich reset potential c [mV] (the others from the task's preset)",
    "d": "the Izhikevich reset of the recovery variable d (the others from the task's preset)",
    "K": "the number of thresholds of the threshold encoding (1..10; 2K + 1 spike channels): "
    "K levels 1 SD apart around 0 for per-slide standardised encodings, at 1 .. K of a "
    "[0, K + 1] range for range encodings",
    "q": "the Victor-Purpura cost [1/s] of the STD-kNN rows (> 0)",
    "tau": "the van Rossum time constant [s] of the STD-kNN rows (> 0)",
    "k": "the number of neighbours of the kNN and STD-kNN rows (1..500)",
    "C": "the regularisation of the linear SVMs (> 0)",
}
ENCODER_PARAMS = ("gain", "max_rate_hz", "preset", "a", "b", "c", "d", "K")
CLASSIFIER_PARAMS = ("q", "tau", "k", "C")
PARAMS = ENCODER_PARAMS + CLASSIFIER_PARAMS
_NUMERIC = {"gain", "max_rate_hz", "a", "b", "c", "d", "q", "tau", "C"}


def parse_sets(items: Sequence[str]) -> dict[str, list]:
    """``["gain=5,15", "preset=RS,FS"]`` -> ``{"gain": [5.0, 15.0], "preset": ["RS", "FS"]}``."""
    out: dict[str, list] = {}
    for item in items:
        name, sep, values = str(item).partition("=")
        name = name.strip()
        if not sep or not name or not values.strip():
            raise ConfigError(f"--set {item!r} is not NAME=v1,v2,...; valid names: {PARAMS}")
        if name not in PARAMS:
            raise ConfigError(f"--set {name}: unknown parameter; valid: {', '.join(PARAMS)}")
        if name in out:
            raise ConfigError(f"--set {name} is given twice")
        vals = [v.strip() for v in values.split(",") if v.strip()]
        out[name] = [_value(name, v) for v in vals]
    if not out:
        raise ConfigError("ablate needs at least one --set NAME=v1,v2")
    return out


def _value(name: str, text: str):
    if name in ("K", "k"):
        try:
            v = int(text)
        except ValueError:
            raise ConfigError(f"--set {name}: {text!r} is not an integer") from None
        if v < 1 or v > (10 if name == "K" else 500):
            raise ConfigError(f"--set {name} = {v}; valid: 1..{10 if name == 'K' else 500}")
        return v
    if name in _NUMERIC:
        try:
            v = float(text)
        except ValueError:
            raise ConfigError(f"--set {name}: {text!r} is not a number") from None
        if not np.isfinite(v) or (name in ("gain", "max_rate_hz", "q", "tau", "C") and v <= 0):
            raise ConfigError(f"--set {name} = {text}; valid: a finite number > 0")
        return v
    izhikevich_preset(text)  # names the valid presets when unknown
    return text


def _izh_params(enc: IzhikevichEncoder, point: Mapping) -> dict:
    """An Izhikevich encoder's parameters at ``point`` (its own names)."""
    kw = {}
    if "preset" in point:
        kw["preset"] = point["preset"]
    abcd = {k: point[k] for k in "abcd" if k in point}
    if abcd:
        base = kw.get("preset", enc.preset)
        bases = base if isinstance(base, list | tuple) else [base]
        new = [replace(izhikevich_preset(b), **abcd) for b in bases]
        kw["preset"] = new if isinstance(base, list | tuple) else new[0]
    if "gain" in point:
        kw.update(gain=point["gain"], max_rate_hz=None)
    if "max_rate_hz" in point:
        kw["max_rate_hz"] = point["max_rate_hz"]
    return kw


def encoding_params(steps: Steps, point: Mapping) -> dict:
    """The encoding's parameters at ``point``, by scikit-learn's ``step__param`` names of the
    pipeline of ``steps`` (``encode__gain``, ``scale__span``, ...). ``K`` thresholds sit 1 SD
    apart around 0 after a per-sample standardisation, or at 1 .. K after a range scaler
    (whose span becomes K + 1)."""
    out = {}
    scaler = next((n for n, s in steps if isinstance(s, RangeScaler)), None)
    for name, est in steps:
        if isinstance(est, IzhikevichEncoder):
            out.update({f"{name}__{k}": x for k, x in _izh_params(est, point).items()})
        if isinstance(est, ThresholdEncoder) and "K" in point:
            k = int(point["K"])
            if scaler is not None:
                out[f"{scaler}__span"] = float(k + 1)
                out[f"{name}__thresholds"] = np.arange(1.0, k + 1.0)
            else:
                out[f"{name}__thresholds"] = np.arange(k) - (k - 1) / 2.0
    return out


def used_params(spec: TaskSpec) -> set[str]:
    """The parameters of :data:`PARAMS` that some step of ``spec`` uses (a suite: none)."""
    if spec.parts:
        return set()
    from ..learn.classifiers import LearnContext

    used = set()
    steps = spec.encoder(LearnContext(rate_hz=100.0, n_channels=1, encoder=spec.encoder))
    for _, est in steps:
        if isinstance(est, IzhikevichEncoder):
            used |= {"gain", "max_rate_hz", "preset", "a", "b", "c", "d"}
        if isinstance(est, ThresholdEncoder):
            used.add("K")
    classes = {r.classifier for r in spec.all_runs()}
    if "std-knn" in classes:
        used |= {"q", "tau", "k"}
    if "knn" in classes:
        used.add("k")
    if classes & {"svm", "svm-raw", "svm-spike"}:
        used.add("C")
    return used


def _relabel(label: str, point: Mapping) -> str:
    """A run's label with the swept values written into it (``q=24/s`` -> ``q=6/s``)."""
    out = label
    if "q" in point:
        out = re.sub(r"q=[0-9.]+/s", f"q={point['q']:g}/s", out)
    if "tau" in point:
        out = re.sub(r"tau=[0-9.]+ms", f"tau={point['tau'] * 1e3:g}ms", out)
    if "k" in point:
        out = re.sub(r"\bk=[0-9]+", f"k={point['k']}", out)
    return out


def _point_spec(spec: TaskSpec, point: Mapping) -> TaskSpec:
    enc_point = {k: v for k, v in point.items() if k in ENCODER_PARAMS}
    base_encoder = spec.encoder

    def encoder(ctx, base=base_encoder, p=enc_point):
        steps = base(ctx)
        Pipeline(steps).set_params(**encoding_params(steps, p))  # sets the steps' estimators
        return steps

    runs = []
    for r in spec.all_runs():
        params = dict(r.params)
        if r.classifier == "std-knn":
            metric = params.get("metric", "victor_purpura")
            if "q" in point and metric in ("victor_purpura", "vp"):
                params["q"] = point["q"]
            if "tau" in point and metric in ("van_rossum", "vr"):
                params["tau"] = point["tau"]
        if "k" in point and r.classifier in ("knn", "std-knn"):
            params["n_neighbors"] = point["k"]
        if "C" in point and r.classifier in ("svm", "svm-raw", "svm-spike"):
            params["C"] = point["C"]
        runs.append(replace(r, params=params, paper=None, label=_relabel(r.name, point)))
    return replace(spec, encoder=encoder, runs=tuple(runs), encode_once=spec.encode_once)


def ablate(
    task_id: str,
    sets: Mapping[str, Sequence],
    out_dir: str | Path,
    *,
    quick: bool = False,
    data: str | Path | None = None,
    classifiers: Sequence[str] | str | None = None,
    repeats: int | None = None,
    seed: int = 0,
    log: Callable[[str], None] | None = None,
    store: str | Path | None = None,
) -> dict:
    """Sweep the grid ``sets`` (name -> values) over the task's data (or the data set in
    ``store``); returns ``{task, rows: [{params, classifier, label, accuracy_mean,
    accuracy_std, accuracy_ci95}], figures}``."""
    log = log or stderr_log
    spec = use_task(task_id)
    if spec.parts:
        raise ConfigError(
            f"task {task_id} is made of parts; ablate one of them: {', '.join(spec.parts)}"
        )
    sets = {k: list(v) for k, v in sets.items()}
    for k, v in sets.items():
        if k not in PARAMS:
            raise ConfigError(f"ablate: unknown parameter {k!r}; valid: {', '.join(PARAMS)}")
        if not v:
            raise ConfigError(f"ablate: parameter {k} has no values")
    unused = sorted(set(sets) - used_params(spec))
    if unused:
        raise ConfigError(
            f"task {task_id} does not use {', '.join(unused)}; it uses: "
            f"{', '.join(p for p in PARAMS if p in used_params(spec))}"
        )
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    task = load_task(
        spec, quick=quick, data=data, classifiers=classifiers, seed=seed, log=log, store=store
    )
    base_runs = task.runs
    keys = list(sets)
    grid = [dict(zip(keys, vals, strict=True)) for vals in itertools.product(*sets.values())]
    rows = []
    for n, point in enumerate(grid):
        log(f"ablate {task_id}: point {n + 1}/{len(grid)}: {point}")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            pspec = _point_spec(spec, point)
            rep = evaluate_task(
                pspec,
                task.ds,
                out / f"point-{n:03d}",
                quick=quick,
                runs=task_runs(pspec, classifiers),
                repeats=repeats,
                seed=seed,
                log=lambda m: None,
                figures=False,
            )
            rep.write(out / f"point-{n:03d}")
        notes = sorted({str(w.message) for w in caught})
        for msg in notes:
            log(f"  warning: {msg}")
        for base, r in zip(base_runs, rep.results, strict=True):
            rows.append(
                {
                    "params": point,
                    "run": base.name,
                    "classifier": r.classifier,
                    "label": r.label,
                    "accuracy_mean": r.accuracy_mean,
                    "accuracy_std": r.accuracy_std,
                    "accuracy_ci95": r.accuracy_ci95,
                    "repeats": r.repeats,
                    "warnings": notes,
                }
            )
        best = max(rep.results, key=lambda r: r.accuracy_mean)
        log(f"  best: {best.label} {best.accuracy_mean:.3f}")
    report = {
        "task": task_id,
        "quick": quick,
        "sets": sets,
        "rows": rows,
        "timing": {
            "load_s": round(task.load_s, 3),
            "wall_s": round(time.perf_counter() - t0, 2),
        },
        "figures": [],
    }
    f = out / "ablation.png"
    plot_ablation(rows, sets, task_id, f)
    report["figures"].append(str(f))
    (out / "ablation.json").write_text(json.dumps(report, indent=2) + "\n")
    _markdown(out / "ablation.md", report)
    return report


def ablation_rows(report: dict) -> tuple[list[str], list[list[str]]]:
    """The ablation's table: the swept parameters, the run, its accuracy (mean, SD and 95%
    interval) and repeats."""
    keys = list(report["sets"])
    head = [*keys, "run", "accuracy (SD)", "95% interval", "repeats"]
    rows = [
        [*(str(r["params"][k]) for k in keys), r["label"]]
        + [f"{r['accuracy_mean']:.3f} ({r['accuracy_std']:.3f})"]
        + [interval_text(r.get("accuracy_ci95")), str(r["repeats"])]
        for r in report["rows"]
    ]
    return head, rows


def _markdown(path: Path, report: dict) -> None:
    title = f"# Ablation of {report['task']}" + (" (quick)" if report["quick"] else "")
    path.write_text("\n".join([title, "", *markdown_table(*ablation_rows(report))]) + "\n")


def plot_ablation(rows: list[dict], sets: Mapping[str, Sequence], title: str, out: Path) -> None:
    """One panel per swept parameter: accuracy against its values, the other parameters at
    their first value, one line per run of the task (up to 20, each in its own colour and
    marker), the legend beside the panels."""
    import matplotlib
    from matplotlib.figure import Figure

    keys = list(sets)
    labels = list(dict.fromkeys(r["run"] for r in rows))[:20]
    colours = matplotlib.colormaps["tab10" if len(labels) <= 10 else "tab20"]
    markers = "osD^v<>pXh"
    fig = Figure(figsize=(4.6 * len(keys) + 2.6, 3.9), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(keys), squeeze=False, sharey=True)).ravel()
    for ax, key in zip(axes, keys, strict=True):
        others = {k: sets[k][0] for k in keys if k != key}
        values = list(sets[key])
        numeric = all(isinstance(v, int | float) for v in values)
        xs = values if numeric else list(range(len(values)))
        for n, lab in enumerate(labels):
            sel = [
                r
                for r in rows
                if r["run"] == lab and all(r["params"][k] == v for k, v in others.items())
            ]
            by = {str(r["params"][key]): r for r in sel}
            m = [by[str(v)]["accuracy_mean"] if str(v) in by else np.nan for v in values]
            s = [by[str(v)]["accuracy_std"] if str(v) in by else np.nan for v in values]
            ax.errorbar(
                xs,
                m,
                yerr=s,
                marker=markers[n % len(markers)],
                ms=4,
                lw=1.2,
                capsize=2,
                color=colours(n),
                label=lab,
            )
        if numeric and len(values) > 2 and min(values) > 0 and max(values) / min(values) >= 20:
            ax.set_xscale("log")
        ax.set_xticks(xs, [f"{v:g}" if numeric else str(v) for v in values])
        ax.minorticks_off()
        if len(values) > 6:
            ax.tick_params(axis="x", labelrotation=45)
        ax.set_xlabel(key, fontsize=9)
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
        ax.set_title(
            ", ".join(f"{k} = {v}" for k, v in others.items()) if others else "",
            fontsize=8,
        )
    axes[0].set_ylabel("accuracy (mean and SD over the repeats)", fontsize=9)
    fig.legend(
        *axes[0].get_legend_handles_labels(),
        loc="outside right upper",
        fontsize=7,
        title="run",
        title_fontsize=7,
    )
    fig.suptitle(f"ablation of {title}", fontsize=10)
    fig.savefig(out, dpi=110)


__all__ = ["PARAMS", "PARAM_HELP", "ablate", "parse_sets", "plot_ablation", "used_params", "Run"]
