"""Frozen record types passed between the stages, in SI units.

- :class:`Recording` is one simulated (or measured) slide: a (time x taxel) array with its
  times, the taxel positions and full metadata. It saves to and loads from ``.npz`` without
  loss and without pickle (metadata is stored as JSON text).
- :class:`TactileDataset` is a labelled set of equally long recordings, the classifiers' input.
- :class:`SpikeTrains` is one encoded sample, passed from the encoders to spike features,
  distances and classifiers. A single spike train is a sorted 1-D ``float64`` array of spike
  times in seconds; a sample is one such array per channel plus the observation window
  ``[t_start, t_end]`` (s) and the channel names; an encoded data set is a plain
  ``list[SpikeTrains]``, one entry per sample.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._validate import finite, finite_array
from .errors import ConfigError

#: Keys every Recording .npz holds.
NPZ_KEYS = ("data", "times", "taxels", "meta_json")


class _NotJsonShaped(Exception):
    """Raised inside :func:`json_copy` where a value is not already what JSON reads back."""


def json_copy(obj):
    """A copy of ``obj`` as a JSON round trip gives it (``json.loads(json.dumps(obj))``):
    dicts and lists copied, the rest as is, where ``obj`` is already JSON-shaped (dicts with
    ``str`` keys, lists, ``str``, ``int``, ``float``, ``bool`` and None, each of exactly that
    type: a round trip gives such data back equal and of the same types), else by the round
    trip itself, which turns tuples into lists and keys into strings, and refuses what is
    not JSON data (TypeError, ValueError). A simulated slide's metadata is JSON-shaped
    already, its pad's path and force a sample each: the round trip took 0.36 ms a slide, a
    twentieth of an L0 slide."""
    try:
        return _json_copy(obj)
    except (_NotJsonShaped, RecursionError):
        return json.loads(json.dumps(obj))


_SCALARS = (str, int, float, bool, type(None))


def _json_copy(obj):
    t = type(obj)
    if t is dict:
        out = {}
        for k, v in obj.items():
            if type(k) is not str:
                raise _NotJsonShaped
            out[k] = _json_copy(v)
        return out
    if t is list:
        if all(type(v) is float for v in obj):  # a series: the common case, copied at once
            return obj.copy()
        return [_json_copy(v) for v in obj]
    if t in _SCALARS:
        return obj
    raise _NotJsonShaped


@dataclass(frozen=True)
class Recording:
    """One slide.

    data: (T, N) float32, the transducer output per taxel (``units``; N for ideal loads).
    times: (T,) float64 [s], sample times (the centre of each averaging window).
    taxels: (N, 3) float64 [m], taxel centres in the pad frame (x along the slide, z out
    of the skin; a taxel under the surface has z < 0).
    units: unit of ``data`` (e.g. "N").
    meta: JSON-able metadata: configuration, versions, seed, fidelity, timings, warnings.
    """

    data: np.ndarray
    times: np.ndarray
    taxels: np.ndarray
    units: str = "N"
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        data = np.asarray(self.data, dtype=np.float32)
        times = np.asarray(self.times, dtype=np.float64)
        taxels = np.asarray(self.taxels, dtype=np.float64)
        if data.ndim != 2 or times.shape != (data.shape[0],) or taxels.shape != (data.shape[1], 3):
            raise ConfigError(
                f"recording shapes do not agree: data {data.shape}, times {times.shape}, "
                f"taxels {taxels.shape}; valid: (T, N), (T,), (N, 3)"
            )
        try:  # metadata is JSON data; normalise it (tuples -> lists) so a round trip is exact
            object.__setattr__(self, "meta", json_copy(self.meta))
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"recording metadata must be JSON data: {exc}") from None
        for name, arr in (("data", data), ("times", times), ("taxels", taxels)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def rate_hz(self) -> float:
        return float(
            self.meta.get(
                "rate_hz", 1.0 / np.median(np.diff(self.times)) if len(self.times) > 1 else 0.0
            )
        )

    @property
    def n_taxels(self) -> int:
        return int(self.data.shape[1])

    def to_npz(self) -> bytes:
        """The recording as the bytes of an .npz with ``data``, ``times``, ``taxels`` and
        ``meta_json`` (what :meth:`save` writes and :meth:`load` reads): a function of the
        recording alone (no time stamp inside, :func:`~sim_tactile.cache.npz_bytes`)."""
        from .cache import npz_bytes

        meta = dict(self.meta, units=self.units)
        return npz_bytes(
            {
                "data": self.data,
                "times": self.times,
                "taxels": self.taxels,
                "meta_json": np.array(json.dumps(meta, sort_keys=True)),
            }
        )

    def save(self, path: str | Path) -> Path:
        """Write :meth:`to_npz` to ``path`` (atomically)."""
        from .cache import atomic_write

        path = Path(path)
        atomic_write(path, self.to_npz())
        return path

    @classmethod
    def load(cls, path: str | Path) -> Recording:
        """Read an .npz written by :meth:`save` (no pickle)."""
        path = Path(path)
        if not path.is_file():
            raise ConfigError(f"recording file {str(path)!r} does not exist")
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in NPZ_KEYS if k not in z.files]
            if missing:
                raise ConfigError(f"{path} is not a sim_tactile recording: missing {missing}")
            meta = json.loads(str(z["meta_json"]))
            return cls(z["data"], z["times"], z["taxels"], units=meta.pop("units", "N"), meta=meta)


@dataclass(frozen=True, eq=False)
class TactileDataset:
    """A labelled set of equally long recordings: the input of every classifier and protocol.

    Real data (the loaders in :mod:`sim_tactile.datasets`) and simulated slides
    (:meth:`from_recordings`, what a task's slide set returns) take this same form, so nothing
    downstream can tell them apart.

    data: ``(samples, time, channels)`` float32, sensor output (``units``).
    labels: ``(samples,)`` int64 class indices ``0 .. len(class_names) - 1``.
    rate_hz: sampling rate [Hz]; sample ``n`` is at ``n / rate_hz`` s from the window start.
    channel_names: one name per channel.
    class_names: one name per class.
    taxel_positions: ``(channels, 3)`` [m] in the pad frame, or None when unknown.
    units: unit of ``data``.
    meta: JSON-able metadata (source, window, layout, notes).
    """

    data: np.ndarray
    labels: np.ndarray
    rate_hz: float
    channel_names: tuple[str, ...]
    class_names: tuple[str, ...]
    taxel_positions: np.ndarray | None = None
    units: str = ""
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        data = np.asarray(self.data, dtype=np.float32)
        labels = np.asarray(self.labels)
        if data.ndim != 3 or 0 in data.shape:
            raise ConfigError(
                f"dataset data must have shape (samples, time, channels), got {data.shape}"
            )
        if labels.ndim != 1 or labels.shape[0] != data.shape[0]:
            raise ConfigError(
                f"dataset has {data.shape[0]} samples but labels of shape {labels.shape}; "
                f"valid: ({data.shape[0]},)"
            )
        if labels.dtype.kind not in "iu":
            raise ConfigError(f"dataset labels must be integers, got dtype {labels.dtype}")
        n_cls = len(self.class_names)
        if labels.min() < 0 or labels.max() >= n_cls:
            raise ConfigError(
                f"dataset labels must lie in [0, {n_cls - 1}] (one per class name), got "
                f"[{labels.min()}, {labels.max()}]"
            )
        if len(self.channel_names) != data.shape[2]:
            raise ConfigError(
                f"dataset has {data.shape[2]} channels but {len(self.channel_names)} channel names"
            )
        finite_array("dataset data", data)
        if not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ConfigError(f"dataset rate_hz = {self.rate_hz} must be a positive number [Hz]")
        pos = self.taxel_positions
        if pos is not None:
            pos = np.asarray(pos, dtype=np.float64)
            if pos.shape != (data.shape[2], 3):
                raise ConfigError(
                    f"taxel_positions must have shape ({data.shape[2]}, 3), got {pos.shape}"
                )
            pos.setflags(write=False)
        labels = labels.astype(np.int64)
        for arr in (data, labels):
            arr.setflags(write=False)
        object.__setattr__(self, "data", data)
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "taxel_positions", pos)
        object.__setattr__(self, "rate_hz", float(self.rate_hz))
        object.__setattr__(self, "channel_names", tuple(str(c) for c in self.channel_names))
        object.__setattr__(self, "class_names", tuple(str(c) for c in self.class_names))

    @property
    def n_samples(self) -> int:
        return int(self.data.shape[0])

    @property
    def n_time(self) -> int:
        return int(self.data.shape[1])

    @property
    def n_channels(self) -> int:
        return int(self.data.shape[2])

    @property
    def duration_s(self) -> float:
        """Length of each recording [s]."""
        return self.n_time / self.rate_hz

    def class_counts(self) -> np.ndarray:
        """Samples per class, shape ``(classes,)``."""
        return np.bincount(self.labels, minlength=len(self.class_names))

    def subset(self, index: np.ndarray) -> TactileDataset:
        """The samples at ``index`` (integer indices or a boolean mask)."""
        idx = np.asarray(index)
        return TactileDataset(
            self.data[idx],
            self.labels[idx],
            self.rate_hz,
            self.channel_names,
            self.class_names,
            self.taxel_positions,
            self.units,
            dict(self.meta),
        )

    def describe(self) -> dict:
        """JSON-able summary (no arrays)."""
        return {
            "samples": self.n_samples,
            "time_steps": self.n_time,
            "channels": self.n_channels,
            "classes": len(self.class_names),
            "rate_hz": self.rate_hz,
            "duration_s": self.duration_s,
            "units": self.units,
            "per_class": self.class_counts().tolist(),
            **{k: v for k, v in self.meta.items() if isinstance(v, str | int | float | list)},
        }

    @classmethod
    def from_recordings(
        cls,
        recordings: list[Recording],
        labels: object,
        class_names: tuple[str, ...] | list[str],
        *,
        meta: dict | None = None,
    ) -> TactileDataset:
        """Stack simulated (or measured) :class:`Recording` s of one length and layout."""
        if not recordings:
            raise ConfigError("from_recordings needs at least one recording")
        first = recordings[0]
        for k, r in enumerate(recordings):
            if r.data.shape != first.data.shape:
                raise ConfigError(
                    f"recording {k} has shape {r.data.shape}, recording 0 has "
                    f"{first.data.shape}; crop them to one length first"
                )
        names = first.meta.get("channel_names") or [f"t{i}" for i in range(first.n_taxels)]
        return cls(
            np.stack([r.data for r in recordings]),
            np.asarray(labels),
            first.rate_hz,
            tuple(names),
            tuple(class_names),
            first.taxels,
            first.units,
            dict(meta or {}),
        )


# ------------------------------------------------------------------------------ spike trains
def as_spike_times(
    times: object,
    name: str = "spike train",
    *,
    t_start: float | None = None,
    t_end: float | None = None,
) -> np.ndarray:
    """Return ``times`` as a contiguous 1-D float64 array after checking it.

    Raises :class:`ConfigError` when the array is not 1-D, holds NaN or infinite values, is not
    sorted (non-decreasing), or has spikes outside ``[t_start, t_end]`` when these are given.
    """
    arr = np.ascontiguousarray(np.asarray(times, dtype=np.float64))
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ConfigError(f"{name} must be a 1-D array of spike times [s], got shape {arr.shape}")
    if arr.size:
        if not np.all(np.isfinite(arr)):
            bad = arr[~np.isfinite(arr)][0]
            raise ConfigError(f"{name} must hold finite spike times [s], got {bad}")
        if np.any(np.diff(arr) < 0):
            raise ConfigError(f"{name} must be sorted in time (non-decreasing); sort it first")
        if t_start is not None and arr[0] < t_start:
            raise ConfigError(
                f"{name} has a spike at {arr[0]:g} s before t_start = {t_start:g} s; "
                f"valid: spikes in [t_start, t_end]"
            )
        if t_end is not None and arr[-1] > t_end:
            raise ConfigError(
                f"{name} has a spike at {arr[-1]:g} s after t_end = {t_end:g} s; "
                f"valid: spikes in [t_start, t_end]"
            )
    return arr


def check_window(t_start: float, t_end: float) -> tuple[float, float]:
    """Check an observation window and return it as floats (s)."""
    t0 = finite("t_start", t_start)
    t1 = finite("t_end", t_end)
    if not t1 > t0:
        raise ConfigError(f"t_end = {t1:g} s must be greater than t_start = {t0:g} s")
    return t0, t1


@dataclass(frozen=True, eq=False)
class SpikeTrains:
    """Spike trains of one sample: one sorted float64 array of times [s] per channel.

    Attributes:
        times: tuple of ``n_channels`` read-only 1-D arrays, spike times in seconds, each
            sorted and inside ``[t_start, t_end]``.
        t_start: start of the observation window [s].
        t_end: end of the observation window [s] (> ``t_start``).
        channel_names: one name per channel.
    """

    times: tuple[np.ndarray, ...]
    t_start: float
    t_end: float
    channel_names: tuple[str, ...]

    def __post_init__(self) -> None:
        t0, t1 = check_window(self.t_start, self.t_end)
        if len(self.channel_names) != len(self.times):
            raise ConfigError(
                f"channel_names has {len(self.channel_names)} entries but there are "
                f"{len(self.times)} channels"
            )
        checked = []
        for k, tr in enumerate(self.times):
            arr = as_spike_times(tr, f"channel {k} ({self.channel_names[k]})", t_start=t0, t_end=t1)
            arr = arr.copy() if arr.flags.writeable else arr
            arr.flags.writeable = False
            checked.append(arr)
        object.__setattr__(self, "times", tuple(checked))
        object.__setattr__(self, "t_start", t0)
        object.__setattr__(self, "t_end", t1)
        object.__setattr__(self, "channel_names", tuple(str(c) for c in self.channel_names))

    @classmethod
    def from_lists(
        cls,
        times: Sequence[object],
        t_start: float,
        t_end: float,
        channel_names: Sequence[str] | None = None,
    ) -> SpikeTrains:
        """Build from any sequence of per-channel spike-time sequences [s]."""
        names = (
            tuple(f"ch{k}" for k in range(len(times)))
            if channel_names is None
            else tuple(channel_names)
        )
        return cls(tuple(np.asarray(t, dtype=np.float64) for t in times), t_start, t_end, names)

    @property
    def n_channels(self) -> int:
        return len(self.times)

    @property
    def duration_s(self) -> float:
        return self.t_end - self.t_start

    def counts(self) -> np.ndarray:
        """Spike count per channel, shape ``(n_channels,)``, int64."""
        return np.array([t.size for t in self.times], dtype=np.int64)

    def __len__(self) -> int:
        return len(self.times)

    def __getitem__(self, k: int) -> np.ndarray:
        return self.times[k]

    def __repr__(self) -> str:
        return (
            f"SpikeTrains(n_channels={self.n_channels}, window=[{self.t_start:g}, "
            f"{self.t_end:g}] s, spikes={int(self.counts().sum())})"
        )


__all__ = [
    "Recording",
    "SpikeTrains",
    "TactileDataset",
    "as_spike_times",
]
