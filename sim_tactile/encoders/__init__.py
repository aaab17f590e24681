"""Neuromorphic encoders: sampled sensor signals -> spike trains.

- Threshold encoding with K thresholds -> 2K + 1 spike channels per input (seed paper 000).
- Izhikevich neurons (presets RS = SA, FS = RA, any a, b, c, d) with an accurate rk4 scheme
  and the papers' 1 ms schemes (seed papers 001-003).
- Leaky and adaptive leaky integrate-and-fire neurons, integrated exactly between events.
- scikit-learn transformers over arrays of shape (samples, time, channels) that return
  ``list[SpikeTrains]``.
"""

from __future__ import annotations

from ..errors import NeuronStepWarning
from .izhikevich import izhikevich_spike_times, simulate_izhikevich
from .lif import simulate_lif
from .neurons import (
    IZHIKEVICH_PRESETS,
    IzhikevichParams,
    LIFParams,
    alif_params,
    izhikevich_preset,
)
from .threshold import threshold_encode
from .transformers import IzhikevichEncoder, LIFEncoder, ThresholdEncoder

__all__ = [
    "IZHIKEVICH_PRESETS",
    "IzhikevichEncoder",
    "IzhikevichParams",
    "LIFEncoder",
    "LIFParams",
    "NeuronStepWarning",
    "ThresholdEncoder",
    "alif_params",
    "izhikevich_preset",
    "izhikevich_spike_times",
    "simulate_izhikevich",
    "simulate_lif",
    "threshold_encode",
]
