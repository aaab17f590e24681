"""Leaky and adaptive leaky integrate-and-fire neurons driven by sampled signals.

Between events the state is advanced with the exact solution for a constant input (the input
is zero-order held), so there is no integration error; a step whose end is at or above the
threshold is bisected to the crossing time (to 1e-10 of a step), and the rest of the step is
integrated after the reset and the refractory period. Crossings that enter and leave the
threshold within a single step are not seen: keep ``dt_s`` well below both time constants.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .._validate import positive
from ..errors import ConfigError
from . import _kernels as K
from ._common import check_current, report, sample_of_step, split
from .neurons import CROSSING_TOL, MAX_SPIKES_PER_STEP, LIFParams, lif_free

#: Default LIF step [s]; the solution is exact between events, so this only sets how finely
#: threshold crossings are looked for.
DEFAULT_LIF_DT_S = 1e-4


def simulate_lif(
    current: np.ndarray,
    rate_hz: float,
    params: LIFParams | Sequence[LIFParams] = LIFParams(),  # noqa: B008 (frozen, immutable)
    *,
    dt_s: float = DEFAULT_LIF_DT_S,
) -> list[np.ndarray]:
    """Spike times [s] of (adaptive) LIF neurons, one per row of ``current``.

    ``current`` is ``(n_neurons, n_samples)`` (or 1-D), the input in the units of ``v``
    (``R * I``) sampled at ``rate_hz`` [Hz]; ``params`` one :class:`LIFParams` or one per neuron.
    Warns :class:`~sim_tactile.errors.NeuronStepWarning` when a neuron fires more than
    once per step.
    """
    dt_s = positive("dt_s", dt_s, unit="s")
    cur = check_current(current)
    if cur.ndim == 1:
        cur = cur[None, :]
    if cur.ndim != 2:
        raise ConfigError(f"current must be 1-D or 2-D (neurons x samples), got {cur.shape}")
    plist = [params] * cur.shape[0] if isinstance(params, LIFParams) else list(params)
    if len(plist) != cur.shape[0]:
        raise ConfigError(f"{len(plist)} LIFParams given for {cur.shape[0]} input signals")
    steps = sample_of_step(cur.shape[1], rate_hz, dt_s)

    def col(name: str) -> np.ndarray:
        return np.array([getattr(p, name) for p in plist], dtype=np.float64)

    times, who, multi, capped, nonfinite = K.lif_run(
        cur,
        steps,
        col("tau_m_s"),
        col("v_rest"),
        col("v_reset"),
        col("v_th"),
        col("refractory_s"),
        col("tau_adapt_s"),
        col("beta"),
        dt_s,
        CROSSING_TOL,
        MAX_SPIKES_PER_STEP,
    )
    report(
        multi,
        capped,
        nonfinite,
        model="LIF",
        dt_s=dt_s,
        scheme="exact",
        max_current=float(cur.max()),
        one_per_step=False,
        max_per_step=MAX_SPIKES_PER_STEP,
    )
    # the kernel runs one neuron after the other: its spikes come grouped by neuron, in time
    return split(times, np.bincount(who, minlength=cur.shape[0]), 1.0)


def simulate_reference(
    current: np.ndarray, rate_hz: float, p: LIFParams, *, dt_s: float = DEFAULT_LIF_DT_S
) -> np.ndarray:
    """Plain-Python reference of :func:`simulate_lif` for one neuron (slow; for tests)."""
    cur = check_current(current).ravel()
    steps = sample_of_step(cur.size, rate_hz, dt_s)
    v, adapt, ref_left = p.v_rest, 0.0, 0.0
    spikes: list[float] = []
    for k, idx in enumerate(steps):
        current_k = float(cur[idx])
        t, rem, fired = k * dt_s, dt_s, 0
        while rem > 0.0:
            if ref_left > 0.0:
                adv = min(ref_left, rem)
                adapt = float(lif_free(0.0, adapt, 0.0, p, adv)[1])
                ref_left, t, rem = ref_left - adv, t + adv, rem - adv
                continue
            ve, ae = (float(x) for x in lif_free(v, adapt, current_k, p, rem))
            if ve < p.v_th + ae:
                v, adapt = ve, ae
                break
            if fired == MAX_SPIKES_PER_STEP:
                break
            lo, hi = 0.0, rem
            while hi - lo > CROSSING_TOL * dt_s:
                mid = 0.5 * (lo + hi)
                vm, am = lif_free(v, adapt, current_k, p, mid)
                if vm < p.v_th + am:
                    lo = mid
                else:
                    hi = mid
            _, am = lif_free(v, adapt, current_k, p, hi)
            t, rem, fired = t + hi, rem - hi, fired + 1
            spikes.append(t)
            v, adapt, ref_left = p.v_reset, float(am) + p.beta, p.refractory_s
    return np.asarray(spikes, dtype=np.float64)
