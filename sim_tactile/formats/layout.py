"""Where a taxel's spikes land in an event stream: its ``x``, ``y`` and polarity ``p``.

Tonic's events carry a pixel address ``(x, y)`` and a polarity ``p`` on a sensor of size
``(W, H, P)``. A tactile layout takes one of two shapes there:

- a **grid** keeps its columns as ``x`` and its rows as ``y`` (``grid3x3`` 3 x 3, ``icub60``
  6 x 10, a sensor file's ``grid_shape``), as ``tonic.datasets.STMNIST`` does with its 10 x 10
  taxels; a layout of several layers that are each the same full lattice (``multilayer3x3x2``:
  two 3 x 3 layers) is one grid per layer, the layer going to the polarity axis;
- a layout **without a grid** (``biotac19``'s electrodes, ``pvdf2``'s two films, a data set
  whose positions are not known) puts the channel on ``x`` with ``H = 1``, as SHD does with
  its 700 channels.

An encoder's several spike trains per channel (the threshold encoder's ``2K + 1``, up / down /
max) go to the polarity: ``p = layer * K + k`` for train ``k`` of ``K``.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._validate import one_of
from ..errors import ConfigError, UnknownNameError

#: How output trains are laid out when their names do not say: ``channel`` (channel-major,
#: ``c * K + k``, the threshold encoder's order) or ``train`` (train-major, ``k * N + c``).
ORDERS = ("channel", "train")
_SUFFIX = re.compile(r"^(?P<base>.+):(?P<kind>[^:]+)$")


@dataclass(frozen=True)
class EventLayout:
    """The event address of every input channel.

    x, y, layer: ``(N,)`` int arrays, channel ``c``'s column, row and layer.
    width, height, layers: the grid's size (``height = 1`` and ``x = c`` without a grid).
    grid: whether the taxels form a grid (else the channel is ``x``).
    """

    x: np.ndarray
    y: np.ndarray
    layer: np.ndarray
    width: int
    height: int
    layers: int
    grid: bool

    @property
    def n_channels(self) -> int:
        return int(self.x.size)

    def sensor_size(self, trains_per_channel: int = 1) -> tuple[int, int, int]:
        """Tonic's ``(W, H, P)`` for ``trains_per_channel`` trains of every channel."""
        return (self.width, self.height, self.layers * int(trains_per_channel))

    def channel_at(self, x: np.ndarray, y: np.ndarray, layer: np.ndarray) -> np.ndarray:
        """The channel index of each address (``-1`` where no channel sits)."""
        table = np.full((self.layers, self.height, self.width), -1, np.int64)
        table[self.layer, self.y, self.x] = np.arange(self.n_channels)
        return table[layer, y, x]

    def describe(self) -> dict:
        return {
            "grid": self.grid,
            "width": self.width,
            "height": self.height,
            "layers": self.layers,
        }


def channel_layout(n_channels: int) -> EventLayout:
    """No grid: channel ``c`` at ``x = c`` (SHD's layout)."""
    c = np.arange(int(n_channels))
    zero = np.zeros_like(c)
    return EventLayout(c, zero, zero, int(n_channels), 1, 1, False)


def grid_of(rows: int, cols: int, n_channels: int) -> EventLayout:
    """A row-major grid ``(rows, cols)`` in channel order."""
    if rows * cols != n_channels:
        raise ConfigError(
            f"grid_shape ({rows}, {cols}) holds {rows * cols} taxels, the data {n_channels}; "
            f"valid: rows * cols = {n_channels}"
        )
    c = np.arange(n_channels)
    return EventLayout(c % cols, c // cols, np.zeros_like(c), cols, rows, 1, True)


def _lattice(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Column and row of each point when the points fill a lattice of at least 2 x 2."""
    xs = np.unique(np.round(xy[:, 0], 9))
    ys = np.unique(np.round(xy[:, 1], 9))
    if xs.size < 2 or ys.size < 2 or xs.size * ys.size != len(xy):
        return None
    col = np.searchsorted(xs, np.round(xy[:, 0], 9))
    row = np.searchsorted(ys, np.round(xy[:, 1], 9))
    if np.unique(row * xs.size + col).size != len(xy):
        return None
    return col, row


def layout_events(layout) -> EventLayout:
    """The event layout of a :class:`~sim_tactile.sensors.layouts.Layout`: its
    ``grid_shape``; else one grid per layer when every layer is the same full lattice of at
    least 2 x 2 taxels; else the channel as ``x``."""
    if layout.grid_shape is not None:
        return grid_of(*layout.grid_shape, layout.n)
    layers = np.unique(layout.layer)
    if layers.size > 1:
        cols = np.empty(layout.n, np.int64)
        rows = np.empty(layout.n, np.int64)
        shapes = set()
        for lay in layers:
            idx = np.flatnonzero(layout.layer == lay)
            found = _lattice(layout.positions[idx, :2])
            if found is None:
                return channel_layout(layout.n)
            cols[idx], rows[idx] = found
            shapes.add((int(found[0].max()) + 1, int(found[1].max()) + 1))
        if len(shapes) == 1:
            (w, h) = shapes.pop()
            layer = np.searchsorted(layers, layout.layer)
            return EventLayout(cols, rows, layer, w, h, int(layers.size), True)
    return channel_layout(layout.n)


def dataset_events(meta: dict, n_channels: int, sensor: str | None = None) -> EventLayout:
    """The event layout of a data set from its metadata: ``grid_shape`` when it records one,
    else its ``sensor`` (a named layout: :func:`layout_events`), else the channel as ``x``."""
    grid = meta.get("grid_shape")
    if grid:
        return grid_of(int(grid[0]), int(grid[1]), n_channels)
    name = sensor or meta.get("sensor")
    if isinstance(name, str):
        from ..sensors.layouts import get_layout

        try:
            layout = get_layout(name)
        except UnknownNameError:
            layout = None
        if layout is not None and layout.n == n_channels:
            return layout_events(layout)
    return channel_layout(n_channels)


@dataclass(frozen=True)
class TrainMap:
    """Which input channel and which of its ``K`` trains each output spike train is."""

    channel: np.ndarray  # (M,) input channel of output train m
    kind: np.ndarray  # (M,) index k of that train among its channel's K
    kinds: tuple[str, ...]  # the K names (``""`` when the encoder gives one train)

    @property
    def per_channel(self) -> int:
        return len(self.kinds)


def train_map(
    out_names: Sequence[str], in_names: Sequence[str], *, order: str = "channel"
) -> TrainMap:
    """How an encoder's ``M`` output trains relate to the ``N`` input channels.

    Names say it where they can: equal names (one train per channel, the neuron encoders),
    or ``"<input>:<kind>"`` (the threshold encoder's ``t0:up0``, ``t0:down0``, ``t0:max``).
    Otherwise ``M`` must be a multiple of ``N`` and ``order`` (:data:`ORDERS`) says how they
    are laid out."""
    out_names, in_names = [str(n) for n in out_names], [str(n) for n in in_names]
    m, n = len(out_names), len(in_names)
    if out_names == in_names:
        return TrainMap(np.arange(n), np.zeros(n, np.int64), ("",))
    index = {name: c for c, name in enumerate(in_names)}
    parsed = [_SUFFIX.match(name) for name in out_names]
    if all(p is not None and p["base"] in index for p in parsed):
        kinds = tuple(dict.fromkeys(p["kind"] for p in parsed))
        ch = np.array([index[p["base"]] for p in parsed], np.int64)
        kind = np.array([kinds.index(p["kind"]) for p in parsed], np.int64)
        pairs = ch * len(kinds) + kind
        if np.unique(pairs).size == m and m == n * len(kinds):
            return TrainMap(ch, kind, kinds)
    order = one_of("order", order, ORDERS)
    if m % n:
        raise ConfigError(
            f"the encoder gives {m} spike trains for {n} input channels and its channel names "
            f"do not say which is which; valid: a multiple of {n} trains, or names "
            "'<input>:<kind>'"
        )
    k = m // n
    idx = np.arange(m)
    ch, kind = (idx // k, idx % k) if order == "channel" else (idx % n, idx // n)
    return TrainMap(ch, kind, tuple(f"train{j}" for j in range(k)))
