"""Synthetic data sets at scale: every slide of a task, or of a user's configuration file,
simulated in parallel (local processes or a Ray cluster, :mod:`sim_tactile.slides.run`) and
written into a Zarr store (:mod:`sim_tactile.datasets.store`), resumably.

Determinism: slide ``k`` of plate ``i`` is simulated with the seed ``derive_seed(seed, i,
k)`` (:meth:`~sim_tactile.slides.SlideSet.jobs`), whoever simulates it and whenever it
finishes, and is written at its own index: the store's arrays depend on the configuration
only, never on the number of workers, the backend or the order of completion.

Only the parent process writes: workers (processes or Ray tasks) simulate and send back the
samples, so a cluster needs no shared file system. A slide is written data first, checksum
last; ``--resume`` checks every written slide against its checksum, writes again the ones
that fail and simulates the rest. What a store cannot hold is refused before anything is
made (:func:`~sim_tactile.datasets.store.check_fits`), and the store is written through its
open folder (:class:`~sim_tactile.datasets.fs.FolderHold`): moved or removed mid-run, the
run stops in one line and the old path is not made again. The configuration file's format:
:mod:`sim_tactile.slides.config`.
"""

from __future__ import annotations

import json
import signal
import sys
import time
from collections import Counter
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from . import _validate as v
from .cache import default_root
from .datasets.chunks import remove_partial_chunks
from .datasets.export import spec_from_tactile
from .datasets.fs import FolderHold, fs_errors, no_empty_folders_left
from .datasets.integrity import (
    chunk_files,
    compare_index,
    damaged_index,
    reading,
    values_digest,
)
from .datasets.lock import StoreLock
from .datasets.store import (
    DataGroup,
    SlideWriter,
    check_fits,
    config_hash,
    create_store,
    open_data,
    open_root,
    read_checksums,
    set_attrs,
    versions,
)
from .errors import ConfigError, StoreError, Terminated, WorkerError
from .hashing import canonical_json
from .interrupts import interrupt_of
from .sensors.calibration import load_calibration
from .sim.plan.options import DEVICES
from .slides.config import config_slide_set, is_config_path, load_config
from .slides.jobs import SlideWorker
from .slides.plan import Plan, slide_plan
from .slides.run import (
    BACKENDS,
    MAX_WORKERS,
    default_workers,
    make_backend,
    stream,
    warning_lines,
)
from .slides.slide_set import SlideSet


# --------------------------------------------------------------------------- plans
def _task_plans(
    task_id: str, quick: bool, seed: int, data, log, cal=None
) -> tuple[list[Plan], dict]:
    from .tasks import DataRequest
    from .tasks.registry import quiet_outdated, use_task, with_calibration

    spec = use_task(task_id)
    if cal is not None:
        spec = with_calibration(spec, cal)
    if spec.parts:
        quiet_outdated(spec.parts)  # the suite's own warning names its successor
        plans = []
        for part in spec.parts:
            (p,), _ = _task_plans(part, quick, seed, data, log)
            p.group = part
            plans.append(p)
        return plans, {"suite": spec.id, "parts": list(spec.parts)}
    if isinstance(spec.get_data, SlideSet):
        return [slide_plan(spec.get_data, quick=quick, seed=seed, task=spec.id, name=spec.id)], {}
    if spec.needs_data_path and data is None:
        raise ConfigError(
            f"task {spec.id} reads recorded data: pass --data PATH (e.g. "
            "../shared/datasets/biotac_slide_20_50)"
        )
    ds = spec.get_data(DataRequest(None if data is None else Path(data), quick, seed, log))
    meta = {k: val for k, val in ds.meta.items() if k != "path"}
    cfg = {"kind": "recorded", "task": spec.id, "quick": bool(quick), "meta": meta}
    return [Plan("", spec_from_tactile(ds, spec.id, cfg), dataset=ds)], {}


def resolve(target: str, *, quick: bool, seed: int | None, data=None, log=None, sensor_config=None):
    """The plans of ``target``: a task id or a configuration file; returns ``(plans,
    root_attrs)``. Everything is validated here, before any slide runs. ``sensor_config``:
    a calibration file (``sim-tactile calibrate``) for the task's sensor."""
    log = log or (lambda m: None)
    cal = None if sensor_config is None else load_calibration(sensor_config)
    path = Path(target)
    # a configuration file by its suffix (the rule a user predicts from the command line, and
    # tasks.config_task's); the task registry, which loads the learners, only for a task id
    if not is_config_path(target):
        from .tasks import task_ids

        if target in task_ids(aliases=True):
            seed = 0 if seed is None else v.integer("--seed", seed, 0)
            return _task_plans(target, quick, seed, data, log, cal)
    if is_config_path(target):
        cfg = load_config(path)
        ss, file_seed, name = config_slide_set(cfg, f"configuration file {path}", path.parent)
        if cal is not None:
            if ss.sensor != cal.sensor:
                raise ConfigError(
                    f"the sensor config calibrates {cal.sensor!r}; {path} simulates {ss.sensor!r}"
                )
            ss = replace(ss, calibration=cal)
        if seed is not None:
            file_seed = v.integer("--seed", seed, 0)
        plan = slide_plan(
            ss, quick=quick, seed=file_seed, task=None, name=name or path.stem, source=cfg
        )
        return [plan], {}
    from .tasks import task_ids

    raise ConfigError(
        f"TASK {target!r} is neither a task id (valid: {', '.join(task_ids())}) nor a "
        "configuration file (.toml or .json)"
    )


# --------------------------------------------------------------------------- the store
def _describe_existing(out: Path) -> str:
    try:
        root = open_root(out)
        parts = root.attrs.get("parts") or []
        groups = [open_data(root[p], out / p, f"{out}/{p}") for p in parts] or [
            open_data(root, out, str(out))
        ]  # checked first: what its attributes claim is what it holds
        n = sum(int(g.attrs["n_slides"]) for g in groups)
        done = sum(
            int((read_checksums(g.arrays["checksum"], str(out))[0] != 0).sum()) for g in groups
        )
    except StoreError as exc:
        return str(exc)
    except Exception:  # a damaged store: saying so is enough here
        return "a store that cannot be read"
    return f"a data set of {n} slides, {done} written, configuration {root.attrs.get('config_hash', '?')}"


def _diff(a: dict, b: dict, prefix: str = "") -> list[str]:
    """The keys whose values differ, as JSON data: a list and a tuple of the same values are
    the same (the store holds JSON; its hash is of the canonical JSON too)."""
    if not prefix:
        a, b = json.loads(canonical_json(a)), json.loads(canonical_json(b))
    out = []
    for k in sorted(set(a) | set(b)):
        x, y = a.get(k), b.get(k)
        if isinstance(x, dict) and isinstance(y, dict):
            out += _diff(x, y, f"{prefix}{k}.")
        elif x != y:
            out.append(f"{prefix}{k}: {x!r} in the store, {y!r} now")
    return out


def _check_same(attrs: dict, plan: Plan, where: str) -> None:
    if attrs.get("config_hash") != plan.spec.hash:
        diffs = _diff(attrs.get("config") or {}, plan.spec.config)
        raise StoreError(
            f"{where} was made from another configuration (hash {attrs.get('config_hash')}, "
            f"this one is {plan.spec.hash}): {'; '.join(diffs[:4]) or 'see its config'}. "
            "--resume only continues the same configuration: choose a new --out"
        )
    if attrs.get("code_version") != plan.spec.code_version:
        raise StoreError(
            f"{where} was made by another version of the simulating code "
            f"({attrs.get('code_version')}, now {plan.spec.code_version}): slides simulated "
            "now would not match the ones written; generate into a new --out"
        )


def _check_index(dg: DataGroup, plan: Plan, where: str) -> None:
    """The index arrays against the ones the configuration gives: the intact ones by value,
    the damaged ones by the digest the store recorded (they can be written again only if
    the configuration gives those values)."""
    expected = plan.spec.index()
    recorded = dg.attrs["integrity"]["values"]
    for name, why in dg.damage.items():
        if values_digest(expected[name]) != recorded[name]:
            raise damaged_index(where, {name: f"{why}, and the configuration gives other values"})
    intact = [k for k in expected if k not in dg.damage]
    compare_index({k: dg.index[k] for k in intact}, {k: expected[k] for k in intact}, where)


def _repair_index(dg: DataGroup, plan: Plan, where: str, out: Path, log) -> list[str]:
    """Write again the damaged index arrays (checked by :func:`_check_index`) from the
    configuration, and record their chunk files' new digests. Returns their names."""
    if not dg.damage:
        return []
    expected = plan.spec.index()
    files = dict(dg.attrs["integrity"]["files"])
    folder = out / plan.group if plan.group else out
    for name, why in dg.damage.items():
        with fs_errors(out):
            dg.arrays[name][...] = expected[name]
        dg.index[name] = expected[name]
        files = {k: d for k, d in files.items() if not k.startswith(f"{name}/c/")}
        files.update(chunk_files(folder, name))  # the bytes as written now
        log(
            f"{where}: the array {name!r} was damaged ({why}); written again from the configuration"
        )
    dg.attrs["integrity"] = {**dg.attrs["integrity"], "files": files}
    set_attrs(dg.group, {"integrity": dg.attrs["integrity"]}, out)
    return [f"{plan.group}/{k}" if plan.group else k for k in dg.damage]


def _open_or_create(out: Path, plans: list[Plan], root_attrs: dict, resume: bool, log):
    """The store's root group and each plan's checked group: the existing ones, checked to
    hold the same configuration and code, with the index arrays the configuration gives
    (``--resume``; damaged ones are written again), or new ones. Nothing is written before
    every check has passed. The caller holds the store's lock."""
    import zarr

    if out.exists() and not resume:
        raise StoreError(
            f"{out} already exists ({_describe_existing(out)}); nothing was changed. Pass "
            "--resume to continue it, or choose a new --out"
        )
    if out.exists() and not (out / "zarr.json").is_file():
        raise StoreError(f"{out} exists and is not a data set; choose a new --out")
    if out.exists():
        root = open_root(out, "r+")
        remove_partial_chunks(out)  # a killed writer's half-written chunk files
        if (root.attrs.get("parts") or []) != (root_attrs.get("parts") or []):
            raise StoreError(
                f"{out} holds {root.attrs.get('parts') or 'one data set'}, this target "
                f"{root_attrs.get('parts') or 'one data set'}: choose a new --out"
            )
    else:
        root_attrs = {**root_attrs, "versions": versions(), "runs": []}
        if root_attrs.get("parts"):  # a suite: the hash of its parts' hashes
            root_attrs["config_hash"] = config_hash({p.group: p.spec.hash for p in plans})
        create_store(out, {p.group: p.spec for p in plans}, root_attrs)
        with reading(str(out), "the store just made"):
            root = zarr.open_group(str(out), mode="r+")
    groups, wheres = [], []
    for plan in plans:  # every check first...
        where = f"{out}" + (f"/{plan.group}" if plan.group else "")
        with reading(where, "its zarr.json"):
            group = root[plan.group] if plan.group else root
        dg = open_data(group, out / plan.group if plan.group else out, where)
        _check_same(dg.attrs, plan, where)
        _check_index(dg, plan, where)
        groups.append(dg)
        wheres.append(where)
    repaired = []  # ...then the repairs
    for plan, dg, where in zip(plans, groups, wheres, strict=True):
        repaired += _repair_index(dg, plan, where, out, log)
    return root, groups, repaired


def _through(hold: FolderHold, plans: list[Plan], groups: list[DataGroup]):
    """The store's root group opened again through ``hold`` (:class:`FolderHold`), and each
    checked data group's ``group`` with it: every write from now on goes into the folder that
    was opened and checked, wherever it is moved. Returns the root group."""
    import zarr

    with reading(str(hold.path), "its zarr.json"):
        root = zarr.open_group(hold.root, mode="r+")
        for plan, dg in zip(plans, groups, strict=True):
            dg.group = root[plan.group] if plan.group else root
    return root


@dataclass
class _Run:
    """The bookkeeping of one ``generate`` call."""

    plans: list[Plan]
    writers: list[SlideWriter] = field(default_factory=list)
    todo: list[tuple[int, int]] = field(default_factory=list)
    warns: list[Counter] = field(default_factory=list)
    written: int = 0
    #: of the written: read from the slide cache, and copied from recorded data
    cached: int = 0
    copied: int = 0
    reused: int = 0
    corrupt: list[dict] = field(default_factory=list)
    sim_s: float = 0.0
    write_s: float = 0.0
    interrupted: bool = False
    #: the signal that stopped the run (SIGTERM), None for Ctrl-C or none
    signal: str | None = None
    repaired: list[str] = field(default_factory=list)
    #: the store's folder, held open while it is written
    hold: FolderHold | None = None


_KEPT = "every slide written so far is kept: run the same command with --resume to continue"


def _recheck_written(groups: list[DataGroup], run: _Run, resumed: bool, out: Path, log) -> None:
    """Open a writer per data set; on resume, read every written slide back against its
    checksum and mark the ones that fail (or whose checksum chunk is unreadable) to be
    written again. Fills ``run.todo``."""
    for k, (plan, dg) in enumerate(zip(run.plans, groups, strict=True)):
        guard = None if run.hold is None else run.hold.check
        w = SlideWriter(dg.group, out, dg.index["lengths"], _KEPT, guard=guard)
        run.writers.append(w)
        run.warns.append(Counter())
        n = plan.spec.n_slides
        done, unreadable = w.done() if resumed else (np.zeros(n, bool), {})
        bad = dict(unreadable)
        for i in np.flatnonzero(done):
            why = w.check(int(i))
            if why:
                bad[int(i)] = why
        for i, why in sorted(bad.items()):
            log(f"{plan.group + ': ' if plan.group else ''}slide {i}: {why}; writing it again")
            run.corrupt.append({"part": plan.group, "slide": i, "reason": why})
            w.clear(i)
            done[i] = False
        run.reused += int(done.sum())
        run.todo += [(k, int(i)) for i in np.flatnonzero(~done)]


def _drain(backend, run: _Run, bar) -> None:
    """Copy the recorded slides and simulate the others still to do, writing each slide as
    it arrives."""
    jobs = []
    for k, i in run.todo:
        plan = run.plans[k]
        if plan.jobs is None:
            _write(run, k, i, np.asarray(plan.dataset.data[i], np.float32), (), 0.0)
            run.copied += 1
            bar.update(1)
        else:
            jobs.append(((k, i), plan.jobs[i]))
    try:
        for (k, i), out in stream(backend, jobs, name=lambda key: _slide_name(run, key)):
            _write(run, k, i, out.data, out.warnings, out.wall_s)
            run.cached += bool(getattr(out, "cached", False))
            bar.update(1)
    except WorkerError as exc:
        raise StoreError(f"{exc}; {_KEPT}") from None


def _slide_name(run: _Run, key: tuple[int, int]) -> str:
    return f"{run.plans[key[0]].spec.name} slide {key[1]}"


def _write(run: _Run, k: int, i: int, x: np.ndarray, warnings, wall_s: float) -> None:
    t0 = time.perf_counter()
    run.writers[k].write(i, x)
    run.write_s += time.perf_counter() - t0
    run.sim_s += wall_s
    run.warns[k].update(warnings)
    run.written += 1


def _check_device(device: str) -> None:
    """Refuse a device that is not here (asked for and absent: one line, nothing made)."""
    v.one_of("--device", device, DEVICES)
    if device != "cpu":
        from .sim.skin.contact.device import require_device

        require_device(device)


def _on_device(plans, device: str) -> None:
    """Set the slides of ``plans`` to solve their phase tables on ``device`` (where they are
    solved, not what a slide is: the store's configuration is the same)."""
    if device == "cpu":
        return
    for plan in plans:
        if plan.jobs is not None:
            plan.jobs = [replace(j, options=replace(j.options, device=device)) for j in plan.jobs]


def generate(
    target: str,
    out: str | Path,
    *,
    workers: int | None = None,
    backend: str = "local",
    address: str | None = None,
    quick: bool = False,
    resume: bool = False,
    seed: int | None = None,
    data: str | Path | None = None,
    progress: bool = True,
    log: Callable[[str], None] | None = None,
    sensor_config: str | Path | None = None,
    device: str = "cpu",
    _worker: Callable | None = None,
) -> dict:
    """Simulate every slide of ``target`` (a task id or a configuration file) into the Zarr
    store ``out``; returns ``{out, trials, resumed, wall_s, ...}``.

    workers: local processes (default: every core; ``SIM_TACTILE_WORKERS``) or, with Ray, the
        CPUs of a local instance / the slides in flight on a cluster (default: its CPUs).
    backend: ``local`` or ``ray`` (``address``: a running cluster, e.g. ``HOST:6379`` or
        ``auto``; None starts a local instance).
    resume: continue an interrupted store of the same configuration (without it an existing
        ``out`` is refused).
    sensor_config: a calibration file (``sim-tactile calibrate``) for the task's sensor.
    device: where the phase tables of slides on a spectral skin are solved (``cpu``, or
        ``cuda``: checked before anything is made; the slides' keys record it).
    _worker: what simulates a job (tests put faults in with it; default: a
        :class:`~sim_tactile.slides.jobs.SlideWorker` that reads the slide cache, never
        writes it).
    """
    t_start = time.perf_counter()
    log = log or (lambda m: print(m, file=sys.stderr, flush=True))
    v.one_of("--backend", backend, BACKENDS)
    if address and backend != "ray":
        raise ConfigError("--address is for --backend ray")
    if workers is not None:
        workers = v.integer("--workers", workers, 1, MAX_WORKERS)
    out = Path(out)
    _check_device(device)
    plans, root_attrs = resolve(
        target, quick=quick, seed=seed, data=data, log=log, sensor_config=sensor_config
    )
    _on_device(plans, device)
    for plan in plans:  # what a store cannot hold is refused before anything is made
        check_fits(plan.spec, f"{target}" + (f" ({plan.group})" if plan.group else ""))
    total = sum(p.spec.n_slides for p in plans)
    StoreLock.probe(out)  # refused before the workers start (the lock below is what counts)
    simulated = any(p.jobs is not None for p in plans)
    fn = _worker or SlideWorker(str(default_root()), write=False)
    # the workers start before this process opens the store, its lock and its I/O threads:
    # fork copies the parent as it is
    runner = (  # recorded data needs no workers: it is copied in this process
        make_backend(fn, kind=backend, workers=workers, address=address, log=log)
        if simulated
        else make_backend(fn, workers=1)
    )
    try:
        with no_empty_folders_left(out), StoreLock(out), ExitStack() as held:
            resumed = out.exists()
            root, groups, repaired = _open_or_create(out, plans, root_attrs, resume, log)
            hold = held.enter_context(FolderHold(out))  # written through its folder from now on
            root = _through(hold, plans, groups)
            run = _Run(plans, repaired=repaired, hold=hold)
            try:
                _fill(runner, run, groups, resumed, out, total, simulated, progress, log)
                hold.check()  # the last slide too went into the store at --out
            except BaseException as exc:
                # an interrupt may surface through a compiled kernel as a SystemError
                stop = interrupt_of(exc)
                if stop is not None:
                    run.interrupted = True
                    if isinstance(stop, Terminated):
                        run.signal = signal.Signals(stop.signum).name
                    log(
                        f"{'stopped by ' + run.signal if run.signal else 'interrupted'}: "
                        f"{run.reused + run.written} of {total} slides are in {out}; run the "
                        "same command with --resume to continue"
                    )
                runner.close(cancel=True)
                if hold.follows or not hold.moved():  # never a file at a vacated path
                    _record_run(root, run, backend, runner.workers, address, t_start, out, log)
                if stop is not None and stop is not exc:
                    raise stop from None
                raise
            runner.close(cancel=True)
            _record_run(root, run, backend, runner.workers, address, t_start, out)
    finally:
        runner.close(cancel=True)
    for plan, warns in zip(plans, run.warns, strict=False):
        for line in warning_lines(warns, plan.spec.n_slides):
            log(f"{plan.group + ': ' if plan.group else ''}{line}")
    return _summary(
        out, total, resumed, backend, workers, runner.workers, plans, root, run, t_start
    )


def _fill(runner, run: _Run, groups, resumed, out: Path, total, simulated, progress, log) -> None:
    """Check what is written (on resume), then simulate and write the rest."""
    _recheck_written(groups, run, resumed, out, log)
    if resumed:
        log(
            f"resuming {out}: {run.reused} of {total} slides written and checked, "
            f"{len(run.todo)} to go ({len(run.corrupt)} corrupt)"
        )
    if run.todo and simulated:
        log(f"{out}: {len(run.todo)} slides on {runner.name}, {runner.workers} worker(s)")
    bar = _progress(total, run.reused, out.name, progress)
    try:
        _drain(runner, run, bar)
    finally:
        bar.close()


def _summary(out, total, resumed, backend, workers, n_workers, plans, root, run, t_start) -> dict:
    """What :func:`generate` returns."""
    wall = time.perf_counter() - t_start
    return {
        "out": str(out),
        "trials": total,
        "resumed": bool(resumed),
        "wall_s": round(wall, 3),
        "written": run.written,
        "simulated": run.written - run.cached - run.copied,
        "cached": run.cached,
        "copied": run.copied,
        "reused": run.reused,
        "regenerated": len(run.corrupt),
        "corrupt": run.corrupt,
        "repaired": run.repaired,
        "backend": backend,
        "workers": n_workers if backend == "local" else workers,
        "parts": [p.group for p in plans if p.group],
        "config_hash": root.attrs.get("config_hash"),
        "simulate_s": round(run.sim_s, 3),
        "write_s": round(run.write_s, 4),
        "store_overhead": round(run.write_s / run.sim_s, 5) if run.sim_s > 0 else None,
        "warnings": {
            (p.group or p.spec.name): [f"{w} (x{c})" for w, c in warns.most_common()]
            for p, warns in zip(plans, run.warns, strict=False)
            if warns
        },
    }


def _record_run(root, run: _Run, backend, workers, address, t_start, out: Path, log=None) -> None:
    """Completion flags, warnings and the run's line in the store's history (parent only,
    under the store's lock). With ``log`` (the run is failing already), a failure to write
    them is logged, not raised: the first fault is the one to report."""
    try:
        for w, c in zip(run.writers, run.warns, strict=False):
            group = w.group
            old = Counter(group.attrs.get("sim_warnings") or {})
            old.update(c)
            set_attrs(
                group,
                {"sim_warnings": dict(old.most_common()), "complete": bool(w.done()[0].all())},
                out,
            )
        entry = {
            "at": datetime.now(UTC).isoformat(timespec="seconds"),
            "backend": backend,
            "workers": workers,
            "address": address,
            "written": run.written,
            "regenerated": len(run.corrupt),
            "repaired": run.repaired,
            "interrupted": run.interrupted,
            "signal": run.signal,
            "wall_s": round(time.perf_counter() - t_start, 3),
        }
        if backend == "ray":
            entry["ray"] = sys.modules["ray"].__version__ if "ray" in sys.modules else None
        set_attrs(root, {"runs": [*(root.attrs.get("runs") or []), entry]}, out)
    except Exception as exc:
        if log is None:
            raise
        log(f"the store's history was not updated: {exc}")


def _progress(total: int, initial: int, desc: str, enabled: bool):
    from tqdm import tqdm

    return tqdm(
        total=total,
        initial=initial,
        desc=desc,
        unit="slide",
        file=sys.stderr,
        disable=not enabled,
        dynamic_ncols=True,
        smoothing=0.05,
    )


__all__ = ["BACKENDS", "default_workers", "generate", "resolve"]
