"""A PyTorch ``Dataset`` over a store, a task's data or any data set, raw or encoded.

:class:`TactileTorchDataset` reads a store lazily (one slide per item, checked against its
checksum, through the public reader), so a store larger than memory trains as it is read.
Item ``i`` depends on ``i`` alone: a ``DataLoader`` with worker processes (each opens the
store itself) yields the same samples, in the same order, as one process; with
``shuffle=True`` the order is the DataLoader's generator's, so seed that generator.

- raw: ``(x, target)``, ``x`` a ``(T, N)`` float32 tensor (the sensor's units);
- encoded (an ``encoder``, or ``encoded=True`` for the task's own encoding): ``x`` a
  ``(steps, M)`` float32 raster of 0 / 1 at ``dt_s`` (default: the sample period), the
  :class:`~sim_tactile.learn.snn.SNNClassifier`'s input;
- ``split="train"`` / ``"test"``: that side of the task's split ``repeat`` (the indices of
  :meth:`~sim_tactile.tasks.TaskProtocol.splits`), in increasing order;
- ``transform`` / ``target_transform``: callables applied to ``x`` and to the target of
  each item, as torchvision's and Tonic's data sets take them.

It is also ``sim_tactile.formats.TactileTorchDataset`` (imported when first named:
importing ``sim_tactile.formats`` does not import torch).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .._validate import positive
from ..errors import ConfigError, require
from ._source import Source
from .events import Encoded

torch = require("torch", "learn")


class TactileTorchDataset(torch.utils.data.Dataset):
    """``(x, target)`` items of a data set (see the module docstring).

    Parameters:
        data: a store (a path, or :func:`sim_tactile.datasets.open`'s), a task's data
            (:func:`sim_tactile.tasks.load`) or a TactileDataset.
        split, repeat: the side and repeat of the task's split; None: every sample.
        encoder: a transformer to ``list[SpikeTrains]`` (fitted, or fitted on all samples).
        encoded: True: the task's own encoding (when ``encoder`` is None).
        dt_s: the raster's step [s] for encoded items (default ``1 / rate_hz``).
        part: a suite's part, for a suite's store.
        transform: ``x -> x'``, applied to each item's tensor (None: as it is).
        target_transform: ``target -> target'``, applied to each item's label.

    Attributes: ``targets`` (the items' labels), ``indices`` (their sample numbers),
    ``classes``, ``channel_names``, ``rate_hz``.
    """

    def __init__(
        self,
        data: Any,
        *,
        split: str | None = None,
        repeat: int = 0,
        encoder: Any = None,
        encoded: bool = False,
        dt_s: float | None = None,
        part: str | None = None,
        transform: Callable[[Any], Any] | None = None,
        target_transform: Callable[[int], Any] | None = None,
    ) -> None:
        for name, fn in (("transform", transform), ("target_transform", target_transform)):
            if fn is not None and not callable(fn):
                raise ConfigError(
                    f"{name} = {fn!r} is not valid; valid: a callable (x -> x), or None"
                )
        self.transform, self.target_transform = transform, target_transform
        self.source = Source(data, part=part)
        self.indices = self.source.split_indices(split, repeat)
        self.targets = self.source.labels[self.indices].copy()
        self.classes = list(self.source.class_names)
        self.channel_names = tuple(self.source.channel_names)
        self.rate_hz = self.source.rate_hz
        self.encode = None
        if encoder is not None or encoded:
            self.encode = Encoded(self.source, encoder, "an encoded data set")
        self.dt_s = 1.0 / self.rate_hz if dt_s is None else positive("dt_s", dt_s, unit="s")

    def __len__(self) -> int:
        return int(self.indices.size)

    def _raster(self, i: int) -> np.ndarray:
        from ..learn.preprocess import SpikeRaster

        trains = [self.encode(i)]
        return SpikeRaster(dt_s=self.dt_s).fit(trains).transform(trains)[0]

    def __getitem__(self, i: int) -> tuple[Any, Any]:
        n = len(self)
        if not -n <= int(i) < n:
            raise IndexError(f"index {i} out of range; valid: [{-n}, {n - 1}]")
        k = int(self.indices[int(i)])
        x = self.source.sample(k) if self.encode is None else self._raster(k)
        x, target = torch.from_numpy(np.array(x, dtype=np.float32)), int(self.source.labels[k])
        if self.transform is not None:
            x = self.transform(x)
        if self.target_transform is not None:
            target = self.target_transform(target)
        return x, target
