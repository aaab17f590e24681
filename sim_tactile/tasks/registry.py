"""The registry of benchmark tasks: versioned ids, one small definition each.

A task id never changes meaning once released (``finger7-v1``, ``biotac20-real``): a change
of data, encoding, protocol or hyperparameters is a new id. A task says where its data comes
from (``get_data``: a loader of real recordings, or a simulation), which classifiers it runs
by default with which parameters, its protocol (split, repeats, the time points of the
accuracy-over-time curve) and the numbers of the paper it reproduces.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from .._names import did_you_mean
from ..encoders.encodings import Steps, threshold_encoding
from ..errors import ConfigError, UnknownNameError
from ..learn.classifiers import LearnContext, get_classifier
from ..records import TactileDataset
from .versions import split_task_id, unknown_task


@dataclass(frozen=True)
class PaperCell:
    """A number of a paper's table: mean accuracy and its standard deviation (or None)."""

    mean: float
    std: float | None
    source: str

    def to_json(self) -> dict:
        return {"mean": self.mean, "std": self.std, "source": self.source}


@dataclass(frozen=True)
class DataRequest:
    """What ``get_data`` gets: the user's data path (real tasks), the quick flag, the seed
    and a logger (one line per call, to stderr). A simulating ``get_data`` puts its wall time
    [s] in the dataset's ``meta["simulate_s"]``; the report's ``timing.simulate_s`` reads it."""

    data: Path | None
    quick: bool
    seed: int
    log: Callable[[str], None]
    #: a store written by ``sim-tactile generate`` to read the data from (see
    #: :func:`sim_tactile.tasks.runner.task_data`)
    store: Path | None = None


@dataclass(frozen=True)
class Run:
    """One row of a task's table: a classifier on a set of channels under a split.

    channels: a key of :attr:`TaskSpec.channel_sets` (``"all"``: every channel); split: None
    for the task's (or the mode's) split; params: overrides of the classifier's parameters
    (for example a distance and its ``q``); label: the row's name (default
    ``classifier[ channels][ split]``); paper: the paper's number for this row.
    """

    classifier: str
    channels: str = "all"
    split: str | None = None
    params: Mapping[str, Any] = field(default_factory=dict)
    label: str = ""
    paper: PaperCell | None = None

    @property
    def name(self) -> str:
        if self.label:
            return self.label
        parts = [self.classifier]
        if self.channels != "all":
            parts.append(self.channels)
        if self.split:
            parts.append(self.split)
        return " ".join(parts)


@dataclass(frozen=True)
class Settings:
    """The protocol and classifier parameters of one mode (full or quick). ``split``
    replaces the task's split in this mode (a quick run has fewer samples per class)."""

    repeats: int = 5
    repeats_by_classifier: Mapping[str, int] = field(default_factory=dict)
    time_points_s: tuple[float, ...] = ()
    time_repeats: int = 1
    params: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    split: str | None = None

    def repeats_for(self, name: str) -> int:
        return int(self.repeats_by_classifier.get(name, self.repeats))


#: A quick run's torch rows (their fits are most of its time): at most this many repeats
#: where the task's quick settings give them none of their own; the report's ``repeats``
#: column states each row's number. A quick run is a smoke run of every row in about a
#: minute; the full run's protocol does not change.
QUICK_NETWORK_REPEATS = 5
#: The torch rows' parameters in a quick run where the task's quick settings give none: a
#: spiking network small enough, and spike-count targets low enough for a 1 s window, to
#: learn on a quick split (finger7-v1 quick, 6/2, its first 5 splits: 0.76 mean accuracy,
#: 1.5 s a fit on one core; the full defaults, 250 / 30 spikes in 94 steps: 0.29, 4.5 s), and
#: the LSTM at 60 epochs (0.88, 3.2 s a fit; its default 200: 0.96, 15.7 s). Measured with
#: perf/bench_quick_snn.py.
QUICK_NETWORK_PARAMS: Mapping[str, Mapping[str, Any]] = {
    "snn": {
        "hidden": 32,
        "target_true": 20.0,
        "target_false": 3.0,
        "epochs": 60,
        "lr": 0.03,
        "batch_size": 8,
        "num_threads": 1,
    },
    "lstm": {"epochs": 60, "num_threads": 1},
}


def quick_form(settings: Settings) -> Settings:
    """A task's quick ``settings`` with :data:`QUICK_NETWORK_PARAMS` and
    :data:`QUICK_NETWORK_REPEATS` for the torch rows it gives nothing of its own."""
    params = {k: dict(v) for k, v in QUICK_NETWORK_PARAMS.items()}
    params.update({k: dict(v) for k, v in settings.params.items()})
    cap = min(settings.repeats, QUICK_NETWORK_REPEATS)
    repeats = {name: cap for name in QUICK_NETWORK_PARAMS}
    repeats.update(settings.repeats_by_classifier)
    return replace(settings, params=params, repeats_by_classifier=repeats)


@dataclass(frozen=True)
class BenchScene:
    """A task's scene in ``sim-tactile bench speed-error``: one of its plates (one whose
    texture has a closed-form pulse period to check), slid with the task's sensor at its
    nominal speed and force. ``key`` names it on the command line; ``left_out`` says why the
    full sweep leaves it out by default ("": it runs)."""

    key: str
    plate: str
    left_out: str = ""


@dataclass(frozen=True)
class TaskSpec:
    """One benchmark task (see the module docstring).

    ``paper`` maps classifier names to the paper's cells; ``notes`` maps classifier names to
    a sentence on why a cell differs from the paper (shown when it differs by more than two
    of the paper's standard deviations); ``remarks`` are sentences shown in every report (the
    choices the paper leaves open). ``features`` are the spike features of svm / lda / knn /
    src. ``get_data`` is None for a suite, whose ``parts`` are tasks of their own.
    ``bench``: the task's scene in the speed-against-error benchmark (None: not in it).
    ``history``: this version's entries in its family's version history (what it changed,
    in which release); ``supersedes``: the older id of its family that it replaces (whose
    users are told once, when they run it, to move here; "" for none). Neither is part of
    the definition (:meth:`describe`): a family's history grows, a released id does not.
    """

    id: str
    title: str
    get_data: Callable[[DataRequest], TactileDataset] | None
    classifiers: tuple[str, ...]
    split: str = "7:3"
    full: Settings = Settings()
    quick: Settings = Settings(repeats=1)
    needs_data_path: bool = False
    encoder: Callable[[LearnContext], Steps] = threshold_encoding
    encoding: str = "threshold encoding, K = 2"
    features: tuple[str, ...] = ("rate_hz", "mean_isi_s")
    paper: Mapping[str, PaperCell] = field(default_factory=dict)
    notes: Mapping[str, str] = field(default_factory=dict)
    remarks: tuple[str, ...] = ()
    reference: str = ""
    runs: tuple[Run, ...] = ()
    channel_sets: Mapping[str, tuple[int, ...]] = field(default_factory=dict)
    encode_once: bool = False
    parts: tuple[str, ...] = ()
    bench: BenchScene | None = None
    history: tuple[str, ...] = ()
    supersedes: str = ""

    def describe(self) -> dict:
        """The whole definition as JSON data (a released id's never changes)."""
        data = self.get_data
        if data is not None:
            data = data.describe() if hasattr(data, "describe") else _qualname(data)
        d = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in _NOT_DEFINITION}
        d.update(
            get_data=data,
            encoder=_qualname(self.encoder),
            full=asdict(self.full),
            quick=asdict(self.settings(True)),
            paper={k: c.to_json() for k, c in self.paper.items()},
            runs=[
                {**asdict(r), "paper": r.paper.to_json() if r.paper else None} for r in self.runs
            ],
            bench=None if self.bench is None else asdict(self.bench),
            aliases=sorted(a for a, t in _ALIASES.items() if t == self.id),
        )
        return json.loads(json.dumps(d))

    def all_runs(self) -> tuple[Run, ...]:
        if self.runs:
            return self.runs
        return tuple(Run(c, paper=self.paper.get(c)) for c in self.classifiers)

    def split_for(self, run: Run, quick: bool) -> str:
        # a mode's split (the quick run's, on fewer samples) overrides the rows' own
        return self.settings(quick).split or run.split or self.split

    def settings(self, quick: bool) -> Settings:
        """The full settings, or the quick ones with the torch rows' quick form
        (:func:`quick_form`)."""
        return quick_form(self.quick) if quick else self.full

    def context(self, dataset: TactileDataset, quick: bool) -> LearnContext:
        grid = dataset.meta.get("grid_shape")
        return LearnContext(
            rate_hz=dataset.rate_hz,
            n_channels=dataset.n_channels,
            grid_shape=tuple(grid) if grid else None,
            encoder=self.encoder,
            spike_features=self.features,
            params=self.settings(quick).params,
        )


#: TaskSpec fields that are not the definition: the family's record around it
_NOT_DEFINITION = ("history", "supersedes")


def _qualname(f: Callable) -> str:
    return f"{f.__module__}.{f.__qualname__}"


_TASKS: dict[str, TaskSpec] = {}
#: Other names of released ids (an alias, like the id it names, never changes meaning).
_ALIASES: dict[str, str] = {}


def register(spec: TaskSpec) -> TaskSpec:
    """Add a task; an id can be registered once (ids never change meaning)."""
    if spec.id in _TASKS or spec.id in _ALIASES:
        raise ConfigError(f"task id {spec.id!r} is already registered; give a new version")
    if (spec.get_data is None) == (not spec.parts):
        raise ConfigError(
            f"task {spec.id}: give get_data (its data) or parts (a suite of tasks), not both"
        )
    for name in (*spec.classifiers, *spec.paper, *(r.classifier for r in spec.runs)):
        get_classifier(name)
    for r in spec.runs:
        if r.channels != "all" and r.channels not in spec.channel_sets:
            raise ConfigError(
                f"task {spec.id}: run {r.name!r} names channel set {r.channels!r}; "
                f"valid: all, {', '.join(spec.channel_sets)}"
            )
    labels = [r.name for r in spec.all_runs()]
    if len(set(labels)) != len(labels):
        raise ConfigError(f"task {spec.id}: two runs share a label: {labels}")
    _check_family(spec)
    _TASKS[spec.id] = spec
    return spec


def _check_family(spec: TaskSpec) -> None:
    """A version's place in its family: its own history (``replace`` copies the older
    version's), and at most one successor for each older id of the same family."""
    family, version = split_task_id(spec.id)
    kin = [t for t in _TASKS.values() if split_task_id(t.id)[0] == family]
    for t in kin:
        if spec.history and spec.history == t.history:
            raise ConfigError(
                f"task {spec.id}: its history is {t.id}'s (copied by replace()); give "
                "history=(...) saying what this version changes"
            )
    if not spec.supersedes:
        return
    old = _TASKS.get(spec.supersedes)
    if old is None or split_task_id(old.id)[0] != family or split_task_id(old.id)[1] >= version:
        raise ConfigError(
            f"task {spec.id}: supersedes = {spec.supersedes!r}; valid: a registered older "
            f"version of the family {family!r}"
        )
    taken = successor(old.id)
    if taken is not None:
        raise ConfigError(
            f"task {spec.id}: {old.id} is already superseded by {taken}; a version has one "
            "successor (replace() may have copied supersedes)"
        )


def alias(name: str, task_id: str) -> None:
    """Let ``name`` stand for the registered ``task_id`` (an older id of the same task)."""
    if name in _TASKS or name in _ALIASES:
        raise ConfigError(f"task id {name!r} is already registered")
    get_task(task_id)
    _ALIASES[name] = task_id


def unregister(task_id: str) -> None:
    """Remove a task registered by :func:`register` (for tests and scripts; the package's
    own tasks are released and stay)."""
    if task_id not in _TASKS:
        raise UnknownNameError(f"task {task_id!r} is not registered")
    del _TASKS[task_id]
    for name in [a for a, t in _ALIASES.items() if t == task_id]:
        del _ALIASES[name]


def task_ids(*, aliases: bool = False) -> tuple[str, ...]:
    """The registered ids (with ``aliases``: and the other names they go by)."""
    return tuple(_TASKS) + (tuple(_ALIASES) if aliases else ())


def get_task(task_id: str) -> TaskSpec:
    """The task ``task_id`` (an id or an alias). An unknown id's error names the versions
    of its family, or the ids it is close to."""
    try:
        return _TASKS[_ALIASES.get(task_id, task_id)]
    except KeyError:
        raise UnknownNameError(unknown_task(task_id, (*_TASKS, *_ALIASES))) from None


def successor(task_id: str) -> str | None:
    """The id that supersedes ``task_id`` (registered with ``supersedes``), or None."""
    tid = _ALIASES.get(task_id, task_id)
    return next((t.id for t in _TASKS.values() if t.supersedes == tid), None)


def latest(task_id: str) -> str:
    """The end of ``task_id``'s chain of successors (``task_id`` itself when current)."""
    tid = _ALIASES.get(task_id, task_id)
    while (nxt := successor(tid)) is not None:
        tid = nxt
    return tid


class OutdatedTaskWarning(UserWarning):
    """A superseded task id was run (it still runs, as released)."""


_WARNED: set[str] = set()


def use_task(task_id: str) -> TaskSpec:
    """:func:`get_task` for a command that runs the task: a superseded id warns, once per
    process, and names the id that supersedes it (as Gymnasium warns of an out-of-date
    environment)."""
    spec = get_task(task_id)
    newer = latest(spec.id)
    if newer != spec.id and spec.id not in _WARNED:
        _WARNED.add(spec.id)
        warnings.warn(
            f"task {spec.id} is out of date: {newer} supersedes it; {spec.id} still runs as "
            "released (the ids a paper should report: sim-tactile tasks --suite core-v1)",
            OutdatedTaskWarning,
            stacklevel=2,
        )
    return spec


def quiet_outdated(task_ids) -> None:
    """Count ``task_ids`` as warned already (a suite's parts, when the suite has warned)."""
    _WARNED.update(task_ids)


def family_versions(task_id: str) -> tuple[str, ...]:
    """The registered ids of ``task_id``'s family, oldest first."""
    family = split_task_id(task_id)[0]
    ids = [t for t in _TASKS if split_task_id(t)[0] == family]
    return tuple(sorted(ids, key=lambda t: split_task_id(t)[1]))


#: Named suites of task ids (``sim-tactile tasks --suite NAME``).
_SUITES: dict[str, tuple[str, ...]] = {}


def register_suite(name: str, ids: tuple[str, ...]) -> None:
    """A named list of registered ids (a suite's name, like an id, never changes meaning)."""
    if name in _SUITES:
        raise ConfigError(f"suite {name!r} is already registered; give a new version")
    for t in ids:
        get_task(t)
    _SUITES[name] = tuple(ids)


def suite(name: str) -> tuple[str, ...]:
    """The task ids of the suite ``name`` (``core-v1``: the ids a paper should report)."""
    try:
        return _SUITES[name]
    except KeyError:
        raise UnknownNameError(
            f"suite {name!r} is not known{did_you_mean(name, list(_SUITES))}; valid: "
            f"{', '.join(_SUITES) or '(none)'}"
        ) from None


def suite_names() -> tuple[str, ...]:
    return tuple(_SUITES)


def with_calibration(spec: TaskSpec, cal) -> TaskSpec:
    """``spec`` simulated with a calibrated sensor (``--sensor-config``): a simulated task
    whose sensor is the calibration's. Its reports say so in a remark (its numbers are not
    the released task's)."""
    from ..slides import SlideSet

    if spec.parts:
        raise ConfigError(
            f"--sensor-config calibrates one sensor; task {spec.id} is a suite of "
            f"{list(spec.parts)}: run the part with that sensor"
        )
    if not isinstance(spec.get_data, SlideSet):
        raise ConfigError(f"--sensor-config is for simulated tasks; {spec.id} reads recordings")
    ss = spec.get_data
    if ss.sensor != cal.sensor:
        raise ConfigError(
            f"the sensor config calibrates {cal.sensor!r}; task {spec.id} simulates {ss.sensor!r}"
        )
    note = (
        f"Sensor calibrated (--sensor-config) on {cal.n_recordings} real recordings: "
        f"{cal.source}; per-channel gains, offsets, noise and drift from the fit."
    )
    return replace(spec, get_data=replace(ss, calibration=cal), remarks=(*spec.remarks, note))
