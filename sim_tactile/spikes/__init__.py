"""Spike trains, spike features and spike-train distances.

- :class:`SpikeTrains`: the record of one encoded sample (one sorted float64 array of spike
  times [s] per channel, the window ``[t_start, t_end]`` and channel names). An encoded data set
  is ``list[SpikeTrains]``.
- :mod:`.distances`: Victor-Purpura, van Rossum, ISI, SPIKE, event synchronization and
  ``pairwise`` / ``cross`` matrices.
- :mod:`.multichannel`: distance matrices between multi-channel samples, and a scikit-learn
  transformer that feeds ``KNeighborsClassifier(metric="precomputed")``.
- :mod:`.features`: spike count, rates, ISI statistics and latency as feature matrices.
- :mod:`.plot`: raster plots (matplotlib, imported on use).
"""

from __future__ import annotations

from ..records import SpikeTrains, as_spike_times
from . import distances
from .features import FEATURES, SpikeFeatures, spike_features
from .multichannel import COMBINE, SpikeTrainDistances, cross_multichannel, pairwise_multichannel

__all__ = [
    "COMBINE",
    "FEATURES",
    "SpikeFeatures",
    "SpikeTrainDistances",
    "SpikeTrains",
    "as_spike_times",
    "cross_multichannel",
    "distances",
    "pairwise_multichannel",
    "spike_features",
]
