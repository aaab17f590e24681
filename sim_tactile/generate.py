"""Synthetic data sets at scale: every slide of a task, or of a user's configuration file,
simulated in parallel (local processes or a Ray cluster) and written into a Zarr store
(:mod:`sim_tactile.datasets.store`), resumably.

Determinism: slide ``k`` of plate ``i`` is simulated with the seed ``SeedSequence([seed, i,
k])`` (:meth:`~sim_tactile.tasks.synthetic.SlideSet.jobs`), whoever simulates it and
whenever it finishes, and is written at its own index: the store's arrays depend on the
configuration only, never on the number of workers, the backend or the order of completion.

Only the parent process writes: workers (processes or Ray tasks) simulate and send back the
samples, so a cluster needs no shared file system. A slide is written data first, checksum
last; ``--resume`` checks every written slide against its checksum, writes again the ones
that fail and simulates the rest.

Configuration files (TOML or JSON, read as data)::

    name = "my-set"              # optional, a label
    seed = 0                     # integer >= 0
    plates = ["finger7/flat", "finger7/ridges-2"]   # >= 2 preset plates (the classes)
    sensor = "grid3x3"           # a sensor (its layout, transducer and pad)
    slides_per_plate = 100       # [2, 100000]
    quick_slides_per_plate = 2   # optional: the slides per plate under --quick
    fidelity = "auto"            # auto, L0, L1, L2
    ideal = false                # record the noise-free normal loads [N]

    [protocol]                   # sim.simulate.Protocol: speed_m_s, force_n, duration_s,
    speed_m_s = 0.06             # rate_hz, press_s, settle_s, passes, return_stroke,
    force_n = 1.0                # offset_y_m (duration_s absent: cross the texture)

    [randomise]                  # per-slide variation (one SD)
    speed_jitter = 0.05          # relative, [0, 0.5]
    force_jitter = 0.1           # relative, [0, 0.5]
    offset_jitter_m = 0.5e-3     # [0, 0.01] m

    [finger]                     # optional: change fields of the sensor's pad (scene.Finger)
    young_pa = 0.3e6
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
import tomllib
from collections import Counter
from collections.abc import Callable
from dataclasses import asdict, fields, replace
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from . import _validate as v
from .datasets.store import (
    PARAM_NAMES,
    SlideWriter,
    StoreError,
    StoreSpec,
    _open_root,
    config_hash,
    create_store,
    spec_from_tactile,
    versions,
)
from .errors import ConfigError, SimTactileError

BACKENDS = ("local", "ray")
_TOP_KEYS = {
    "name": "a label",
    "seed": "integer >= 0",
    "plates": "list of >= 2 preset plate names",
    "sensor": "sensor name",
    "slides_per_plate": "integer in [2, 100000]",
    "quick_slides_per_plate": "integer in [2, slides_per_plate]",
    "fidelity": "auto, L0, L1, L2",
    "ideal": "true or false",
    "protocol": "table",
    "randomise": "table",
    "finger": "table",
}
_RANDOMISE = ("speed_jitter", "force_jitter", "offset_jitter_m")


# --------------------------------------------------------------------------- plans
class Plan:
    """One data set to write: its store layout and, for simulated data, a job per slide
    (``jobs``) or, for recorded data, the recordings (``dataset``)."""

    def __init__(self, group: str, spec: StoreSpec, jobs=None, dataset=None) -> None:
        self.group = group
        self.spec = spec
        self.jobs = jobs
        self.dataset = dataset


def _slide_plan(slides, *, quick, seed, task, name, finger=None, source=None) -> Plan:
    from .sensors import get_sensor
    from .sim.protocol import Protocol
    from .tasks.synthetic import _class_name, _code_version

    n = slides.quick_slides if quick else slides.slides
    plates = slides.plates_for(quick)
    jobs = slides.jobs(n, seed, quick)
    if finger is not None:
        for j in jobs:
            j["finger"] = finger
    proto = slides.window_protocol()
    n_time = max(1, round(proto.duration_s * proto.rate_hz))  # as sim.simulate counts them
    params = np.empty((len(jobs), len(PARAM_NAMES)))
    for r, j in enumerate(jobs):  # the draw simulate() makes from the slide's seed
        p = Protocol(**j["protocol"]).varied(np.random.default_rng(j["seed"]))
        params[r] = (p.speed_m_s, p.force_n, p.offset_y_m)
    sensor = get_sensor(slides.sensor)
    layout = sensor.layout
    setup = {**slides.describe(), "plates": list(plates)}
    config = {
        "kind": "simulated",
        "task": task,
        "quick": bool(quick),
        "seed": int(seed),
        "slides_per_plate": int(n),
        **setup,
        "finger": finger,
    }
    meta = {
        "source": f"simulated: {len(plates)} plates x {n} slides, {slides.sensor}",
        "sensor": slides.sensor,
        "slides_per_class": n,
        "window_s": n_time / proto.rate_hz,
        "setup": setup,
    }
    if layout.grid_shape is not None:
        meta["grid_shape"] = list(layout.grid_shape)
    spec = StoreSpec(
        name=name,
        config=config,
        labels=np.repeat(np.arange(len(plates)), n),
        slide=np.tile(np.arange(n), len(plates)),
        seeds=np.array([j["seed"] for j in jobs], dtype=np.uint64),
        params=params,
        lengths=np.full(len(jobs), n_time, np.int64),
        channel_names=tuple(layout.names),
        class_names=tuple(_class_name(p) for p in plates),
        rate_hz=proto.rate_hz,
        units="N" if slides.ideal else sensor.units,
        taxel_positions=np.asarray(layout.positions),
        dataset_meta=meta,
        code_version=_code_version(),
    )
    if source is not None:
        spec.dataset_meta["config_file"] = source
    return Plan("", spec, jobs=jobs)


def task_slide_config(task_id: str, quick: bool, seed: int) -> tuple[str, str]:
    """``(config hash, code version)`` that ``generate task_id`` writes (for ``--store``)."""
    from .tasks import get_task

    p = _slide_plan(get_task(task_id).get_data, quick=quick, seed=seed, task=task_id, name=task_id)
    return p.spec.hash, p.spec.code_version


def _task_plans(task_id: str, quick: bool, seed: int, data, log) -> tuple[list[Plan], dict]:
    from .tasks import DataRequest, get_task
    from .tasks.synthetic import SlideSet

    spec = get_task(task_id)
    if spec.parts:
        plans = []
        for part in spec.parts:
            (p,), _ = _task_plans(part, quick, seed, data, log)
            p.group = part
            plans.append(p)
        return plans, {"suite": task_id, "parts": list(spec.parts)}
    if isinstance(spec.get_data, SlideSet):
        return [_slide_plan(spec.get_data, quick=quick, seed=seed, task=task_id, name=task_id)], {}
    if spec.needs_data_path and data is None:
        raise ConfigError(
            f"task {task_id} reads recorded data: pass --data PATH (e.g. "
            "../shared/datasets/biotac_slide_20_50)"
        )
    ds = spec.get_data(DataRequest(None if data is None else Path(data), quick, seed, log))
    meta = {k: v for k, v in ds.meta.items() if k != "path"}
    cfg = {"kind": "recorded", "task": task_id, "quick": bool(quick), "meta": meta}
    return [Plan("", spec_from_tactile(ds, task_id, cfg), dataset=ds)], {}


def load_config(path: str | Path) -> dict:
    """Read a configuration file (TOML or JSON) as data; no code is run."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"configuration file {str(path)!r} does not exist")
    text = path.read_bytes()
    try:
        if path.suffix.lower() == ".json":
            cfg = json.loads(text)
        else:
            cfg = tomllib.loads(text.decode())
    except (ValueError, UnicodeDecodeError) as exc:
        raise ConfigError(f"configuration file {path}: cannot be parsed: {exc}") from None
    if not isinstance(cfg, dict):
        raise ConfigError(f"configuration file {path}: the top level must be a table / object")
    return cfg


def _table(cfg: dict, key: str, where: str) -> dict:
    t = cfg.get(key, {})
    if not isinstance(t, dict):
        raise ConfigError(f"{where}: {key} must be a table, got {t!r}")
    return t


def config_slide_set(cfg: dict, where: str = "configuration"):
    """Validate a configuration (from :func:`load_config`) and build its
    :class:`~sim_tactile.tasks.synthetic.SlideSet`; returns ``(slide_set, seed, finger dict
    or None, name)``. Every error names the parameter and its valid values."""
    from .plates import preset_names
    from .sensors import get_sensor, sensor_names
    from .sim.fidelity import LEVELS
    from .sim.protocol import Protocol
    from .tasks.synthetic import SlideSet, crossing_s

    def err(msg: str) -> ConfigError:
        return ConfigError(f"{where}: {msg}")

    unknown = sorted(set(cfg) - set(_TOP_KEYS))
    if unknown:
        raise err(
            f"unknown key(s) {', '.join(unknown)}; valid: "
            + ", ".join(f"{k} ({d})" for k, d in _TOP_KEYS.items())
        )
    for key in ("plates", "sensor", "slides_per_plate"):
        if key not in cfg:
            raise err(f"{key} is missing ({_TOP_KEYS[key]})")
    plates = cfg["plates"]
    if not isinstance(plates, list) or not all(isinstance(p, str) for p in plates):
        raise err(f"plates must be a list of preset plate names, got {plates!r}")
    if len(plates) < 2 or len(set(plates)) != len(plates):
        raise err(f"plates must name at least 2 distinct plates, got {plates}")
    bad = [p for p in plates if p not in preset_names()]
    if bad:
        raise err(f"plate {bad[0]!r} is not a preset; valid: {', '.join(preset_names())}")
    sensor = cfg["sensor"]
    if sensor not in sensor_names():
        raise err(f"sensor = {sensor!r} is not valid; valid: {', '.join(sensor_names())}")
    name = cfg.get("name", "")
    if not isinstance(name, str):
        raise err(f"name must be a string, got {name!r}")
    try:
        seed = v.integer("seed", cfg.get("seed", 0), 0, 2**32 - 1)
        slides = v.integer("slides_per_plate", cfg["slides_per_plate"], 2, 100_000)
        quick = v.integer("quick_slides_per_plate", cfg.get("quick_slides_per_plate", 2), 2, slides)
        fidelity = v.one_of("fidelity", cfg.get("fidelity", "auto"), ["auto", *LEVELS])
    except ConfigError as exc:
        raise err(str(exc)) from None
    ideal = cfg.get("ideal", False)
    if not isinstance(ideal, bool):
        raise err(f"ideal must be true or false, got {ideal!r}")

    proto_t, rand_t = _table(cfg, "protocol", where), _table(cfg, "randomise", where)
    pnames = [f.name for f in fields(Protocol) if f.name not in _RANDOMISE]
    bad = sorted(set(proto_t) - set(pnames))
    if bad:
        hint = " (put the jitters under [randomise])" if set(bad) & set(_RANDOMISE) else ""
        raise err(f"unknown protocol key(s) {', '.join(bad)}{hint}; valid: {', '.join(pnames)}")
    bad = sorted(set(rand_t) - set(_RANDOMISE))
    if bad:
        raise err(f"unknown randomise key(s) {', '.join(bad)}; valid: {', '.join(_RANDOMISE)}")
    for sect, t in (("protocol", proto_t), ("randomise", rand_t)):
        for k, val in t.items():
            ok = isinstance(val, bool) if k == "return_stroke" else _is_number(val)
            if not ok:
                raise err(
                    f"{sect}.{k} must be a {'boolean' if k == 'return_stroke' else 'number'}, got {val!r}"
                )
    kw = {"rate_hz": get_sensor(sensor).layout.rate_hz, **proto_t, **rand_t}
    try:
        proto = Protocol(**kw)
    except ConfigError as exc:
        sect = "randomise" if str(exc).split(" ")[0] in _RANDOMISE else "protocol"
        raise err(f"{sect}.{exc}") from None
    if proto.speed_m_s == 0 and proto.duration_s is None:
        raise err("protocol.speed_m_s = 0 needs a protocol.duration_s")

    finger_t = _table(cfg, "finger", where)
    finger = None
    if finger_t:
        base = get_sensor(sensor).finger
        names = [f.name for f in fields(base)]
        bad = sorted(set(finger_t) - set(names))
        if bad:
            raise err(f"unknown finger key(s) {', '.join(bad)}; valid: {', '.join(names)}")
        kw = {k: tuple(x) if isinstance(x, list) else x for k, x in finger_t.items()}
        try:
            f = replace(base, **kw)
        except ConfigError as exc:
            raise err(str(exc)) from None
        except TypeError as exc:
            raise err(f"finger: {exc}") from None
        ex, ey = get_sensor(sensor).layout.extent_m
        px, py = f.patch_m
        if ex > px / 2 + 1e-9 or ey > py / 2 + 1e-9:
            raise err(
                f"the finger's pad (+-{px / 2:g} x +-{py / 2:g} m) is smaller than the "
                f"{sensor} layout (+-{ex:g} x +-{ey:g} m); valid: a pad that carries the taxels"
            )
        finger = json.loads(json.dumps(asdict(f)))
        if proto.duration_s is None:  # cross the texture with this pad, not the sensor's
            pad_x = f.patch_m[0]
            t = max(
                crossing_s(p, sensor, proto.speed_m_s)
                - get_sensor(sensor).finger.patch_m[0] / proto.speed_m_s
                + pad_x / proto.speed_m_s
                for p in plates
            )
            proto = replace(proto, duration_s=math.ceil(t * proto.rate_hz) / proto.rate_hz)
    try:
        ss = SlideSet(
            plates=tuple(plates),
            sensor=sensor,
            protocol=proto,
            slides=slides,
            quick_slides=quick,
            fidelity=fidelity,
            ideal=ideal,
        )
    except ConfigError as exc:
        raise err(str(exc)) from None
    return ss, seed, finger, name


def _is_number(x) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def resolve(target: str, *, quick: bool, seed: int | None, data=None, log=None):
    """The plans of ``target``: a task id or a configuration file; returns ``(plans,
    root_attrs)``. Everything is validated here, before any slide runs."""
    from .tasks import task_ids

    log = log or (lambda m: None)
    if target in task_ids():
        return _task_plans(
            target, quick, 0 if seed is None else v.integer("--seed", seed, 0), data, log
        )
    path = Path(target)
    if path.suffix.lower() in (".toml", ".json") or path.is_file():
        cfg = load_config(path)
        ss, file_seed, finger, name = config_slide_set(cfg, f"configuration file {path}")
        if seed is not None:
            file_seed = v.integer("--seed", seed, 0)
        plan = _slide_plan(
            ss,
            quick=quick,
            seed=file_seed,
            task=None,
            name=name or path.stem,
            finger=finger,
            source=cfg,
        )
        return [plan], {}
    raise ConfigError(
        f"TASK {target!r} is neither a task id (valid: {', '.join(task_ids())}) nor a "
        "configuration file (.toml or .json)"
    )


# --------------------------------------------------------------------------- workers
def simulate_slide(job: dict) -> tuple[np.ndarray, list[str], float, tuple[float, ...]]:
    """Simulate one slide (in a worker): ``(samples float32 (T, N), warnings, wall [s], the
    drawn (speed, force, offset))``. A slide already in the local slide cache (a task's
    ``run``) is read instead."""
    from .cache import ArtefactCache
    from .records import Recording
    from .tasks.synthetic import simulate_job

    t0 = time.perf_counter()
    cache = ArtefactCache.default()
    hit = cache.get(ArtefactCache.key(job), "slide.npz")
    if hit is not None:
        rec, warns = Recording.load(hit), []
    else:
        res = simulate_job(job, cache)
        rec, warns = res.recording, list(res.warnings)
    p = rec.meta["protocol"]
    drawn = (p["speed_m_s"], p["force_n"], p["offset_y_m"])
    return np.asarray(rec.data, np.float32), warns, time.perf_counter() - t0, drawn


def _worker_init() -> None:  # pragma: no cover - runs in the workers
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle


def _warm(_: int) -> int:  # pragma: no cover - runs in the workers
    return os.getpid()


class _Done:
    """A result already at hand (one worker, or recorded data)."""

    def __init__(self, value=None, exc=None) -> None:
        self.value, self.exc = value, exc

    def result(self):
        if self.exc is not None:
            raise self.exc
        return self.value


class _Serial:
    """One worker: simulate in this process."""

    name = "local"

    def __init__(self, fn) -> None:
        self.fn = fn
        self.slots = 1

    def submit(self, job):
        try:
            return _Done(self.fn(job))
        except SimTactileError as exc:
            return _Done(exc=exc)

    def wait(self, pending):
        return list(pending)

    def result(self, h):
        return h.result()

    def close(self, cancel: bool = False) -> None:
        pass


class _Pool:
    """Local worker processes (fork where there is one, as the slide cache's pool)."""

    name = "local"

    def __init__(self, fn, workers: int) -> None:
        from concurrent.futures import ProcessPoolExecutor
        from multiprocessing import get_all_start_methods, get_context

        ctx = get_context("fork" if "fork" in get_all_start_methods() else "spawn")
        self.fn = fn
        self.slots = 2 * workers
        self.pool = ProcessPoolExecutor(workers, mp_context=ctx, initializer=_worker_init)
        # start every worker now, before this process opens the store (its I/O threads)
        list(self.pool.map(_warm, range(workers)))

    def submit(self, job):
        return self.pool.submit(self.fn, job)

    def wait(self, pending):
        from concurrent.futures import FIRST_COMPLETED, wait

        done, _ = wait(list(pending), return_when=FIRST_COMPLETED)
        return list(done)

    def result(self, h):
        from concurrent.futures.process import BrokenProcessPool

        try:
            return h.result()
        except BrokenProcessPool:
            raise StoreError(
                "a worker process died (killed, or out of memory?); every slide written so "
                "far is kept: run the same command with --resume to continue"
            ) from None

    def close(self, cancel: bool = False) -> None:
        self.pool.shutdown(wait=not cancel, cancel_futures=cancel)


class _Ray:
    """Ray tasks, on a local instance (``address`` None: ``workers`` CPUs) or a cluster."""

    name = "ray"

    def __init__(self, fn, workers: int | None, address: str | None, log) -> None:
        from .errors import require

        ray = require("ray", "ray")
        self.ray = ray
        self.own = not ray.is_initialized()
        if self.own:
            kw = {"include_dashboard": False, "log_to_driver": False}
            if address:
                ray.init(address=address, **kw)
            else:
                ray.init(num_cpus=workers or os.cpu_count() or 1, **kw)
        cpus = int(ray.cluster_resources().get("CPU", 1))
        log(f"ray: {cpus} CPUs in the cluster" + (f" at {address}" if address else " (local)"))
        self.slots = 2 * (workers if (workers and address) else cpus)
        # a worker that dies is replaced and its slide simulated again (same seed, same data)
        self.remote = ray.remote(num_cpus=1, max_retries=3)(fn)

    def submit(self, job):
        return self.remote.remote(job)

    def wait(self, pending):
        done, _ = self.ray.wait(list(pending), num_returns=1)
        return done

    def result(self, h):
        return self.ray.get(h)

    def close(self, cancel: bool = False) -> None:
        if self.own:
            self.ray.shutdown()


def default_workers() -> int:
    env = os.environ.get("SIM_TACTILE_WORKERS")
    if env:
        return v.integer("SIM_TACTILE_WORKERS", int(env) if env.isdigit() else env, 1, 1024)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


# --------------------------------------------------------------------------- generate
def _describe_existing(out: Path) -> str:
    try:
        root = _open_root(out)
    except StoreError as exc:
        return str(exc)
    groups = [root[p] for p in root.attrs.get("parts") or []] or [root]
    n = sum(int(g.attrs["n_slides"]) for g in groups)
    done = sum(int((g["checksum"][:] != 0).sum()) for g in groups)
    return f"a data set of {n} slides, {done} written, configuration {root.attrs.get('config_hash', '?')}"


def _diff(a: dict, b: dict, prefix: str = "") -> list[str]:
    out = []
    for k in sorted(set(a) | set(b)):
        x, y = a.get(k), b.get(k)
        if isinstance(x, dict) and isinstance(y, dict):
            out += _diff(x, y, f"{prefix}{k}.")
        elif x != y:
            out.append(f"{prefix}{k}: {x!r} in the store, {y!r} now")
    return out


def _check_same(group, plan: Plan, out: Path) -> None:
    attrs = group.attrs
    where = f"{out}" + (f"/{plan.group}" if plan.group else "")
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
    _simulate: Callable = simulate_slide,
) -> dict:
    """Simulate every slide of ``target`` (a task id or a configuration file) into the Zarr
    store ``out``; returns ``{out, trials, resumed, wall_s, ...}``.

    workers: local processes (default: every core; ``SIM_TACTILE_WORKERS``) or, with Ray, the
        CPUs of a local instance / the slides in flight on a cluster (default: its CPUs).
    backend: ``local`` or ``ray`` (``address``: a running cluster, e.g. ``HOST:6379`` or
        ``auto``; None starts a local instance).
    resume: continue an interrupted store of the same configuration (without it an existing
        ``out`` is refused).
    """
    t_start = time.perf_counter()
    log = log or (lambda m: print(m, file=sys.stderr, flush=True))
    v.one_of("--backend", backend, BACKENDS)
    if address and backend != "ray":
        raise ConfigError("--address is for --backend ray")
    if workers is not None:
        workers = v.integer("--workers", workers, 1, 4096)
    out = Path(out)
    plans, root_attrs = resolve(target, quick=quick, seed=seed, data=data, log=log)
    total = sum(p.spec.n_slides for p in plans)
    if out.exists() and not resume:
        raise StoreError(
            f"{out} already exists ({_describe_existing(out)}); nothing was changed. Pass "
            "--resume to continue it, or choose a new --out"
        )
    if out.exists() and not (out / "zarr.json").is_file():
        raise StoreError(f"{out} exists and is not a data set; choose a new --out")

    simulated = any(p.jobs is not None for p in plans)
    n_workers = workers or default_workers()
    if not simulated:
        runner = _Serial(_simulate)
    elif backend == "ray":
        runner = _Ray(_simulate, workers, address, log)
    elif n_workers == 1:
        runner = _Serial(_simulate)
    else:
        runner = _Pool(_simulate, n_workers)

    import zarr

    resumed = out.exists()
    stats = {"written": 0, "reused": 0, "regenerated": 0, "corrupt": []}
    writers: list[SlideWriter] = []
    todo: list[tuple[int, int]] = []
    root = None
    interrupted = checked = False
    sim_s = write_s = 0.0
    warns: list[Counter] = [Counter() for _ in plans]
    try:
        if resumed:
            root = _open_root(out, "r+")
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
            root = zarr.open_group(str(out), mode="r+")
        for plan in plans:  # all checks before anything is written
            if resumed:
                _check_same(root[plan.group] if plan.group else root, plan, out)
        checked = True
        for k, plan in enumerate(plans):
            group = root[plan.group] if plan.group else root
            w = SlideWriter(group)
            writers.append(w)
            done = w.done() if resumed else np.zeros(plan.spec.n_slides, bool)
            for i in np.flatnonzero(done):
                bad = w.check(int(i))
                if bad:
                    where = f"{plan.group}: " if plan.group else ""
                    log(f"{where}slide {i}: {bad}; writing it again")
                    stats["corrupt"].append({"part": plan.group, "slide": int(i), "reason": bad})
                    w.clear(int(i))
                    done[i] = False
            stats["reused"] += int(done.sum())
            todo += [(k, int(i)) for i in np.flatnonzero(~done)]
        stats["regenerated"] = len(stats["corrupt"])
        if resumed:
            log(
                f"resuming {out}: {stats['reused']} of {total} slides written and checked, "
                f"{len(todo)} to go ({stats['regenerated']} corrupt)"
            )
        if todo and simulated:
            log(
                f"{out}: {len(todo)} slides on {runner.name}"
                + (f", {n_workers} worker(s)" if runner.name == "local" else "")
            )
        bar = _progress(total, stats["reused"], out.name, progress)
        try:
            queue = iter(todo)
            pending: dict = {}
            while True:
                while len(pending) < runner.slots:
                    key = next(queue, None)
                    if key is None:
                        break
                    plan = plans[key[0]]
                    if plan.jobs is not None:
                        pending[runner.submit(plan.jobs[key[1]])] = key
                    else:
                        x = plan.dataset.data[key[1]]
                        pending[_Done((x, [], 0.0, (math.nan,) * 3))] = key
                if not pending:
                    break
                ready = [h for h in pending if isinstance(h, _Done)] or runner.wait(pending)
                for h in ready:
                    k, i = pending.pop(h)
                    try:
                        x, w_list, wall, drawn = (
                            h.result() if isinstance(h, _Done) else runner.result(h)
                        )
                    except StoreError:
                        raise
                    except SimTactileError as exc:
                        raise SimTactileError(
                            f"{plans[k].spec.name} slide {i}: {str(exc).splitlines()[0]}"
                        ) from exc
                    _check_drawn(plans[k], i, drawn)
                    t0 = time.perf_counter()
                    writers[k].write(i, x)
                    write_s += time.perf_counter() - t0
                    sim_s += wall
                    warns[k].update(w_list)
                    stats["written"] += 1
                    bar.update(1)
        finally:
            bar.close()
    except KeyboardInterrupt:
        interrupted = True
        log(
            f"interrupted: {stats['reused'] + stats['written']} of {total} slides are in {out}; "
            "run the same command with --resume to continue"
        )
        runner.close(cancel=True)
        raise
    finally:
        if not interrupted:
            runner.close(cancel=True)
        if checked:
            _record_run(
                root,
                plans,
                writers,
                warns,
                stats,
                backend,
                n_workers,
                address,
                t_start,
                interrupted,
            )
    wall = time.perf_counter() - t_start
    return {
        "out": str(out),
        "trials": total,
        "resumed": bool(resumed),
        "wall_s": round(wall, 3),
        "written": stats["written"],
        "reused": stats["reused"],
        "regenerated": stats["regenerated"],
        "corrupt": stats["corrupt"],
        "backend": backend,
        "workers": n_workers if backend == "local" else workers,
        "parts": [p.group for p in plans if p.group],
        "config_hash": root.attrs.get("config_hash") if root is not None else None,
        "simulate_s": round(sim_s, 3),
        "write_s": round(write_s, 4),
        "store_overhead": round(write_s / sim_s, 5) if sim_s > 0 else None,
    }


def _check_drawn(plan: Plan, i: int, drawn) -> None:
    want = plan.spec.params[i]
    got = np.asarray(drawn, dtype=np.float64)
    if not np.array_equal(np.nan_to_num(want, nan=-1.0), np.nan_to_num(got, nan=-1.0)):
        raise StoreError(
            f"slide {i}: the simulator drew {got.tolist()} for {list(PARAM_NAMES)}, the store "
            f"expects {want.tolist()}; the seeding of the protocol changed"
        )


def _record_run(
    root, plans, writers, warns, stats, backend, workers, address, t_start, interrupted
):
    """Completion flags, warnings and the run's line in the store's history (parent only)."""
    for plan, w, c in zip(plans, writers, warns, strict=False):
        group = root[plan.group] if plan.group else root
        old = Counter(group.attrs.get("sim_warnings") or {})
        old.update(c)
        group.attrs.update(
            {"sim_warnings": dict(old.most_common()), "complete": bool(w.done().all())}
        )
    run = {
        "at": datetime.now(UTC).isoformat(timespec="seconds"),
        "backend": backend,
        "workers": workers,
        "address": address,
        "written": stats["written"],
        "regenerated": stats["regenerated"],
        "interrupted": interrupted,
        "wall_s": round(time.perf_counter() - t_start, 3),
    }
    if backend == "ray":
        run["ray"] = sys.modules["ray"].__version__ if "ray" in sys.modules else None
    root.attrs.update({"runs": [*(root.attrs.get("runs") or []), run]})


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
