"""Spikes as Tonic events: ``(x, y, t, p)`` structured arrays on a ``sensor_size`` ``(W, H, P)``.

Any encoder's output (:class:`~sim_tactile.records.SpikeTrains`: the threshold, Izhikevich and
LIF encoders, or a user's own) becomes events: channel ``c`` sits at the address the layout
gives it (:mod:`.layout`: a grid keeps its x and y; a layout without one puts the channel on
x), train ``k`` of its ``K`` goes to the polarity, and a spike at ``t`` seconds from the
window's start is an event at ``round(t * 1e6)`` microseconds (Tonic's unit). Events are
sorted by time, then x, y and p.

Back again, events give the same spike trains: exactly for spikes on the microsecond grid
(an encoder on the sample grid: the threshold encoder at any rate dividing 1 MHz, whose times
``n / rate`` come back as ``(n * 1e6 / rate) / 1e6``, the same float), and to within 0.5 us
for spike times between samples (the neuron encoders' crossing times).

:class:`TactileEvents` is a data set of ``(events, target)`` over a task's data, a store or
the real recordings, so that ``tonic.transforms`` (``ToFrame``, ``Denoise``, ``TimeJitter``)
and ``tonic.collation.PadTensors`` work on it as on Tonic's own ``STMNIST`` (a taxel grid) or
``SHD`` (channels without a grid).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..errors import ConfigError, require
from ..records import SpikeTrains
from ._source import Source
from .layout import EventLayout, TrainMap, dataset_events, train_map

#: Tonic's event fields, with an integer polarity (an encoder may give more than two trains
#: per channel).
EVENT_DTYPE = np.dtype([("x", np.int16), ("y", np.int16), ("t", np.int64), ("p", np.int16)])
#: Tonic's time unit: microseconds per second.
US_PER_S = 1_000_000


def _tonic():
    return require("tonic", "tonic")


class EventCodec:
    """Spike trains of one encoder on one layout <-> Tonic events.

    layout: where each input channel sits; tmap: which input channel and train each output
    spike train is; names: the output trains' names (a :class:`SpikeTrains`' channel names).
    """

    def __init__(self, layout: EventLayout, tmap: TrainMap, names: Sequence[str]) -> None:
        if tmap.channel.size != len(names):
            raise ConfigError(f"{len(names)} train names for {tmap.channel.size} trains")
        if tmap.channel.size and int(tmap.channel.max()) >= layout.n_channels:
            raise ConfigError(
                f"the trains name input channel {int(tmap.channel.max())}; the layout has "
                f"{layout.n_channels}"
            )
        self.layout, self.tmap, self.names = layout, tmap, tuple(str(n) for n in names)
        k = tmap.per_channel
        ch = tmap.channel
        self._x = layout.x[ch].astype(np.int16)
        self._y = layout.y[ch].astype(np.int16)
        self._p = (layout.layer[ch] * k + tmap.kind).astype(np.int16)
        # output train of each address (layer * K + k, y, x)
        table = np.full(self.sensor_size[::-1], -1, np.int64)
        table[self._p, self._y, self._x] = np.arange(ch.size)
        self._train_at = table

    @property
    def sensor_size(self) -> tuple[int, int, int]:
        """Tonic's ``(W, H, P)``."""
        return self.layout.sensor_size(self.tmap.per_channel)

    def to_events(self, trains: SpikeTrains) -> np.ndarray:
        """The spikes of ``trains`` as events (``EVENT_DTYPE``), sorted by t, x, y, p."""
        if not isinstance(trains, SpikeTrains):
            raise ConfigError(f"trains must be a SpikeTrains, got {type(trains).__name__}")
        if trains.channel_names != self.names:
            raise ConfigError(
                f"the spike trains' channels {list(trains.channel_names[:4])}... are not this "
                f"codec's {list(self.names[:4])}...; make the codec from the same encoder"
            )
        counts = trains.counts()
        which = np.repeat(np.arange(len(counts)), counts)
        t = np.concatenate(trains.times) if len(counts) else np.empty(0)
        t_us = np.rint((t - trains.t_start) * US_PER_S).astype(np.int64)
        x, y, p = self._x[which], self._y[which], self._p[which]
        order = np.lexsort((p, y, x, t_us))
        tonic = _tonic()
        return tonic.io.make_structured_array(
            x[order], y[order], t_us[order], p[order], dtype=EVENT_DTYPE
        )

    def to_spike_trains(
        self, events: np.ndarray, *, t_end_s: float, t_start_s: float = 0.0
    ) -> SpikeTrains:
        """Events back as :class:`SpikeTrains` on the window ``[t_start_s, t_end_s]``: each
        event's time ``t_start_s + t / 1e6`` on the train at its address."""
        ev = np.asarray(events)
        if ev.dtype.names is None or not {"x", "y", "t", "p"} <= set(ev.dtype.names):
            raise ConfigError(f"events must have fields x, y, t, p; got dtype {ev.dtype}")
        w, h, p = self.sensor_size
        bad = (ev["x"] < 0) | (ev["x"] >= w) | (ev["y"] < 0) | (ev["y"] >= h)
        bad |= (ev["p"] < 0) | (ev["p"] >= p)
        if bad.any():
            k = int(np.argmax(bad))
            raise ConfigError(
                f"event {k} at (x={ev['x'][k]}, y={ev['y'][k]}, p={ev['p'][k]}) lies outside "
                f"the sensor (W, H, P) = {self.sensor_size}"
            )
        train = self._train_at[ev["p"], ev["y"], ev["x"]]
        if (train < 0).any():
            raise ConfigError("events at an address where no taxel sits; valid: this codec's")
        t = t_start_s + ev["t"].astype(np.float64) / US_PER_S
        order = np.lexsort((t, train))
        train, t = train[order], t[order]
        cuts = np.searchsorted(train, np.arange(len(self.names) + 1))
        times = tuple(t[cuts[c] : cuts[c + 1]] for c in range(len(self.names)))
        return SpikeTrains(times, t_start_s, t_end_s, self.names)


def codec_for(
    trains: SpikeTrains,
    input_names: Sequence[str],
    layout: EventLayout,
    *,
    order: str = "channel",
) -> EventCodec:
    """The codec of an encoder whose output looks like ``trains`` (:func:`.train_map`)."""
    return EventCodec(
        layout, train_map(trains.channel_names, input_names, order=order), trains.channel_names
    )


def _fitted(encoder: Any, source: Source) -> Any:
    """``encoder`` itself when fitted; else a clone fitted on every sample of ``source``
    (its unset ``rate_hz`` parameters get the data's rate)."""
    import copy

    from sklearn.exceptions import NotFittedError
    from sklearn.utils.validation import check_is_fitted

    from ..tasks.methods import prepared

    if not hasattr(encoder, "get_params"):  # duck-typed: fitted when it holds a learned_ state
        if any(k.endswith("_") and not k.startswith("_") for k in vars(encoder)):
            return encoder
        return copy.deepcopy(encoder).fit(source.all_data())
    try:
        check_is_fitted(encoder)
        return encoder
    except NotFittedError:
        return prepared(encoder, None, source.rate_hz).fit(source.all_data())


def task_encoder(source: Source) -> Any | None:
    """The task's own encoding as one Pipeline (None without a task)."""
    if source.task is None:
        return None
    from sklearn.pipeline import Pipeline

    from ..records import TactileDataset
    from ..tasks import get_task

    spec = get_task(source.task)
    probe = TactileDataset(
        np.zeros((1, 1, len(source.channel_names)), np.float32),
        np.zeros(1, np.int64),
        source.rate_hz,
        source.channel_names,
        source.class_names,
    )
    return Pipeline(spec.encoder(spec.context(probe, source.quick)))


class Encoded:
    """A source's samples encoded one at a time by a fitted encoder (spike trains)."""

    def __init__(self, source: Source, encoder: Any, what: str) -> None:
        enc = encoder if encoder is not None else task_encoder(source)
        if enc is None:
            raise ConfigError(
                f"{what} needs spike trains, but this data set holds raw sensor streams "
                f"({source.units or 'no unit'}) and names no task whose encoding could make "
                "them; valid: pass encoder=... (e.g. sim_tactile.encoders.ThresholdEncoder())"
            )
        self.source = source
        self.encoder = _fitted(enc, source)

    def __call__(self, i: int) -> SpikeTrains:
        out = self.encoder.transform(self.source.sample(i)[None])
        if len(out) != 1 or not isinstance(out[0], SpikeTrains):
            raise ConfigError(
                f"the encoder {type(self.encoder).__name__} returned "
                f"{type(out[0] if len(out) else out).__name__}; valid: one SpikeTrains per "
                "sample (an encoder of sim_tactile.encoders, or one like them)"
            )
        return out[0]


class TactileEvents:
    """``(events, target)`` pairs of a task's data, a store or a data set, as a Tonic data set.

    Parameters:
        data: :func:`sim_tactile.tasks.load`'s data, a store (its path, or
            :func:`sim_tactile.datasets.open`'s), or a TactileDataset (the real recordings).
        encoder: a transformer from ``(samples, time, channels)`` to ``list[SpikeTrains]``,
            fitted or not (then fitted on all samples); default: the task's own encoding.
            A data set without a task needs one.
        split, repeat: ``"train"`` / ``"test"`` of the task's split number ``repeat`` (as
            :meth:`~sim_tactile.tasks.TaskProtocol.splits` gives them); None: all samples.
        layout: an :class:`~.layout.EventLayout` (default: from the data set's sensor).
        order: how trains lie when their names do not say (:func:`.train_map`).
        transform, target_transform: applied to the events and the target (Tonic's).
        part: a suite's part, for a suite's store.

    Attributes: ``sensor_size`` (W, H, P), ``ordering`` ``"xytp"``, ``dtype``, ``classes``.
    """

    ordering = "xytp"
    dtype = EVENT_DTYPE

    def __init__(
        self,
        data: Any,
        *,
        encoder: Any = None,
        split: str | None = None,
        repeat: int = 0,
        layout: EventLayout | None = None,
        order: str = "channel",
        transform: Callable | None = None,
        target_transform: Callable | None = None,
        part: str | None = None,
    ) -> None:
        _tonic()
        self.source = Source(data, part=part)
        self.indices = self.source.split_indices(split, repeat)
        self.encode = Encoded(self.source, encoder, "events")
        n = len(self.source.channel_names)
        self.layout = layout or dataset_events(self.source.meta, n)
        if self.layout.n_channels != n:
            raise ConfigError(f"layout has {self.layout.n_channels} channels, the data {n}")
        first = self.encode(int(self.indices[0]) if len(self.indices) else 0)
        self.codec = codec_for(first, self.source.channel_names, self.layout, order=order)
        self.transform, self.target_transform = transform, target_transform
        self.classes = list(self.source.class_names)

    @property
    def sensor_size(self) -> tuple[int, int, int]:
        return self.codec.sensor_size

    def __len__(self) -> int:
        return int(self.indices.size)

    def spike_trains(self, i: int) -> SpikeTrains:
        """Item ``i``'s spike trains, as the encoder gives them."""
        return self.encode(int(self.indices[i]))

    def targets(self) -> np.ndarray:
        return self.source.labels[self.indices]

    def __getitem__(self, i: int) -> tuple[np.ndarray, int]:
        if not -len(self) <= int(i) < len(self):
            raise IndexError(f"index {i} out of range; valid: [{-len(self)}, {len(self) - 1}]")
        events = self.codec.to_events(self.spike_trains(int(i) % len(self)))
        target = int(self.source.labels[self.indices[int(i)]])
        if self.transform is not None:
            events = self.transform(events)
        if self.target_transform is not None:
            target = self.target_transform(target)
        return events, target
