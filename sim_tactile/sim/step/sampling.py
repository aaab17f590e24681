"""What a driver makes of its steps: each sample the trapezoid mean of the loads over its
period (:class:`SampleAverager`), and the result of one simulated window
(:class:`SimResult`) and its sensor's output (:func:`sensor_output`), shared by the finger's slide (:mod:`~sim_tactile.sim.slide`) and the
probe rig's (:mod:`~sim_tactile.sim.rig_sim`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from ... import __version__
from ...records import Recording
from ..plan.fidelity import Fidelity


@dataclass
class SimResult:
    """A simulated window: its recording, the fidelity it ran at (None for the probe rig,
    whose grid is its own), the simulated and wall time [s] and the warnings."""

    recording: Recording
    fidelity: Fidelity | None
    sim_s: float
    wall_s: float
    warnings: list[str] = field(default_factory=list)


class SampleAverager:
    """Each sample is the mean load over its period by the trapezoid rule on the steps: half
    the load at the period's start, the steps inside, half the load at its end (the next
    period's first step); so a sample is centred on its time at any step. Feed it every
    step's taxel loads and force with :meth:`add` (step ``k`` of sample ``s``), call
    :meth:`end_sample` after each sample's last step and :meth:`finish` with the step that
    follows the last sample."""

    def __init__(self, n_samples: int, n_taxels: int, steps_per_sample: int) -> None:
        self.loads = np.empty((n_samples, n_taxels), dtype=np.float64)
        self.forces = np.empty(n_samples)
        self.n_sub = steps_per_sample
        self._acc = np.zeros(n_taxels)
        self._first = np.zeros(n_taxels)  # the load at the start of the current period
        self._prev_sum = np.zeros(n_taxels)
        self._prev_first = np.zeros(n_taxels)
        self._fsum = self._f_first = self._f_prev_sum = self._f_prev_first = 0.0

    def add(self, s: int, k: int, now: np.ndarray, f: float) -> None:
        if k == 0:
            if s:  # the previous sample ends where this step starts
                self._close(s - 1, now, f)
            self._first[:] = now
            self._f_first = f
        self._acc += now
        self._fsum += f

    def end_sample(self) -> None:
        self._prev_sum[:], self._prev_first[:] = self._acc, self._first
        self._f_prev_sum, self._f_prev_first = self._fsum, self._f_first
        self._acc[:] = 0.0
        self._fsum = 0.0

    def finish(self, now: np.ndarray, f: float) -> None:
        self._close(len(self.forces) - 1, now, f)

    def _close(self, s: int, now: np.ndarray, f_end: float) -> None:
        self.loads[s] = (self._prev_sum + 0.5 * (now - self._prev_first)) / self.n_sub
        self.forces[s] = (self._f_prev_sum + 0.5 * (f_end - self._f_prev_first)) / self.n_sub


def sensor_output(loads: np.ndarray, sensor, rate_hz: float, seed: int, ideal: bool):
    """``(out, units, transducer)``: the sensor's output of the taxel loads (T, N) [N] at
    ``rate_hz``, its imperfections seeded by ``seed`` (the stream ``[seed, 1]``); the loads
    themselves where ``ideal`` or the sensor has no transducer."""
    if ideal or sensor.transducer is None:
        return loads, "N", "ideal"
    out = sensor.transduce(loads, rate_hz, np.random.default_rng([seed, 1]))
    return out, sensor.units, sensor.transducer_json()


def versions() -> dict:
    """The versions a recording was made with."""
    return {"sim_tactile": __version__, "mujoco": mujoco.__version__, "numpy": np.__version__}
