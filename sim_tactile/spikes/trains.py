"""The spike-train record passed from the encoders to features, distances and classifiers.

A single spike train is a sorted 1-D ``float64`` array of spike times in seconds. A
multi-channel recording of one sample is a :class:`SpikeTrains`: one such array per channel
plus the observation window ``[t_start, t_end]`` (s) and the channel names. An encoded data
set is a plain ``list[SpikeTrains]``, one entry per sample.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._validate import finite
from ..errors import ConfigError


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
