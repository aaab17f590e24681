"""Frozen record types passed between the stages, in SI units.

:class:`Recording` is one simulated (or measured) slide: a (time x taxel) array with its
times, the taxel positions and full metadata. It saves to and loads from ``.npz`` without
loss and without pickle (metadata is stored as JSON text).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._validate import finite_array
from .errors import ConfigError

#: Keys every Recording .npz holds.
NPZ_KEYS = ("data", "times", "taxels", "meta_json")


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
            object.__setattr__(self, "meta", json.loads(json.dumps(self.meta)))
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

    def save(self, path: str | Path) -> Path:
        """Write an .npz (atomically) with ``data``, ``times``, ``taxels`` and ``meta_json``."""
        import io

        from .cache import atomic_write

        buf = io.BytesIO()
        meta = dict(self.meta, units=self.units)
        np.savez(
            buf,
            data=self.data,
            times=self.times,
            taxels=self.taxels,
            meta_json=np.array(json.dumps(meta, sort_keys=True)),
        )
        path = Path(path)
        atomic_write(path, buf.getvalue())
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
    (:meth:`from_recordings`) take this same form, so nothing downstream can tell them apart.

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
