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
from dataclasses import replace
from pathlib import Path

import numpy as np
from sklearn.pipeline import Pipeline

from .. import __version__
from .._validate import integer
from ..datasets.reader import open_store, parts_of
from ..errors import ConfigError, StoreError, require
from ..hashing import derive_seed
from ..learn.classifiers import (
    FEATURE_MODELS,
    LearnContext,
    feature_estimator,
    get_classifier,
    make_classifier,
    std_knn_params,
)
from ..learn.precomputed import OnDistances, OnFeatures, sample_index
from ..learn.protocols import EvalResult, evaluate, repeated_splits
from ..records import TactileDataset
from ..slides import SlideSet
from ..slides.plan import task_slide_config
from ..spikes import SpikeFeatures
from ..spikes.multichannel import pairwise_multichannel
from ..spikes.trains import SpikeTrains
from .registry import DataRequest, Run, TaskSpec, get_task
from .report import compare, paper_text, write_figures, write_markdown


def _path(p: str | Path | None) -> Path | None:
    return None if p is None else Path(p)


def _stderr(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _classifier_list(spec: TaskSpec, classifiers: Sequence[str] | str | None) -> list[str]:
    if classifiers is None:
        return list(dict.fromkeys(r.classifier for r in spec.all_runs()))
    names = classifiers.split(",") if isinstance(classifiers, str) else list(classifiers)
    names = [n.strip() for n in names if n.strip()]
    if not names:
        raise ConfigError("--classifiers is empty; give names like svm-raw,snn")
    for n in names:
        get_classifier(n)
    if len(set(names)) != len(names):
        raise ConfigError(f"--classifiers names a classifier twice: {','.join(names)}")
    return names


def _runs(spec: TaskSpec, classifiers, names: list[str]) -> list[Run]:
    """The task's runs, restricted to ``names`` when the user chose classifiers; a chosen
    classifier without a run of its own gets one on all channels."""
    runs = list(spec.all_runs())
    if classifiers is None:
        return runs
    out = [r for r in runs if r.classifier in names]
    out += [Run(n, paper=spec.paper.get(n)) for n in names if all(r.classifier != n for r in out)]
    return out


def _channels(spec: TaskSpec, run: Run, ds) -> list[int] | None:
    if run.channels == "all":
        return None
    cols = [int(c) for c in spec.channel_sets[run.channels]]
    if not cols or min(cols) < 0 or max(cols) >= ds.n_channels:
        raise ConfigError(
            f"channel set {run.channels!r} = {cols} is not within the data's "
            f"{ds.n_channels} channels"
        )
    return cols


def _run_context(ctx: LearnContext, run: Run, cols, ds) -> LearnContext:
    params = {k: dict(v) for k, v in ctx.params.items()}
    run_params = dict(run.params)
    features = run_params.pop("features", ctx.spike_features)
    if run_params:
        params[run.classifier] = {**params.get(run.classifier, {}), **run_params}
    return replace(
        ctx,
        spike_features=tuple([features] if isinstance(features, str) else features),
        n_channels=ds.n_channels if cols is None else len(cols),
        grid_shape=ctx.grid_shape if cols is None else None,
        params=params,
    )


class _Precomputed:
    """Spike features and spike-train distances of the whole data set, computed once from
    the encoding fitted on all samples (tasks with ``encode_once``)."""

    def __init__(self, spec: TaskSpec, ds, encoded) -> None:
        if encoded[0].n_channels != ds.n_channels:
            raise ConfigError(
                f"task {spec.id}: encode_once needs one spike train per input channel, the "
                f"encoder gives {encoded[0].n_channels} for {ds.n_channels}"
            )
        self.encoded = encoded
        self.features = spec.features
        self._feats = SpikeFeatures(features=spec.features).fit_transform(encoded)
        self._dist: dict[str, np.ndarray] = {}
        self.distance_s = 0.0

    @staticmethod
    def handles(name: str) -> bool:
        return name in FEATURE_MODELS or name == "std-knn"

    def describe(self) -> dict:
        return {
            "features": list(self.features),
            "feature_matrix": list(self._feats.shape),
            "distance_matrices": sorted(self._dist),
            "distance_s": round(self.distance_s, 3),
        }

    def estimator(self, name: str, ctx: LearnContext, cols):
        if name in FEATURE_MODELS:
            nf = len(self.features)
            missing = [f for f in ctx.spike_features if f not in self.features]
            if missing:
                raise ConfigError(
                    f"spike features {missing} are not among the task's precomputed features "
                    f"{list(self.features)}"
                )
            which = [self.features.index(f) for f in ctx.spike_features]
            chans = range(self.encoded[0].n_channels) if cols is None else cols
            sel = [c * nf + j for c in chans for j in which]
            return OnFeatures(feature_estimator(name, ctx), self._feats[:, sel])
        metric, params, combine, k = std_knn_params(ctx)
        key = json.dumps([metric, params, combine, cols], sort_keys=True)
        if key not in self._dist:
            t0 = time.perf_counter()
            trains = self.encoded
            if cols is not None:
                trains = [
                    SpikeTrains(
                        tuple(s.times[c] for c in cols),
                        s.t_start,
                        s.t_end,
                        tuple(s.channel_names[c] for c in cols),
                    )
                    for s in self.encoded
                ]
            self._dist[key] = pairwise_multichannel(trains, metric, combine=combine, **params)
            self.distance_s += time.perf_counter() - t0
        return OnDistances(self._dist[key], n_neighbors=k)


def task_data(spec: TaskSpec, req: DataRequest) -> TactileDataset:
    """The task's data set: ``spec.get_data(req)``, or, with ``req.store``, the store's data
    set after checking that it was generated for this task with the same quick flag and seed
    (and, for simulated tasks, the same configuration and slide code)."""
    if req.store is None:
        return spec.get_data(req)
    path = req.store
    st = open_store(path, spec.id if spec.id in parts_of(path) else None)
    cfg = st.config
    if cfg.get("task") != spec.id or bool(cfg.get("quick")) != req.quick:
        raise StoreError(
            f"{st.path} holds {cfg.get('task') or 'a configuration file'}'s "
            f"{'quick ' if cfg.get('quick') else ''}data, not {spec.id}"
            f"{' --quick' if req.quick else ''}: generate it with 'sim-tactile generate "
            f"{spec.id}{' --quick' if req.quick else ''} --out DIR.zarr'"
        )
    if isinstance(spec.get_data, SlideSet):
        want, code = task_slide_config(spec.get_data, spec.id, req.quick, req.seed)
        if st.config_hash != want:
            raise StoreError(
                f"{st.path} was generated with another configuration (hash {st.config_hash}, "
                f"{spec.id} with seed {req.seed} is {want}); generate it again"
            )
        if st.meta.get("code_version") != code:
            raise StoreError(
                f"{st.path} was simulated by another version of the simulating code "
                f"({st.meta.get('code_version')}, now {code}); generate it again"
            )
    req.log(f"{spec.id}: reading {len(st)} slides from {st.path} ({st.config_hash})")
    return st.to_tactile()


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
    store: str | Path | None = None,
) -> dict:
    """Run ``task_id`` and write its report into ``out_dir``; returns the report dict.

    Args:
        quick: the task's quick settings (fewer epochs, repeats and time points).
        data: folder of the real data set (tasks ``*-real``).
        classifiers: names (list or ``"a,b"``) instead of the task's default set.
        repeats: number of splits for every classifier instead of the task's numbers.
        seed: seeds the splits and every model.
        store: read the data from this store (``sim-tactile generate``) instead.
    """
    log = log or _stderr
    spec = get_task(task_id)
    if spec.parts:
        return _run_suite(spec, out_dir, quick, data, classifiers, repeats, seed, log, store)
    names = _classifier_list(spec, classifiers)
    seed = integer("seed", seed, 0, None)
    if repeats is not None:
        repeats = integer("repeats", repeats, 1, None)
    if any(get_classifier(n).needs_torch for n in names):
        require("torch", "learn")
    if spec.needs_data_path and data is None and store is None:
        raise ConfigError(
            f"task {task_id} runs on real recordings: pass --data PATH (the folder of the data "
            f"set, e.g. ../shared/datasets/biotac_slide_20_50)"
        )
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    t0 = time.perf_counter()
    ds = task_data(spec, DataRequest(_path(data), quick, seed, log, _path(store)))
    load_s = time.perf_counter() - t0
    log(
        f"{task_id}: {ds.n_samples} samples x {ds.n_time} steps x {ds.n_channels} channels at "
        f"{ds.rate_hz:g} Hz, {len(ds.class_names)} classes (loaded in {load_s:.1f} s)"
    )
    return evaluate_task(
        spec,
        ds,
        out,
        quick=quick,
        classifiers=classifiers,
        names=names,
        repeats=repeats,
        seed=seed,
        log=log,
        load_s=load_s,
        t_start=t_start,
    )


def evaluate_task(
    spec: TaskSpec,
    ds,
    out: Path,
    *,
    quick: bool,
    classifiers,
    names: list[str],
    repeats: int | None,
    seed: int,
    log: Callable[[str], None],
    load_s: float = 0.0,
    t_start: float | None = None,
    figures: bool = True,
) -> dict:
    """Encode, classify and report a loaded data set under ``spec`` (see :func:`run_task`)."""
    t_start = time.perf_counter() if t_start is None else t_start
    task_id = spec.id
    settings = spec.settings(quick)
    out.mkdir(parents=True, exist_ok=True)
    ctx = spec.context(ds, quick)

    t0 = time.perf_counter()
    encoded = Pipeline(spec.encoder(ctx)).fit_transform(ds.data)
    encode_s = time.perf_counter() - t0

    runs = _runs(spec, classifiers, names)
    n_rep = {r.name: repeats or settings.repeats_for(r.classifier) for r in runs}
    pre = _Precomputed(spec, ds, encoded) if spec.encode_once else None
    split_cache: dict[str, list] = {}
    results: dict[str, EvalResult] = {}
    wall: dict[str, float] = {}
    t_cls = time.perf_counter()
    for run in runs:
        name = run.name
        cs = get_classifier(run.classifier)
        split = spec.split_for(run, quick)
        cols = _channels(spec, run, ds)
        if split not in split_cache:
            split_cache[split] = repeated_splits(
                ds.labels, split, max(n_rep.values()), derive_seed(seed, 0)
            )
        rctx = _run_context(ctx, run, cols, ds)
        log(f"{task_id}: {name} on {cs.features}, split {split}, {n_rep[name]} repeat(s)")
        t0 = time.perf_counter()
        if pre is not None and pre.handles(run.classifier):
            x, times_s = sample_index(ds.n_samples), ()

            def make(r, run=run, cols=cols, rctx=rctx):
                return pre.estimator(run.classifier, rctx, cols)
        else:
            x = ds.data if cols is None else ds.data[:, :, cols]
            times_s = settings.time_points_s

            def make(r, run=run, rctx=rctx):
                return make_classifier(
                    run.classifier, rctx, derive_seed(seed, "model", run.classifier, r)
                )

        results[name] = evaluate(
            make,
            x,
            ds.labels,
            split_cache[split][: n_rep[name]],
            times_s=times_s,
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
    for run in runs:
        name = run.name
        r = results[name]
        cell = run.paper
        rows.append(
            {
                "classifier": run.classifier,
                "label": name,
                "channels": run.channels,
                "split": spec.split_for(run, quick),
                "features": get_classifier(run.classifier).features,
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
            "split": spec.settings(quick).split or spec.split,
            "repeats": n_rep,
            "time_points_s": list(settings.time_points_s),
            "time_repeats": settings.time_repeats,
            "seed": seed,
            "encoding": spec.encoding,
            "params": {n: dict(settings.params.get(n, {})) for n in names},
            "precomputed": pre.describe() if pre is not None else None,
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
    if figures:
        report["figures"] = write_figures(out, spec, ds, encoded, results, runs)
    report["timing"]["wall_s"] = round(time.perf_counter() - t_start, 2)
    (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
    write_markdown(out / "report.md", report, spec)
    return report


def _run_suite(
    spec: TaskSpec, out_dir, quick, data, classifiers, repeats, seed, log, store
) -> dict:
    """A task made of parts (one per sensor): each part's report in ``out_dir/<part>``, and
    one report whose rows are the parts' rows, labelled ``<part>: <row>``."""
    t0 = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    parts = {}
    for part in spec.parts:
        log(f"{spec.id}: part {part}")
        parts[part] = run_task(
            part,
            out / part,
            quick=quick,
            data=data,
            classifiers=classifiers,
            repeats=repeats,
            seed=seed,
            log=log,
            store=store,
        )
    rows = [
        {**r, "label": f"{part}: {r.get('label', r['classifier'])}", "part": part}
        for part, rep in parts.items()
        for r in rep["results"]
    ]
    timing = {
        k: round(sum(rep["timing"].get(k, 0.0) for rep in parts.values()), 3)
        for k in ("simulate_s", "encode_s", "classify_s", "load_s")
    }
    timing["wall_s"] = round(time.perf_counter() - t0, 2)
    report = {
        "task": spec.id,
        "title": spec.title,
        "quick": quick,
        "results": rows,
        "timing": timing,
        "figures": [f for rep in parts.values() for f in rep["figures"]],
        "parts": {part: str(out / part / "report.json") for part in parts},
        "protocol": {part: rep["protocol"] for part, rep in parts.items()},
        "dataset": {part: rep["dataset"] for part, rep in parts.items()},
        "remarks": list(spec.remarks),
        "reference": spec.reference,
        "environment": next(iter(parts.values()))["environment"],
    }
    (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
    lines = [f"# {spec.id}: {spec.title}", ""]
    if quick:
        lines += ["**Quick run**: fewer plates, slides, epochs and repeats.", ""]
    lines += [
        "| run | accuracy (SD) | paper (SD) | repeats | vs paper |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        ptxt = paper_text(r["paper"])
        lines.append(
            f"| {r['label']} | {r['accuracy_mean']:.3f} ({r['accuracy_std']:.3f}) | {ptxt} | "
            f"{r['repeats']} | {r['comparison']['message']} |"
        )
    lines += ["", "Parts: " + ", ".join(f"[{p}]({p}/report.md)" for p in parts)]
    lines += [""] + [f"- {x}" for x in spec.remarks]
    (out / "report.md").write_text("\n".join(lines) + "\n")
    return report
