"""One view of the data sets the bridges read: a task's data (:func:`sim_tactile.tasks.load`),
a store (read lazily, slide by slide, through :class:`~sim_tactile.datasets.SlideStore`), or
any :class:`~sim_tactile.records.TactileDataset` (the real recordings), with the task's
splits where the data set has a task."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .._validate import integer, one_of
from ..datasets import SlideStore, open_store
from ..errors import ConfigError
from ..records import TactileDataset
from ..tasks import TaskData, get_task
from ..tasks.splits import task_splits

#: The sides of a task's split a bridge can read.
SIDES = ("train", "test")


class Source:
    """A data set's samples and labels; ``sample(i)`` reads one sample ``(T_i, N)`` float32.

    A store is opened again in each process that reads it (a DataLoader's workers), so a
    :class:`Source` pickles as its path."""

    def __init__(self, data: Any, *, part: str | None = None) -> None:
        self.task: str | None = None
        self.quick = False
        self.seed = 0
        self._x: np.ndarray | None = None
        self._store: SlideStore | None = None
        self.store_path: Path | None = None
        self.part = part
        if isinstance(data, TaskData):
            ds = data.dataset
            self.task, self.seed = data.task, int(data.protocol.seed)
            self._split_rule = (data.protocol.split, data.protocol.seed)
            self._from_tactile(ds)
        elif isinstance(data, TactileDataset):
            self._split_rule = None
            self._from_tactile(data)
        elif isinstance(data, SlideStore | str | Path):
            st = data if isinstance(data, SlideStore) else open_store(data, part)
            self.store_path, self._store = st.path, st
            self.part = None  # st.path already names the part's group
            cfg = st.config
            self.task, self.quick = cfg.get("task"), bool(cfg.get("quick"))
            self.seed = int(cfg.get("seed") or 0)
            self._split_rule = None
            if self.task:
                spec = get_task(self.task)
                self._split_rule = (spec.settings(self.quick).split or spec.split, self.seed)
            self.labels = np.asarray(st.labels, np.int64)
            self.class_names, self.channel_names = st.class_names, st.channel_names
            self.rate_hz, self.units = st.rate_hz, st.units
            self.meta = dict(st.meta.get("dataset_meta") or {})
            self.lengths = np.asarray(st.lengths, np.int64)
        else:
            raise ConfigError(
                f"data = {type(data).__name__} is not a data set; valid: a task's data "
                "(sim_tactile.tasks.load), a store (a path or sim_tactile.datasets.open) or a "
                "TactileDataset"
            )

    def _from_tactile(self, ds: TactileDataset) -> None:
        self._x = ds.data
        self.labels = np.asarray(ds.labels, np.int64)
        self.class_names, self.channel_names = ds.class_names, ds.channel_names
        self.rate_hz, self.units, self.meta = ds.rate_hz, ds.units, dict(ds.meta)
        self.lengths = np.full(ds.n_samples, ds.n_time, np.int64)

    # ------------------------------------------------------------------ pickling
    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_store"] = None  # a worker opens the store itself
        return state

    @property
    def store(self) -> SlideStore | None:
        if self._store is None and self.store_path is not None:
            self._store = open_store(self.store_path)
        return self._store

    # ------------------------------------------------------------------ reading
    def __len__(self) -> int:
        return int(self.labels.size)

    @property
    def is_store(self) -> bool:
        return self.store_path is not None

    def sample(self, i: int) -> np.ndarray:
        """Sample ``i``: ``(T_i, N)`` float32 (a store checks the slide's checksum)."""
        if self._x is not None:
            return self._x[int(i)]
        return np.asarray(self.store[int(i)], np.float32)

    def all_data(self) -> np.ndarray:
        """Every sample, ``(samples, T, N)`` (a store's are read whole: one length)."""
        if self._x is not None:
            return self._x
        return self.store.to_tactile().data

    def split_indices(self, side: str | None, repeat: int = 0) -> np.ndarray:
        """The sample indices of ``side`` (``train`` / ``test``) of repeat ``repeat`` of the
        task's split (as :meth:`TaskProtocol.splits` gives them), or all samples (None)."""
        if side is None:
            return np.arange(len(self), dtype=np.int64)
        side = one_of("split", side, SIDES)
        repeat = integer("repeat", repeat, 0, None)
        if self._split_rule is None:
            raise ConfigError(
                f"split = {side!r}: this data set has no task, so no task split; valid: "
                "split=None (all samples), or load a task's data (sim_tactile.tasks.load) "
                "or a store generated for a task"
            )
        rule, seed = self._split_rule
        pair = task_splits(self.labels, rule, repeat + 1, seed)[repeat]
        return np.asarray(pair[SIDES.index(side)], np.int64)
