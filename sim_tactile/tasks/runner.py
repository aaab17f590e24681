"""Run a benchmark task: data -> protocol for each classifier -> report and figures.

:func:`run_task` returns the report ``{task, results: [{classifier, features,
accuracy_mean, accuracy_std, paper}], timing: {simulate_s, encode_s, classify_s}, figures}``
(with more keys; :class:`~.report.Report`) and writes ``report.json``, ``report.md`` and PNG
figures into ``out_dir``. :func:`load_task` is the part ``run`` and ``ablate`` share: the
task, its checked options and its data.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from sklearn.pipeline import Pipeline

from .._validate import integer
from ..datasets.fs import no_empty_folders_left, write_faults
from ..datasets.reader import open_store, parts_of
from ..errors import ConfigError, StoreError
from ..hashing import derive_seed
from ..learn.classifiers import LearnContext, get_classifier, make_classifier
from ..learn.precomputed import sample_index
from ..learn.protocols import EvalResult, evaluate
from ..records import TactileDataset
from ..sensors.calibration import load_calibration
from ..slides import SlideSet
from ..slides.plan import slide_plan, task_slide_config
from .config_task import PREFIX as CONFIG_PREFIX
from .config_task import config_task, is_config_path
from .figures import write_figures
from .flags import flag_rows
from .intervals import interval_list
from .methods import Method, as_methods, classify_methods, method_row
from .needs import check_torch
from .nir_export import check_nir_export, export_snn, nir_row
from .precompute import Precomputed
from .registry import DataRequest, Run, TaskSpec, quiet_outdated, use_task, with_calibration
from .report import Report, ResultRow, compare
from .result_file import environment, write_result_files
from .splits import splits_digest, task_splits


def stderr_log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def classifier_list(spec: TaskSpec, classifiers: Sequence[str] | str | None) -> list[str]:
    """The classifier names a run uses: the task's, or the user's (``"a,b"`` or a list)."""
    if classifiers is None:
        return list(dict.fromkeys(r.classifier for r in spec.all_runs()))
    if isinstance(classifiers, str) and classifiers.strip() == "none":
        return []  # no built-in row: the user's methods only
    names = classifiers.split(",") if isinstance(classifiers, str) else list(classifiers)
    names = [n.strip() for n in names if n.strip()]
    if not names:
        raise ConfigError("--classifiers is empty; give names like svm-raw,snn (or none)")
    for n in names:
        get_classifier(n)
    if len(set(names)) != len(names):
        raise ConfigError(f"--classifiers names a classifier twice: {','.join(names)}")
    return names


def task_runs(spec: TaskSpec, classifiers: Sequence[str] | str | None) -> list[Run]:
    """The task's runs, restricted to the chosen classifiers; a chosen classifier without a
    run of its own gets one on all channels."""
    runs = list(spec.all_runs())
    if classifiers is None:
        return runs
    names = classifier_list(spec, classifiers)
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


def task_data(spec: TaskSpec, req: DataRequest) -> TactileDataset:
    """The task's data set: ``spec.get_data(req)``, or, with ``req.store``, the store's data
    set after checking that it was generated for this task with the same quick flag and seed
    (and, for simulated tasks, the same configuration and slide code, and the labels, slide
    numbers, seeds and drawn parameters that configuration gives, derived again here)."""
    if req.store is None:
        return spec.get_data(req)
    path = req.store
    st = open_store(path, spec.id if spec.id in parts_of(path) else None)
    cfg = st.config
    task = None if spec.id.startswith(CONFIG_PREFIX) else spec.id  # a file's: no task
    if cfg.get("task") != task or bool(cfg.get("quick")) != req.quick:
        raise StoreError(
            f"{st.path} holds {cfg.get('task') or 'a configuration file'}'s "
            f"{'quick ' if cfg.get('quick') else ''}data, not {spec.id}"
            f"{' --quick' if req.quick else ''}: generate it with 'sim-tactile generate "
            f"{spec.id}{' --quick' if req.quick else ''} --out DIR.zarr'"
        )
    if isinstance(spec.get_data, SlideSet):
        want, code = task_slide_config(spec.get_data, task, req.quick, req.seed)
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
        plan = slide_plan(spec.get_data, quick=req.quick, seed=req.seed, task=task, name=spec.id)
        st.check_against(plan.spec.index())
    req.log(f"{spec.id}: reading {len(st)} slides from {st.path} ({st.config_hash})")
    return st.to_tactile()


@dataclass
class LoadedTask:
    """A task, its runs under the chosen classifiers, and its data set (loaded in ``load_s``)."""

    spec: TaskSpec
    runs: list[Run]
    ds: TactileDataset
    load_s: float


def load_task(
    spec: TaskSpec,
    *,
    quick: bool,
    data: str | Path | None,
    classifiers: Sequence[str] | str | None,
    seed: int,
    log: Callable[[str], None],
    store: str | Path | None = None,
) -> LoadedTask:
    """Check the options against the task, then load (or simulate) its data set."""
    runs = task_runs(spec, classifiers)
    check_torch(spec, runs)
    if spec.needs_data_path and data is None and store is None:
        raise ConfigError(
            f"task {spec.id} runs on real recordings: pass --data PATH (the folder of the data "
            f"set, e.g. ../shared/datasets/biotac_slide_20_50)"
        )
    t0 = time.perf_counter()
    req = DataRequest(
        None if data is None else Path(data),
        quick,
        seed,
        log,
        None if store is None else Path(store),
    )
    ds = task_data(spec, req)
    load_s = time.perf_counter() - t0
    log(
        f"{spec.id}: {ds.n_samples} samples x {ds.n_time} steps x {ds.n_channels} channels at "
        f"{ds.rate_hz:g} Hz, {len(ds.class_names)} classes (loaded in {load_s:.1f} s)"
    )
    return LoadedTask(spec, runs, ds, load_s)


def run_task(
    task_id: str,
    out_dir: str | Path,
    *,
    quick: bool = False,
    data: str | Path | None = None,
    classifiers: Sequence[str] | str | None = None,
    repeats: int | None = None,
    seed: int | None = None,
    log: Callable[[str], None] | None = None,
    store: str | Path | None = None,
    sensor_config: str | Path | None = None,
    methods=None,
    export_nir: str | Path | None = None,
    about=None,
) -> dict:
    """Run ``task_id`` and write its report into ``out_dir``; returns the report as JSON data.
    ``task_id`` may also be a configuration file (``.toml`` / ``.json``, :mod:`.config_task`).

    Args:
        quick: the task's quick settings (fewer epochs, repeats and time points).
        data: folder of the real data set (tasks ``*-real-v1``).
        classifiers: names (list or ``"a,b"``) instead of the task's default set.
        repeats: number of splits for every classifier instead of the task's numbers.
        seed: seeds the splits and every model (None, the default here as on the command
            line: a configuration file's seed, which then also seeds its slides, as
            ``generate`` does; 0 for a task).
        store: read the data from this store (``sim-tactile generate``) instead.
        sensor_config: a calibration file (``sim-tactile calibrate``) for the task's sensor.
        methods: the user's methods, name -> estimator or (encoder, estimator)
            (:mod:`.methods`), scored beside the built-in rows.
        export_nir: save the snn row's network (its last repeat) there as a NIR graph
            (:mod:`.nir_export`).
        about: method name -> ``{"version": ..., "link": ...}`` for the user's methods'
            result files.

    Each row's result file (:mod:`.result_file`) is written into ``out_dir/results`` (not
    for a configuration file: it is no registered task).
    """
    # a failed run leaves no empty --out behind; a full or read-only disk is one line
    with no_empty_folders_left(Path(out_dir)), write_faults(Path(out_dir)):
        return _run_task(
            task_id,
            out_dir,
            quick,
            data,
            classifiers,
            repeats,
            seed,
            log,
            store,
            sensor_config,
            methods,
            export_nir,
            about,
        )


def _run_task(
    task_id,
    out_dir,
    quick,
    data,
    classifiers,
    repeats,
    seed,
    log,
    store,
    sensor_config,
    methods,
    export_nir=None,
    about=None,
) -> dict:
    t_start = time.perf_counter()
    env = environment()  # now: the commit of the code that runs, whatever moves meanwhile
    log = log or stderr_log
    if is_config_path(task_id):
        spec, file_seed = config_task(task_id)
        seed = file_seed if seed is None else seed
    else:
        spec = use_task(task_id)
        seed = 0 if seed is None else seed
    if sensor_config is not None:
        spec = with_calibration(spec, load_calibration(sensor_config))
    seed = integer("seed", seed, 0, None)
    if repeats is not None:
        repeats = integer("repeats", repeats, 1, None)
    if export_nir is not None:
        export_nir = check_nir_export(export_nir, spec, task_runs(spec, classifiers))
    if spec.parts:
        methods = {m.name: m for m in as_methods(methods)} or None  # checked before any part
        return _run_suite(
            spec, out_dir, quick, data, classifiers, repeats, seed, log, store, methods, about
        )
    runs = task_runs(spec, classifiers)
    user = as_methods(methods, {r.name for r in runs})
    if not runs and not user:
        raise ConfigError(
            "nothing to run: no built-in classifier (--classifiers none) and no method"
        )
    task = load_task(
        spec, quick=quick, data=data, classifiers=classifiers, seed=seed, log=log, store=store
    )
    report = evaluate_task(
        spec,
        task.ds,
        Path(out_dir),
        quick=quick,
        runs=task.runs,
        repeats=repeats,
        seed=seed,
        log=log,
        methods=user,
        export_nir=export_nir,
    )
    report.timing["load_s"] = round(task.load_s, 3)
    if not is_config_path(task_id):
        report.result_files = write_result_files(
            spec, report, task.ds.labels, Path(out_dir), about, env
        )
    report.timing["wall_s"] = round(time.perf_counter() - t_start, 2)
    report.write(Path(out_dir))
    return report.to_json()


def evaluate_task(
    spec: TaskSpec,
    ds: TactileDataset,
    out: Path,
    *,
    quick: bool,
    runs: list[Run],
    repeats: int | None,
    seed: int,
    log: Callable[[str], None],
    figures: bool = True,
    methods: Sequence[Method] = (),
    export_nir: Path | None = None,
) -> Report:
    """Encode ``ds``, run each of ``runs`` and of the user's ``methods`` under the task's
    protocol and make the report (with its figures in ``out``; the caller writes it)."""
    t0 = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    settings = spec.settings(quick)
    ctx = spec.context(ds, quick)
    encoded = Pipeline(spec.encoder(ctx)).fit_transform(ds.data)
    encode_s = time.perf_counter() - t0
    n_rep = {r.name: repeats or settings.repeats_for(r.classifier) for r in runs}
    n_rep.update({m.name: repeats or settings.repeats for m in methods})
    pre = Precomputed(spec, ds, encoded) if spec.encode_once else None
    t1 = time.perf_counter()
    keep = nir_row(runs) if export_nir is not None else None
    results, wall, splits = _classify(
        spec, ds, ctx, runs, n_rep, pre, quick=quick, seed=seed, log=log, keep=keep
    )
    if keep is not None:
        model = results[keep.name].model
        path = export_snn(export_nir, model, spec, keep, ds.class_names, n_rep[keep.name])
        log(f"{spec.id}: the {keep.name} row's network (its last repeat) as NIR: {path}")
    user_enc = classify_methods(spec, ds, methods, n_rep, results, wall, splits, quick, seed, log)
    encode_s += user_enc
    classify_s = time.perf_counter() - t1 - user_enc
    names = list(dict.fromkeys(r.classifier for r in runs))
    report = Report(
        task=spec.id,
        title=spec.title,
        quick=quick,
        results=[_row(spec, run, results[run.name], wall[run.name], quick) for run in runs]
        + [method_row(spec, m, results[m.name], wall[m.name], quick) for m in methods],
        timing={
            "simulate_s": round(float(ds.meta.get("simulate_s", 0.0)), 3),
            "encode_s": round(encode_s, 3),
            "classify_s": round(classify_s, 3),
            "load_s": 0.0,
        },
        figures=[],
        protocol={
            "split": settings.split or spec.split,
            "repeats": n_rep,
            "time_points_s": list(settings.time_points_s),
            "time_repeats": settings.time_repeats,
            "seed": seed,
            "encoding": spec.encoding,
            "params": {n: dict(settings.params.get(n, {})) for n in names},
            "precomputed": pre.describe() if pre is not None else None,
            "splits_sha256": {k: splits_digest(v) for k, v in splits.items()},
        },
        dataset=ds.describe(),
        remarks=list(spec.remarks),
        reference=spec.reference,
        environment=environment(),  # the package version, commit and machine
    )
    flag_rows(report.results, ds.duration_s, lambda m: log(f"{spec.id}: {m}"))
    if figures:
        report.figures = write_figures(out, spec, ds, encoded, results, [*runs, *methods])
    report.timing["wall_s"] = round(time.perf_counter() - t0, 2)
    return report


def _classify(spec, ds, ctx, runs, n_rep, pre, *, quick, seed, log, keep=None):
    """Each run's repeated evaluation: ``({name: EvalResult}, {name: wall [s]}, {split:
    its (train, test) pairs})``. The splits are seeded by ``(seed, 0)``
    (:func:`task_splits`), the models by the classifier's name and the repeat."""
    settings = spec.settings(quick)
    split_cache: dict[str, list] = {}
    results: dict[str, EvalResult] = {}
    wall: dict[str, float] = {}
    for run in runs:
        name = run.name
        cs = get_classifier(run.classifier)
        split = spec.split_for(run, quick)
        cols = _channels(spec, run, ds)
        if split not in split_cache:
            split_cache[split] = task_splits(ds.labels, split, max(n_rep.values()), seed)
        rctx = _run_context(ctx, run, cols, ds)
        log(f"{spec.id}: {name} on {cs.features}, split {split}, {n_rep[name]} repeat(s)")
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
            keep_model=keep is not None and run.name == keep.name,
        )
        wall[name] = time.perf_counter() - t0
        r = results[name]
        log(f"{spec.id}: {name} accuracy {r.mean:.3f} +- {r.std:.3f} ({wall[name]:.1f} s)")
    return results, wall, split_cache


def _row(spec: TaskSpec, run: Run, r: EvalResult, wall_s: float, quick: bool) -> ResultRow:
    cell = run.paper
    extra = {k: v for k, v in r.to_json().items() if k not in ("accuracy_mean", "accuracy_std")}
    return ResultRow(
        classifier=run.classifier,
        label=run.name,
        features=get_classifier(run.classifier).features,
        accuracy_mean=round(r.mean, 4),
        accuracy_std=round(r.std, 4),
        accuracy_ci95=interval_list(r.accuracies),
        paper=cell.to_json() if cell else None,
        repeats=len(r.accuracies),
        comparison=compare(r.mean, cell, spec.notes.get(run.name), quick=quick),
        wall_s=round(wall_s, 2),
        channels=run.channels,
        split=spec.split_for(run, quick),
        extra=extra,
    )


def _run_suite(
    spec: TaskSpec, out_dir, quick, data, classifiers, repeats, seed, log, store, methods, about
):
    """A task made of parts (one per sensor): each part's report in ``out_dir/<part>``, and
    one report whose rows are the parts' rows, labelled ``<part>: <row>``."""
    t0 = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    quiet_outdated(spec.parts)  # the suite's own warning names its successor
    parts = {}
    for part in spec.parts:
        log(f"{spec.id}: part {part}")
        doc = run_task(
            part,
            out / part,
            quick=quick,
            data=data,
            classifiers=classifiers,
            repeats=repeats,
            seed=seed,
            log=log,
            store=store,
            methods=methods,
            about=about,
        )
        parts[part] = Report.from_json(doc)
    rows = [
        replace(r, label=f"{part}: {r.label}", part=part)
        for part, rep in parts.items()
        for r in rep.results
    ]
    timing = {
        k: round(sum(rep.timing.get(k, 0.0) for rep in parts.values()), 3)
        for k in ("simulate_s", "encode_s", "classify_s", "load_s")
    }
    timing["wall_s"] = round(time.perf_counter() - t0, 2)
    report = Report(
        task=spec.id,
        title=spec.title,
        quick=quick,
        results=rows,
        timing=timing,
        figures=[f for rep in parts.values() for f in rep.figures],
        protocol={part: rep.protocol for part, rep in parts.items()},
        dataset={part: rep.dataset for part, rep in parts.items()},
        remarks=list(spec.remarks),
        reference=spec.reference,
        environment=next(iter(parts.values())).environment,
        parts={part: str(out / part / "report.json") for part in parts},
        result_files=[f for rep in parts.values() for f in rep.result_files or []],
    )
    report.write(out)
    return report.to_json()
