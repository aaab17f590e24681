"""The benchmarks behind ``sim-tactile bench``: speed against error, and stability.

- :mod:`.speed_error`: for each task's scene, every fidelity level and a range of time steps
  and node pitches, the real-time factor and the error against the finest level and against
  the closed forms (pulse period of a grating, Hertz), with a table and a Pareto figure.
- :mod:`.stability`: the hard cases (fast slides, high forces, sharp edges, features below the
  node pitch, coarse steps, a bottomed skin, extreme neuron inputs, dead and noisy taxels,
  empty spike trains); each must end in a measured result that passes sanity checks or in a
  named error, never in a crash or a silently wrong number.
"""

from __future__ import annotations

from .._lazy import lazy_exports

#: The public names and the module that defines each (loaded on first use).
_EXPORTS = {
    "run_speed_error": ".speed_error",
    "run_stability": ".stability",
    "run_sim_real": ".sim_real",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
