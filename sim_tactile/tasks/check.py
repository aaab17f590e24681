"""``sim-tactile check RESULT.json``: a result file (:mod:`.result_file`) validated against
the registered task. Each refusal is one line; a file with none passes.

What is checked, in this order (a missing block or an unknown task stops the check there):

- the schema (its name and version) and the ``config`` and ``results`` blocks;
- the task: a registered id (not an alias or a suite), its family and version, and a
  ``results`` block that holds that task alone;
- a paper's number (``reported``): the cell that the task registers for the row;
- the protocol's fixed fields: the mode, the row's split, the seed (0: the task's splits),
  the encode-once flag, the interval's definition, and enough repeats (at least
  :data:`~.intervals.MIN_REPEATS`, and at least the task's own for the row);
- the split digest: the splits drawn again from the file's labels, split, repeats and seed;
- each metric: as many repeats as the protocol, their mean and SD, and the 95% interval
  recomputed from them (:mod:`.intervals`);
- the closed track: the task's own definition (its digest), data (its labels) and encoding,
  and a method whose only part of its own is the classifier.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..errors import ConfigError, UnknownNameError
from ..slides import SlideSet
from . import intervals
from .defs.real import LABELS_SHA256
from .methods import TASK_ENCODER
from .registry import TaskSpec, get_task
from .result_file import (
    INTERVAL,
    METRICS,
    NO_ENCODER,
    SCHEMA,
    labels_sha256,
    reads_recordings,
    run_of,
    task_sha256,
)
from .splits import splits_digest, task_splits
from .versions import split_task_id

#: The keys every ``config`` block has, with their JSON types (``version``: null for an
#: id of no version).
CONFIG_KEYS = {
    "model_name": str,
    "method": Mapping,
    "task": str,
    "family": str,
    "version": (int, type(None)),
    "task_sha256": str,
    "track": str,
    "reported": bool,
    "protocol": Mapping,
    "interval": Mapping,
}
PROTOCOL_KEYS = {
    "mode": str,
    "split": str,
    "repeats": int,
    "seed": int,
    "splits_sha256": str,
    "labels_sha256": str,
    "labels": list,
    "encoding": str,
    "encode_once": bool,
}
METHOD_KEYS = {"name": str, "version": str, "builtin": bool, "encoder": str}
_TYPE_NAMES = {str: "a string", int: "a whole number", bool: "true or false", list: "a list"}
TRACKS = ("closed", "open")


def check_file(path: str | Path) -> list[str]:
    """The refusals of the result file at ``path`` ([] when it is valid)."""
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        return ["no such file"]
    except (OSError, UnicodeDecodeError) as exc:
        return [f"cannot be read ({exc})"]
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        return [f"not JSON ({exc}): the file is incomplete or damaged"]
    return check_document(doc)


def check_document(doc) -> list[str]:
    """The refusals of a result file's document ([] when it is valid)."""
    head = _head(doc)
    if isinstance(head, list):
        return head
    spec, cfg, metrics = head
    out = []
    family, version = split_task_id(spec.id)
    if cfg["family"] != family or cfg["version"] != version:
        out.append(
            f"config.family / config.version = {cfg['family']!r} / {cfg['version']!r}; "
            f"task {spec.id} is version {version} of the family {family!r}"
        )
    if cfg["track"] not in TRACKS:
        out.append(f"config.track = {cfg['track']!r}; valid: {' or '.join(TRACKS)}")
    if cfg["reported"] is True:
        return out + _reported(spec, cfg, metrics)
    if cfg["reported"] is not False:
        out.append(f"config.reported = {cfg['reported']!r}; valid: true or false")
    proto = cfg["protocol"]
    if (line := _incomplete("config.protocol", proto, PROTOCOL_KEYS)) is not None:
        return [*out, line]  # nothing below can be read
    out += _protocol(spec, cfg)
    out += _metrics(spec.id, proto, metrics)
    if cfg["track"] == "closed":
        out += _closed(spec, cfg)
    return out


def _incomplete(where: str, block, keys) -> str | None:
    """The refusal of a block that lacks a key or holds one of another JSON type (None: the
    block is whole)."""
    if not isinstance(block, Mapping):
        return f"{where} is not an object: the file is incomplete"
    missing = [k for k in keys if k not in block]
    if missing:
        return f"{where} lacks {', '.join(missing)}: the file is incomplete"
    for k, want in keys.items():
        v = block[k]
        bad_int = want is int and isinstance(v, bool)  # JSON's true is no number
        if not isinstance(v, want) or bad_int:
            name = _TYPE_NAMES.get(want, "an object" if want is Mapping else "a whole number")
            return f"{where}.{k} = {_short(v)}; valid: {name}"
    return None


def _short(v) -> str:
    text = json.dumps(v)
    return text if len(text) <= 60 else text[:57] + "..."


def _head(doc):
    """``(spec, config, metrics)``, or the refusal that stops the check."""
    if not isinstance(doc, Mapping):
        return ["not a result file: the document is not a JSON object"]
    schema = doc.get("schema")
    if schema != SCHEMA:
        if isinstance(schema, Mapping) and schema.get("name") == SCHEMA["name"]:
            return [
                f"schema version {schema.get('version')!r}; this sim-tactile reads version "
                f"{SCHEMA['version']}"
            ]
        return [f"not a sim-tactile result file: schema = {schema!r}, want {SCHEMA}"]
    cfg, res = doc.get("config"), doc.get("results")
    if not isinstance(cfg, Mapping) or not isinstance(res, Mapping):
        return ["a result file has a config and a results block (objects): the file is incomplete"]
    for where, block, keys in (
        ("config", cfg, CONFIG_KEYS),
        ("config.method", cfg.get("method"), METHOD_KEYS),
    ):
        if (line := _incomplete(where, block, keys)) is not None:
            return [line]
    task, method = cfg["task"], cfg["method"]
    try:
        spec = get_task(task)
    except UnknownNameError as exc:
        return [f"config.task: {exc}"]
    if spec.id != task:
        return [f"config.task = {task!r} is another name of {spec.id}; a result names the id"]
    if spec.parts:
        return [f"config.task = {task} is a suite; a result file holds one of its parts"]
    if set(res) != {task} or not isinstance(res[task], Mapping):
        return [f"results holds {sorted(res)}; a result file holds one task's metrics: {task}"]
    if cfg["model_name"] != method["name"]:
        return [f"config.model_name = {cfg['model_name']!r} is not config.method.name"]
    return spec, cfg, res[task]


def _reported(spec: TaskSpec, cfg, metrics) -> list[str]:
    """A paper's number: the task's registered cell for the row, no repeats, no interval."""
    row = cfg["method"].get("row")
    run = next((r for r in spec.all_runs() if r.name == row and r.paper is not None), None)
    if run is None:
        rows = [r.name for r in spec.all_runs() if r.paper is not None]
        return [
            f"reported: config.method.row = {row!r} is not a row of {spec.id} with a paper's "
            f"number; valid: {rows}"
        ]
    cell, out = run.paper, []
    if metrics.get("accuracy") != cell.mean or metrics.get("accuracy_sd") != cell.std:
        out.append(
            f"reported: accuracy (SD) = {metrics.get('accuracy')!r} ({metrics.get('accuracy_sd')!r})"
            f"; {spec.id} registers {cell.mean} ({cell.std}) for {row!r} ({cell.source})"
        )
    if metrics.get("accuracy_repeats") is not None or metrics.get("accuracy_ci95") is not None:
        out.append("reported: a paper's number was not re-run here: no repeats and no interval")
    return out


def _protocol(spec: TaskSpec, cfg) -> list[str]:
    """The protocol's fixed fields, the repeats and the split digest."""
    p, method = cfg["protocol"], cfg["method"]
    if p["mode"] not in ("full", "quick"):
        return [f"config.protocol.mode = {p['mode']!r}; valid: full or quick"]
    quick = p["mode"] == "quick"
    run = run_of(spec, method["name"]) if method["builtin"] else None
    out = []
    if method["builtin"] and run is None:
        out.append(
            f"config.method.name = {method['name']!r} is not a row of {spec.id}; its rows: "
            f"{[r.name for r in spec.all_runs()]}"
        )
    settings = spec.settings(quick)
    split = spec.split_for(run, quick) if run else (settings.split or spec.split)
    need = max(settings.repeats_for(run.classifier) if run else settings.repeats, 1)
    if p["split"] != split:
        out.append(
            f"config.protocol.split = {p['split']!r}; {spec.id}'s {p['mode']} protocol splits "
            f"this row {split!r}"
        )
    if p["seed"] != 0:
        out.append(f"config.protocol.seed = {p['seed']!r}; the task's splits are seed 0's")
    if p["encode_once"] != spec.encode_once:
        out.append(
            f"config.protocol.encode_once = {p['encode_once']!r}; {spec.id}'s is {spec.encode_once}"
        )
    n = p["repeats"]
    if n < 1:
        return [*out, f"config.protocol.repeats = {n!r}; valid: a whole number >= 1"]
    if n < max(intervals.MIN_REPEATS, need):
        out.append(
            f"config.protocol.repeats = {n}: too few; {spec.id}'s {p['mode']} protocol has "
            f"{need} for this row, and an interval needs at least {intervals.MIN_REPEATS}"
        )
    if cfg["interval"] != INTERVAL:
        out.append(f"config.interval = {cfg['interval']!r}; the schema's is {INTERVAL}")
    if p["split"] != split or p["seed"] != 0:
        return out  # refused already: its splits are not the task's whatever their digest
    return out + _splits(p, n)


def _splits(p, n: int) -> list[str]:
    labels = p["labels"]
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in labels):
        return ["config.protocol.labels: valid: a list of whole numbers (the class of each sample)"]
    if labels_sha256(labels) != p["labels_sha256"]:
        return ["config.protocol.labels_sha256 is not the digest of config.protocol.labels"]
    try:
        digest = splits_digest(task_splits(np.asarray(labels), p["split"], n, p["seed"]))
    except (ConfigError, TypeError, ValueError) as exc:
        return [f"config.protocol: the splits cannot be drawn again ({exc})"]
    if digest != p["splits_sha256"]:
        return [
            f"config.protocol.splits_sha256 is not the digest of the task's splits ({p['split']}, "
            f"{n} repeats, seed {p['seed']}, drawn from the labels): the splits are not the "
            "task's"
        ]
    return []


def _metrics(task: str, p, metrics) -> list[str]:
    """Each metric's repeats, mean, SD and interval."""
    out = []
    if "accuracy" not in metrics:
        out.append(f"results.{task} has no accuracy: the file is incomplete")
    with np.errstate(all="ignore"):  # numbers near the float's limits are refused, not warned of
        for name in METRICS:
            if name in metrics:
                out += _metric(f"results.{task}.{name}", name, metrics, p["repeats"])
    return out


def _metric(where: str, name: str, m, n: int) -> list[str]:
    keys = (name, f"{name}_sd", f"{name}_ci95", f"{name}_repeats")
    if any(k not in m for k in keys):
        return [f"{where}: needs {', '.join(keys)}: the file is incomplete"]
    reps = m[f"{name}_repeats"]
    if not isinstance(reps, list) or not all(_finite(v) for v in reps):
        return [f"{where}_repeats: valid: a list of finite numbers, one per repeat"]
    if len(reps) != n:
        return [
            f"{where}_repeats holds {len(reps)} values; config.protocol.repeats is {n} (a "
            "repeat was dropped or added)"
        ]
    lo, hi = (0.0, 1.0) if name == "accuracy" else (0.0, math.inf)
    if not all(lo <= v <= hi for v in reps):
        return [f"{where}_repeats: a value outside [{lo:g}, {hi:g}]"]
    x, out = np.asarray(reps, dtype=np.float64), []
    for key, want, what in ((name, np.mean(x), "mean"), (f"{name}_sd", np.std(x), "SD")):
        if not _finite(m[key]) or not intervals.close(float(m[key]), float(want)):
            out.append(
                f"{where.rsplit('.', 1)[0]}.{key} = {m[key]!r} is not the {what} of its {n} "
                f"repeats ({float(want):.6g})"
            )
    ci = m[f"{name}_ci95"]
    if n < intervals.MIN_REPEATS:
        if ci is not None:
            out.append(f"{where}_ci95: no interval below {intervals.MIN_REPEATS} repeats")
    elif not (
        isinstance(ci, list) and len(ci) == 2 and all(_finite(v) for v in ci)
    ) or not intervals.interval_agrees(ci, x):
        out.append(
            f"{where}_ci95 = {ci!r} is not the 95% interval of its repeats "
            f"({intervals.interval_text(intervals.interval(x), 6)} recomputed)"
        )
    return out


def _finite(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _closed(spec: TaskSpec, cfg) -> list[str]:
    """The closed track: the task's own definition, data and encoding; only the classifier
    is the method's."""
    p, method, out = cfg["protocol"], cfg["method"], []
    if cfg["task_sha256"] != task_sha256(spec, p["mode"] == "quick"):
        out.append(
            f"closed track: config.task_sha256 is not {spec.id}'s definition (a calibrated "
            "sensor, data of your own or another package version's task): the open track"
        )
    want = expected_labels_sha256(spec, p["mode"] == "quick")
    if want is None:
        out.append(f"closed track: {spec.id}'s labels cannot be verified (no pinned digest)")
    elif p["labels_sha256"] != want:
        out.append(
            f"closed track: the labels are not {spec.id}'s (its data set's classes, in its "
            "order): data of your own stand in the open track"
        )
    if p["encoding"] != spec.encoding:
        out.append(
            f"closed track: config.protocol.encoding = {p['encoding']!r} is not "
            f"{spec.id}'s ({spec.encoding!r})"
        )
    run = run_of(spec, method["name"]) if method["builtin"] else None
    allowed = {TASK_ENCODER}
    if run is not None and reads_recordings(run.classifier):
        allowed = {NO_ENCODER}  # the task's own raw rows (svm-raw, lstm)
    if method["encoder"] not in allowed:
        out.append(
            f"closed track: config.method.encoder = {method['encoder']!r}: the method brings "
            f"its own encoding; the closed track takes {spec.id}'s own encoder, only the "
            "classifier is yours (a ('task', estimator) method): submit it to the open track"
        )
    return out


def expected_labels_sha256(spec: TaskSpec, quick: bool) -> str | None:
    """The digest of a task's labels: drawn from its slide set (simulated), or pinned
    (the real data sets, :data:`~.defs.real.LABELS_SHA256`); None where neither is known."""
    data = spec.get_data
    if isinstance(data, SlideSet):
        n = len(data.plates_for(quick))
        return labels_sha256(np.repeat(np.arange(n), data.slides_for(quick)))
    return LABELS_SHA256.get(spec.id)
