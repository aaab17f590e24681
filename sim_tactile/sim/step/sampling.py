"""What a driver makes of its steps: each sample the trapezoid mean of the loads over its
period (:class:`SampleAverager`), and the result of one simulated window
(:class:`SimResult`) and its sensor's output (:func:`sensor_output`), shared by the finger's slide (:mod:`~sim_tactile.sim.slide`) and the
probe rig's (:mod:`~sim_tactile.sim.rig_sim`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from ... import __version__
from ..._jit import njit
from ...errors import PhysicsError
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


def sample_means(loads: np.ndarray, forces: np.ndarray, n: int, n_sub: int):
    """Each of ``n`` samples the trapezoid mean of its ``n_sub`` steps of ``loads`` (S, N)
    and ``forces`` (S,) (``S = n n_sub + 1``: the last step closes the last sample), as
    :class:`SampleAverager` forms it step by step: ``(loads (n, N), forces (n,))``, equal to
    it bit for bit, in one compiled call."""
    out_l = np.empty((n, loads.shape[1]))
    out_f = np.empty(n)
    _trapezoid(np.ascontiguousarray(loads), np.ascontiguousarray(forces), n_sub, out_l, out_f)
    return out_l, out_f


@njit
def _trapezoid(loads, forces, n_sub, out_l, out_f):
    """:func:`sample_means`: the sums in the averager's order (each sample's steps in turn,
    from zero), then ``(sum + (end - start) / 2) / n_sub``."""
    n, m = out_l.shape
    acc = np.empty(m)
    for s in range(n):
        a = s * n_sub
        b = a + n_sub
        for t in range(m):
            acc[t] = 0.0
        fsum = 0.0
        for i in range(a, b):
            for t in range(m):
                acc[t] += loads[i, t]
            fsum += forces[i]
        for t in range(m):
            out_l[s, t] = (acc[t] + 0.5 * (loads[b, t] - loads[a, t])) / n_sub
        out_f[s] = (fsum + 0.5 * (forces[b] - forces[a])) / n_sub


def sample_x(x_after: np.ndarray, cmd: np.ndarray, n: int, n_sub: int, rate_hz: float):
    """The pad's x at each of ``n`` samples' centres from its x after each step and each
    step's speed command (half a sample back from the sample's last step)."""
    last = np.arange(1, n + 1) * n_sub - 1  # each sample's last step
    return x_after[last] - 0.5 * cmd[last] / rate_hz


def solved_steps(total: int, every: int) -> np.ndarray:
    """The steps of ``total`` at which a slide solved at every ``every``-th step solves:
    the first, every ``every``-th, and the last."""
    return np.append(np.arange(0, total - 1, every, dtype=np.int64), total - 1)


@njit
def fill_between(loads: np.ndarray, forces: np.ndarray, solved: np.ndarray) -> None:
    """The steps between two solved ones on the line between them (in the step's index:
    the pad's travel, which the arm's servo keeps even): step ``g + k`` of a gap of ``m``
    takes ``(1 - k/m) a + (k/m) b``, each product rounded on its own."""
    n_t = loads.shape[1]
    for q in range(solved.size - 1):
        g = solved[q]
        j = solved[q + 1]
        m = j - g
        for k in range(1, m):
            w = k / m
            u = 1.0 - w
            for t in range(n_t):
                loads[g + k, t] = u * loads[g, t] + w * loads[j, t]
            forces[g + k] = u * forces[g] + w * forces[j]


def check_mujoco(d, also: list[str] | tuple = ()) -> None:
    """Raise where MuJoCo warned while stepping the state ``d`` (or ``also`` names other
    warnings: a collider's): the run is not trustworthy."""
    bad = list(also)
    if d.warning.number.any():
        bad = [mujoco.mjtWarning(i).name for i, w in enumerate(d.warning) if w.number] + bad
    if bad:
        raise PhysicsError(f"MuJoCo warning(s) {', '.join(bad)}: the simulation is not trustworthy")


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
