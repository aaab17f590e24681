"""Encodings: the pipeline steps from a task's sampled signals to spike trains, as
``context -> [(name, transformer), ...]`` (the context gives the sampling rate). The
threshold encodings of seed paper 000 live here; the tasks define their neuron encodings
with the same shape. Each step has a name, so a sweep changes a parameter through
scikit-learn's ``Pipeline.set_params(encode__gain=...)``.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from .scaling import RangeScaler, SampleStandardizer
from .transformers import ThresholdEncoder

Steps = list[tuple[str, Any]]


class EncodingContext(Protocol):
    """What an encoding needs to know of the data: its sampling rate [Hz]."""

    rate_hz: float


#: Thresholds (in standard deviations of each sample's channel) of :func:`threshold_encoding`.
THRESHOLDS_SD = (-0.5, 0.5)
#: Percentiles of the training data that :func:`range_threshold_encoding` maps to 0 and K + 1.
RANGE_PCT = (1.0, 99.0)


def threshold_encoding(ctx: EncodingContext) -> Steps:
    """Threshold encoding of each slide's fluctuations (the default): each channel of each
    sample standardised over its own window, then K = 2 thresholds at -0.5 and +0.5 standard
    deviations (2K + 1 = 5 spike channels per input; see :mod:`sim_tactile.encoders.threshold`).
    The spikes carry how a signal moves, not its level."""
    return [
        ("standardize", SampleStandardizer()),
        ("encode", ThresholdEncoder(rate_hz=ctx.rate_hz, thresholds=np.array(THRESHOLDS_SD))),
    ]


def range_threshold_encoding(ctx: EncodingContext) -> Steps:
    """Threshold encoding against the training data's range: each channel scaled so that
    its 1st..99th percentile over the training set becomes [0, K + 1] = [0, 3], then the
    K = 2 thresholds at 1 and 2, as eq. 1 of seed paper 000 writes them. The spikes carry
    when a signal reaches which level of its channel's range."""
    return [
        ("scale", RangeScaler(*RANGE_PCT, span=3.0)),
        ("encode", ThresholdEncoder(rate_hz=ctx.rate_hz, thresholds=np.array([1.0, 2.0]))),
    ]
