"""Helpers shared by the neuron encoders: input checks, zero-order hold, diagnostics."""

from __future__ import annotations

import math
import warnings

import numpy as np

from .._validate import finite_array, positive
from ..errors import ConfigError, NeuronStepWarning, PhysicsError


def check_current(current: object, name: str = "current") -> np.ndarray:
    """Return a C-contiguous float64 array; NaN or infinite values raise a ConfigError."""
    arr = np.ascontiguousarray(np.asarray(current, dtype=np.float64))
    return finite_array(name, arr, "replace or interpolate missing samples before encoding")


def sample_of_step(n_samples: int, rate_hz: float, dt_s: float) -> np.ndarray:
    """Zero-order hold: index of the input sample in force at the start of each neuron step.

    The recording covers ``n_samples / rate_hz`` seconds; it is simulated in
    ``ceil(duration / dt_s)`` steps (rounding away differences below 1e-9 of a step) and step
    ``k`` (starting at ``k * dt_s``) uses sample ``floor(k * dt_s * rate_hz)``.
    """
    rate_hz = positive("rate_hz", rate_hz, unit="Hz")
    dt_s = positive("dt_s", dt_s, unit="s")
    if n_samples < 1:
        raise ConfigError(f"the input has {n_samples} samples; at least 1 is needed")
    steps_f = n_samples / (rate_hz * dt_s)
    n_steps = max(1, math.ceil(steps_f - 1e-9))
    k = np.arange(n_steps, dtype=np.float64)
    idx = np.floor(k * (dt_s * rate_hz) + 1e-9).astype(np.int64)
    return np.minimum(idx, n_samples - 1)


def split(times: np.ndarray, counts: np.ndarray, scale: float) -> list[np.ndarray]:
    """Cut the kernel's flat spike-time output into one array per neuron, times * scale [s]."""
    edges = np.concatenate(([0], np.cumsum(counts)))
    return [times[edges[i] : edges[i + 1]] * scale for i in range(counts.size)]


def report(
    multi: np.ndarray,
    capped: np.ndarray,
    nonfinite: np.ndarray,
    *,
    model: str,
    dt_s: float,
    scheme: str,
    max_current: float,
    one_per_step: bool,
    max_per_step: int,
) -> None:
    """Turn kernel diagnostics into a PhysicsError (overflow) or NeuronStepWarning."""
    if nonfinite.any():
        raise PhysicsError(
            f"{model}: the state of {int(nonfinite.sum())} neuron(s) overflowed with input "
            f"up to {max_current:g}; the input is far beyond what the {scheme} step of "
            f"dt_s = {dt_s:g} s can integrate: scale it down or reduce dt_s"
        )
    if multi.any() or capped.any():
        limit = 1.0 / dt_s
        if one_per_step:
            what = (
                f"fired on consecutive steps in {int(multi.sum())} step(s): the {scheme} scheme "
                f"fires at most once per step, so its rate is capped at 1/dt_s = {limit:g} Hz"
            )
        else:
            what = (
                f"fired more than once within one step in {int(multi.sum())} step(s), i.e. "
                f"above the 1/dt_s = {limit:g} Hz the step resolves"
            )
            if capped.any():
                what += (
                    f"; in {int(capped.sum())} step(s) more than {max_per_step} spikes were "
                    f"needed and only {max_per_step} were kept"
                )
        warnings.warn(
            f"{model}: input up to {max_current:g} is too strong for dt_s = {dt_s:g} s: the "
            f"neuron {what}. Reduce dt_s or the input gain.",
            NeuronStepWarning,
            stacklevel=3,
        )
