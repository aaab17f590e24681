"""Spike-response-model (SRM) neurons in discrete time, the building block of the SNN.

A neuron's membrane potential at step ``n`` (seed paper 000, eq. 2) is

    u[n] = sum_i w_i (eps * s_i)[n] + (nu * o)[n]

with the synaptic response kernel ``eps[m] = (m / tau_sr) exp(1 - m / tau_sr)`` (an alpha
function that peaks at 1 after ``tau_sr`` steps), the refractory kernel
``nu[m] = -scale_ref * theta * (m / tau_ref) exp(1 - m / tau_ref)`` (zero at ``m = 0``, so a
spike acts from the next step on), the input spike trains ``s_i`` and the neuron's own output
``o``. The neuron fires (``o[n] = 1``) when ``u[n] >= theta``. These are the SRM kernels of
SLAYER (Shrestha & Orchard 2018), with time in steps.

The refractory term is the convolution of the output with ``c * m d^m`` (``d = exp(-1 /
tau_ref)``, ``c = -scale_ref * theta * e / tau_ref``), which two first-order recursions give
exactly: ``b[n] = d b[n-1] + d a[n-1]``, ``a[n] = d a[n-1] + o[n]``, ``nu * o = c b``.
:func:`srm_spikes_torch` is the plain reference; :func:`srm_spikes_numba` the fast CPU path,
tested equal to it. Both set the recursion's state to zero once it falls below
:data:`FLUSH` (a decaying state would otherwise reach subnormal floats, which are ~100 times
slower to compute with; the dropped refractory term is below 1e-12 theta).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit

#: The alpha kernel is cut where it has fallen below 1e-4 of its peak: m / tau > 13.4.
KERNEL_SPAN = 14.0
#: Recursion states below this are set to zero (see the module docstring).
FLUSH = 1e-12


def alpha_kernel(tau_steps: float) -> np.ndarray:
    """``eps[m] = (m / tau) exp(1 - m / tau)`` for ``m = 0 .. ceil(14 tau)``, float32."""
    m = np.arange(int(math.ceil(KERNEL_SPAN * tau_steps)) + 1, dtype=np.float64)
    return (m / tau_steps * np.exp(1.0 - m / tau_steps)).astype(np.float32)


def refractory_constants(theta: float, tau_ref_steps: float, scale_ref: float):
    """``(d, c)`` of the refractory recursion, float32."""
    d = math.exp(-1.0 / tau_ref_steps)
    c = -scale_ref * theta * math.e / tau_ref_steps
    return np.float32(d), np.float32(c)


def srm_spikes_torch(torch, u, theta: float, d: float, c: float):
    """Reference: spikes and refractory potential of neurons driven by ``u``.

    ``u``: tensor ``(..., T)``, the synaptic part of the membrane potential. Returns
    ``(spikes, refractory)``, both shaped like ``u`` (spikes are 0.0 / 1.0). No gradient.
    """
    with torch.no_grad():
        ut = u.detach().movedim(-1, 0).contiguous()
        spikes = torch.zeros_like(ut)
        refr = torch.zeros_like(ut)
        a = torch.zeros_like(ut[0])
        b = torch.zeros_like(ut[0])
        d = torch.tensor(d, dtype=ut.dtype, device=ut.device)
        c = torch.tensor(c, dtype=ut.dtype, device=ut.device)
        for n in range(ut.shape[0]):
            b = d * b + d * a
            b = torch.where(b < FLUSH, 0.0, b)
            r = c * b
            s = (ut[n] + r >= theta).to(ut.dtype)
            a = d * a + s
            a = torch.where(a < FLUSH, 0.0, a)
            spikes[n] = s
            refr[n] = r
        return spikes.movedim(0, -1), refr.movedim(0, -1)


@njit
def _srm_rows(u, theta, d, c, spikes, refr):  # pragma: no cover - compiled
    for m in range(u.shape[0]):
        a = np.float32(0.0)
        b = np.float32(0.0)
        for n in range(u.shape[1]):
            b = d * b + d * a
            if b < FLUSH:
                b = np.float32(0.0)
            r = c * b
            s = np.float32(1.0) if u[m, n] + r >= theta else np.float32(0.0)
            a = d * a + s
            if a < FLUSH:
                a = np.float32(0.0)
            spikes[m, n] = s
            refr[m, n] = r


def srm_spikes_numba(torch, u, theta: float, d: float, c: float):
    """Fast CPU path of :func:`srm_spikes_torch` (same arithmetic in float32)."""
    shape = u.shape
    rows = np.ascontiguousarray(u.detach().cpu().numpy().reshape(-1, shape[-1]), np.float32)
    spikes = np.empty_like(rows)
    refr = np.empty_like(rows)
    _srm_rows(rows, np.float32(theta), np.float32(d), np.float32(c), spikes, refr)
    dev = u.device
    return (
        torch.from_numpy(spikes.reshape(shape)).to(dev),
        torch.from_numpy(refr.reshape(shape)).to(dev),
    )
