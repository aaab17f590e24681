"""A task as data and protocol, for a user's own framework, and a user's methods scored on it.

:func:`load` returns a task's data set and its evaluation protocol (OpenML's task: data plus
fixed splits): ``X`` of shape ``(samples, time, channels)``, the labels, class names, rate and
channel positions, and :meth:`TaskProtocol.splits`, the (train, test) indices the task's own
runs use, repeat by repeat, the same for a given seed. What a user computes on them is
comparable with the built-in rows. :func:`evaluate` scores the user's methods
(:mod:`.methods`) under the task's protocol and writes the same report as ``run``, the
user's rows beside the built-in ones and the paper's numbers.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._validate import integer
from ..errors import ConfigError
from ..records import TactileDataset
from .registry import use_task
from .runner import load_task, run_task
from .splits import splits_digest, task_splits


def _quiet(msg: str) -> None:
    return None


@dataclass(frozen=True)
class TaskProtocol:
    """A task's evaluation protocol: its split (``"24/8"``: per class; ``"7:3"``: a
    stratified ratio), the repeats of its rows, the seed of its splits, the time points of
    its accuracy-over-time curve, and whether it encodes its recordings once on all samples
    before splitting (``encode_once``, as the papers that encoded offline did). ``splits``
    holds every split the task's rows use (roughness8-v1: 9:1, 7:3 and 5:5)."""

    task: str
    split: str
    repeats: int
    seed: int
    time_points_s: tuple[float, ...]
    encode_once: bool
    split_names: tuple[str, ...]
    labels: np.ndarray = field(repr=False, compare=False)

    def splits(self, split: str | None = None, repeats: int | None = None) -> Iterator:
        """Yield ``(train, test)`` index arrays (sorted int64), repeat by repeat: the pairs
        the task's own run uses for ``split`` (default: the task's), ``repeats`` of them
        (default: the task's). The first ``k`` pairs do not depend on ``repeats``."""
        split = self.split if split is None else split
        n = self.repeats if repeats is None else integer("repeats", repeats, 1, None)
        yield from task_splits(self.labels, split, n, self.seed)

    def get_train_test_split_indices(self, repeat: int, split: str | None = None):
        """The ``(train, test)`` indices of one repeat (OpenML's name for it)."""
        r = integer("repeat", repeat, 0, None)
        return task_splits(self.labels, self.split if split is None else split, r + 1, self.seed)[r]

    def digest(self, split: str | None = None, repeats: int | None = None) -> str:
        """SHA-256 of the splits, as a report's ``protocol.splits_sha256`` holds it."""
        return splits_digest(list(self.splits(split, repeats)))


@dataclass(frozen=True)
class TaskData:
    """A task's data set and protocol (:func:`load`). ``X``: ``(samples, time, channels)``
    float32 in the sensor's ``units``; ``y``: ``(samples,)`` int64 class indices into
    ``class_names``; ``channel_positions_m``: ``(channels, 3)`` in the pad frame [m], or None
    where the data set does not give them (the real iCub)."""

    task: str
    X: np.ndarray = field(repr=False)
    y: np.ndarray = field(repr=False)
    class_names: tuple[str, ...]
    channel_names: tuple[str, ...]
    rate_hz: float
    channel_positions_m: np.ndarray | None = field(repr=False)
    units: str
    protocol: TaskProtocol
    dataset: TactileDataset = field(repr=False)

    def get_X_and_y(self) -> tuple[np.ndarray, np.ndarray]:
        return self.X, self.y

    def splits(self, split: str | None = None, repeats: int | None = None) -> Iterator:
        """The protocol's splits (:meth:`TaskProtocol.splits`)."""
        return self.protocol.splits(split, repeats)


def load(
    task_id: str,
    *,
    quick: bool = False,
    data: str | Path | None = None,
    store: str | Path | None = None,
    seed: int = 0,
    log: Callable[[str], None] | None = None,
) -> TaskData:
    """The data set and protocol of ``task_id`` (a simulated task simulates its slides, or
    reads them from the slide cache; ``data``: the real data set's folder for ``*-real``
    tasks; ``store``: a store made by ``sim-tactile generate``). ``seed`` seeds the splits as
    ``run --seed`` does."""
    spec = use_task(task_id)
    if spec.parts:
        raise ConfigError(f"task {task_id} is a suite of {', '.join(spec.parts)}; load one of them")
    seed = integer("seed", seed, 0, None)
    task = load_task(
        spec,
        quick=quick,
        data=data,
        classifiers=None,
        seed=seed,
        log=log or _quiet,
        store=store,
    )
    ds = task.ds
    settings = spec.settings(quick)
    split = settings.split or spec.split
    names = tuple(dict.fromkeys([split, *(spec.split_for(r, quick) for r in spec.all_runs())]))
    protocol = TaskProtocol(
        task=spec.id,
        split=split,
        repeats=settings.repeats,
        seed=seed,
        time_points_s=tuple(settings.time_points_s),
        encode_once=spec.encode_once,
        split_names=names,
        labels=np.asarray(ds.labels).copy(),
    )
    return TaskData(
        task=spec.id,
        X=ds.data,
        y=np.asarray(ds.labels, dtype=np.int64),
        class_names=tuple(ds.class_names),
        channel_names=tuple(ds.channel_names),
        rate_hz=float(ds.rate_hz),
        channel_positions_m=None if ds.taxel_positions is None else np.asarray(ds.taxel_positions),
        units=ds.units,
        protocol=protocol,
        dataset=ds,
    )


def evaluate(
    task_id: str,
    methods: Mapping[str, Any],
    *,
    quick: bool = False,
    repeats: int | None = None,
    seed: int | None = None,
    out: str | Path | None = None,
    data: str | Path | None = None,
    store: str | Path | None = None,
    classifiers: str | list[str] | None = None,
    log: Callable[[str], None] | None = None,
    about: Mapping[str, Mapping[str, str]] | None = None,
) -> dict:
    """Score ``methods`` (name -> an estimator on the raw ``(samples, time, channels)``
    array, or an ``(encoder, estimator)`` pair: :mod:`.methods`) on ``task_id`` under its
    protocol, beside its built-in rows (``classifiers``: which of them; ``"none"``: only the
    user's), and return the report as ``run`` makes it. With ``out`` the report and its
    figures are written there, as ``run --out`` writes them; without, into a temporary
    folder that is removed. ``seed``: the splits' and models' seed; None, as ``run``
    without ``--seed``: a configuration file's own seed (which its slides and store were
    made with), else 0.

    With ``out``, each row's result file (:mod:`.result_file`; ``report["result_files"]``)
    is written into ``out/results``, for ``sim-tactile check`` and the leaderboard;
    ``about`` gives a method's ``version`` (or commit) and ``link`` for its file, by name.
    A method ``("task", estimator)`` (:data:`~.methods.TASK_ENCODER`) reads the task's own
    encoding: its file stands in the closed track."""
    if not methods:
        raise ConfigError("methods is empty; give name -> estimator or (encoder, estimator)")
    import tempfile

    kw = dict(quick=quick, data=data, classifiers=classifiers, repeats=repeats, seed=seed)
    kw.update(log=log or _quiet, store=store, methods=methods, about=_about(about, methods))
    if out is not None:
        return run_task(task_id, out, **kw)
    with tempfile.TemporaryDirectory(prefix="sim-tactile-evaluate-") as tmp:
        report = run_task(task_id, Path(tmp) / "report", **kw)
        report["figures"] = []  # they were in the removed folder
        report["result_files"] = []
        return report


def _about(about, methods) -> dict | None:
    """``about`` checked: method name -> ``{version, link}`` (strings)."""
    if about is None:
        return None
    if not isinstance(about, Mapping):
        raise ConfigError(f"about must map a method's name to {{version, link}}, got {about!r}")
    out = {}
    for name, info in about.items():
        if name not in methods:
            raise ConfigError(
                f"about names {name!r}, which is not a method; valid: {list(methods)}"
            )
        if not isinstance(info, Mapping) or set(info) - {"version", "link"}:
            raise ConfigError(
                f"about[{name!r}] = {info!r}; valid: a mapping with 'version' and 'link'"
            )
        out[name] = {k: str(v) for k, v in info.items() if v is not None}
    return out
