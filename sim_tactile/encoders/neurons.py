"""Neuron models as frozen parameters plus pure step functions (numpy, any array shape).

Izhikevich (2003), in the model's own units (seed papers 001-003): time in ms, ``v`` and ``u``
in mV, the input ``I`` in the model's current units::

    dv/dt = 0.04 v^2 + 5 v + 140 - u + I
    du/dt = a (b v - u)
    if v >= v_peak (30 mV): v <- c, u <- u + d

Leaky integrate-and-fire (LIF) and adaptive LIF (threshold adaptation), in SI time::

    tau_m dv/dt = -(v - v_rest) + I       (I in the units of v, i.e. R * current)
    theta = v_th + A,  dA/dt = -A / tau_adapt,  A <- A + beta at each spike
    if v >= theta: v <- v_reset, held for refractory_s

The step functions here are the plain reference; the encoders run numba kernels
(:mod:`._kernels`) that the tests compare with them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import finite, non_negative, one_of, positive
from ..cache import memoized
from ..errors import ConfigError, UnknownNameError


@dataclass(frozen=True)
class IzhikevichParams:
    """Izhikevich neuron parameters (model units: ms, mV).

    Attributes:
        a: recovery time scale [1/ms].
        b: sensitivity of ``u`` to ``v`` [dimensionless].
        c: reset potential [mV].
        d: reset increment of ``u`` [mV].
        v_peak: spike cut-off [mV] (30 in all seed papers).
        v_init: initial (rest) potential [mV]; the neuron starts at ``v_init``, ``u = b v_init``.
    """

    a: float
    b: float
    c: float
    d: float
    v_peak: float = 30.0
    v_init: float = -65.0

    def __post_init__(self) -> None:
        for name in ("a", "b", "c", "d", "v_peak", "v_init"):
            object.__setattr__(self, name, finite(name, getattr(self, name)))
        positive("a", self.a, unit="1/ms")
        if not self.c < self.v_peak:
            raise ConfigError(f"c = {self.c:g} mV must be below v_peak = {self.v_peak:g} mV")


#: Regular spiking (slowly adapting, SA; papers 001-003) and fast spiking (rapidly adapting,
#: RA; paper 003) presets of Izhikevich (2003).
IZHIKEVICH_PRESETS: dict[str, IzhikevichParams] = {
    "RS": IzhikevichParams(a=0.02, b=0.2, c=-65.0, d=8.0),
    "SA": IzhikevichParams(a=0.02, b=0.2, c=-65.0, d=8.0),
    "FS": IzhikevichParams(a=0.1, b=0.2, c=-65.0, d=2.0),
    "RA": IzhikevichParams(a=0.1, b=0.2, c=-65.0, d=2.0),
}

SCHEMES = ("rk4", "euler", "izhikevich2003")
#: Default step per scheme [s]: 0.1 ms for rk4 (spike times within 0.01 ms of a tight ODE
#: solution, see docs/spikes.md); 1 ms for the papers' schemes.
DEFAULT_DT_S = {"rk4": 1e-4, "euler": 1e-3, "izhikevich2003": 1e-3}


def izhikevich_preset(name: str | IzhikevichParams) -> IzhikevichParams:
    """Parameters of a preset name (RS = SA, FS = RA), or ``name`` itself if already params."""
    if isinstance(name, IzhikevichParams):
        return name
    if name not in IZHIKEVICH_PRESETS:
        raise UnknownNameError(
            f"preset = {name!r} is not known; valid: {', '.join(IZHIKEVICH_PRESETS)}"
        )
    return IZHIKEVICH_PRESETS[name]


def izhikevich_rhs(v, u, current, p: IzhikevichParams):
    """Time derivatives ``(dv/dt, du/dt)`` [mV/ms]."""
    return (0.04 * v + 5.0) * v + 140.0 - u + current, p.a * (p.b * v - u)


def izhikevich_map(v, u, current, p: IzhikevichParams, h_ms, scheme: str = "rk4"):
    """One step of length ``h_ms`` [ms] without the threshold: the scheme's pure update."""
    if scheme == "rk4":
        k1v, k1u = izhikevich_rhs(v, u, current, p)
        k2v, k2u = izhikevich_rhs(v + 0.5 * h_ms * k1v, u + 0.5 * h_ms * k1u, current, p)
        k3v, k3u = izhikevich_rhs(v + 0.5 * h_ms * k2v, u + 0.5 * h_ms * k2u, current, p)
        k4v, k4u = izhikevich_rhs(v + h_ms * k3v, u + h_ms * k3u, current, p)
        return (
            v + h_ms / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
            u + h_ms / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u),
        )
    if scheme == "euler":
        dv, du = izhikevich_rhs(v, u, current, p)
        return v + h_ms * dv, u + h_ms * du
    if scheme == "izhikevich2003":  # two half steps for v, then u with the new v
        for _ in range(2):
            v = v + 0.5 * h_ms * ((0.04 * v + 5.0) * v + 140.0 - u + current)
        return v, u + h_ms * p.a * (p.b * v - u)
    raise ConfigError(f"scheme = {scheme!r} is not valid; valid: {', '.join(SCHEMES)}")


#: Relative width [fraction of the step] to which the rk4 threshold crossing is bisected.
CROSSING_TOL = 1e-10
#: At most this many spikes are resolved within one step; more is reported as a warning.
MAX_SPIKES_PER_STEP = 16


@memoized("stable current limits", maxsize=256)
def stable_current_limit(p: IzhikevichParams, dt_ms: float, scheme: str) -> float:
    """Most negative constant input for which the rest state is stable under the scheme.

    The linearised step map at the stable (lower) fixed point must have spectral radius <= 1;
    below this input the discrete neuron oscillates and can fire spuriously (docs/physics.md:
    forward Euler at 1 ms spikes for I <= -70). Returned in the model's current units.
    """
    one_of("scheme", scheme, SCHEMES)

    def radius(current: float) -> float:
        # lower fixed point of 0.04 v^2 + (5 - b) v + 140 + I = 0 (u = b v)
        disc = (5.0 - p.b) ** 2 - 0.16 * (140.0 + current)
        v = (-(5.0 - p.b) - math.sqrt(disc)) / 0.08
        u = p.b * v
        jac = np.empty((2, 2))
        for k, (ev, eu) in enumerate(((1e-6, 0.0), (0.0, 1e-6))):
            vp, up = izhikevich_map(v + ev, u + eu, current, p, dt_ms, scheme)
            vm, um = izhikevich_map(v - ev, u - eu, current, p, dt_ms, scheme)
            jac[0, k] = (vp - vm) / 2e-6
            jac[1, k] = (up - um) / 2e-6
        return float(np.max(np.abs(np.linalg.eigvals(jac))))

    hi = ((5.0 - p.b) ** 2 / 0.16) - 140.0 - 1e-9  # the fixed point exists below this
    if radius(hi - 1.0) > 1.0:
        return hi
    lo = hi - 1.0
    while radius(lo) <= 1.0:
        lo = hi - 2.0 * (hi - lo)
        if lo < -1e12:
            return -math.inf
    top = hi - 1.0
    for _ in range(80):
        mid = 0.5 * (lo + top)
        if radius(mid) <= 1.0:
            top = mid
        else:
            lo = mid
    return top


@dataclass(frozen=True)
class LIFParams:
    """(Adaptive) leaky integrate-and-fire parameters; ``beta = 0`` is the plain LIF.

    Attributes:
        tau_m_s: membrane time constant [s].
        v_rest: resting potential (units of the input).
        v_reset: reset potential.
        v_th: base threshold.
        refractory_s: absolute refractory period [s] (v held at v_reset).
        tau_adapt_s: time constant of the threshold adaptation [s].
        beta: threshold increment per spike (0: no adaptation).
    """

    tau_m_s: float = 0.02
    v_rest: float = 0.0
    v_reset: float = 0.0
    v_th: float = 1.0
    refractory_s: float = 0.0
    tau_adapt_s: float = 0.2
    beta: float = 0.0

    def __post_init__(self) -> None:
        positive("tau_m_s", self.tau_m_s, unit="s")
        positive("tau_adapt_s", self.tau_adapt_s, unit="s")
        non_negative("refractory_s", self.refractory_s, unit="s")
        non_negative("beta", self.beta)
        for name in ("v_rest", "v_reset", "v_th"):
            finite(name, getattr(self, name))
        if not self.v_reset < self.v_th:
            raise ConfigError(f"v_reset = {self.v_reset:g} must be below v_th = {self.v_th:g}")


def alif_params(**kwargs: float) -> LIFParams:
    """Adaptive LIF with the defaults ``beta = 0.5``, ``tau_adapt_s = 0.2`` unless given."""
    kwargs.setdefault("beta", 0.5)
    return LIFParams(**kwargs)


def lif_free(v0, a0, current, p: LIFParams, t_s):
    """Exact state after ``t_s`` seconds of constant input without a spike: ``(v, A)``."""
    v_inf = p.v_rest + current
    return (
        v_inf + (v0 - v_inf) * np.exp(-t_s / p.tau_m_s),
        a0 * np.exp(-t_s / p.tau_adapt_s),
    )
