"""A held slide's steps in one compiled call (:func:`held_slide`), its path stepped first
(:func:`glide`).

Under quasi-static force control a slide's path is kinematic: the held step sets the pad's
height, zeroes the bone's vertical speed and force, and MuJoCo moves it along the slide with
the arm's speed servo. The slide joint's motion then does not depend on the heights the held
steps find (the joints are orthogonal and nothing else acts on it), so the pad's positions
along the whole window are those of the dynamics stepped alone, as a slide read wholly off
its phase table steps them (:class:`~.tabled.Glide`). :func:`held_slide` steps them first, on
a copy of the runner's MuJoCo state, then solves every held step of the window in one call of
:func:`_held_steps`: the same :func:`~.held._held_kernel` at the same positions, each from
the height the step before it found (MuJoCo leaves the press joint where the held step put
it), with the contact set carried from step to step. It is the per-step slide's arithmetic
in another order: the records are equal bit for bit (``tests/test_sim_held_run.py``).

Where the press joint does move under the dynamics alone (a model whose bone feels gravity or
a spring), the copy says so and the Python loop steps the slide.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import mujoco
import numpy as np

from ..._jit import njit
from ...errors import PhysicsError
from ..plan.protocol import SPEED_RAMP_S
from .held import CompiledHeldStep, _held_kernel
from .runner import V_STICK, Runner, coast
from .sampling import check_mujoco, fill_between, sample_means, sample_x, solved_steps
from .strokes import Strokes

#: Kernel status: a step's load or depth needs the runner's own checks (which raise).
CHECK = 10


def held_slide(runner: Runner, window, proto, n_sub: int, every: int):
    """The slide phase of :func:`~sim_tactile.sim.slide._slide_sampled` (``every`` >= 1),
    compiled: ``(loads (T, N), forces (T,), x_pad (T,), stopped_at_s, wall_s)`` with the
    runner's drag sums updated, or None where the runner's held step is not the compiled one
    or its press joint moves under the dynamics alone (the Python loop serves)."""
    if not isinstance(runner.hold, CompiledHeldStep):
        return None
    t0 = time.perf_counter()
    n = window.n_samples
    total = n * n_sub + 1  # the steps the samples read (the last one closes the last sample)
    path = glide_runner(runner, window, proto.speed_m_s, runner.dt, total, n_sub)
    if path is None:
        return None
    solved = solved_steps(total, every)
    loads = np.empty((total, runner.s.layout.n))
    forces = np.empty(total)
    held_steps(runner, path, solved, proto.force_n, loads, forces)
    fill_between(loads, forces, solved)
    out_loads, out_forces = sample_means(loads, forces, n, n_sub)
    x_pad = path.x_pad(n, n_sub, proto.rate_hz)
    return out_loads, out_forces, x_pad, path.strokes.stopped_at_s, time.perf_counter() - t0


def glide_runner(r: Runner, window, speed_m_s, dt, total: int, n_sub: int) -> Path | None:
    """:func:`glide` on a pressed runner's own MuJoCo state, which is put back afterwards
    (:data:`_KEPT_STATE`): the runner goes on from the press as from an untouched copy."""
    kept = _kept(r._m_dyn, r.d_dyn)
    try:
        return glide(r.d_dyn, r._m_dyn, r._jx, r._jz, window, speed_m_s, dt, total, n_sub)
    finally:
        _restore(r._m_dyn, r.d_dyn, kept)


#: What :func:`held_slide` keeps of the runner's MuJoCo state while the path is glided on it:
#: everything a later ``mj_step`` reads (MuJoCo's integration state), so that the held steps,
#: or the Python loop where the glide is refused, go on from the press as from an untouched
#: copy (a copy of the ``MjData`` cost 0.35 ms a slide in the bindings; this, microseconds).
_KEPT_STATE = mujoco.mjtState.mjSTATE_INTEGRATION


def _kept(m, d) -> tuple:
    """``d``'s integration state and its warning counters (:data:`_KEPT_STATE`), the
    counters read as the bindings' arrays over ``mjData.warning`` (a loop over its items
    took 84 us, a tenth of an L0 slide's set-up, for what is two short copies)."""
    state = np.empty(mujoco.mj_stateSize(m, _KEPT_STATE))
    mujoco.mj_getState(m, d, state, _KEPT_STATE)
    return state, d.warning.number.copy(), d.warning.lastinfo.copy()


def _restore(m, d, kept: tuple) -> None:
    """Put back what :func:`_kept` kept."""
    state, number, lastinfo = kept
    mujoco.mj_setState(m, d, state, _KEPT_STATE)
    d.warning.number[:] = number
    d.warning.lastinfo[:] = lastinfo


@dataclass
class Path:
    """A held slide's steps along the slide (:func:`glide`): the slide joint's position and
    speed as each step starts, the step's speed command and the pad's x on the plate after
    it, and the strokes (when it stopped)."""

    x_joint: np.ndarray
    vx: np.ndarray
    cmd: np.ndarray
    x_after: np.ndarray
    strokes: Strokes

    def x_pad(self, n: int, n_sub: int, rate_hz: float) -> np.ndarray:
        """The pad's x at each of ``n`` samples' centres, as the per-step slide records it."""
        return sample_x(self.x_after, self.cmd, n, n_sub, rate_hz)


def glide(d, m, jx, jz, window, speed_m_s, dt, total: int, n_sub: int) -> Path | None:
    """The slide joint's path over ``total`` steps of ``dt`` [s] along ``window``'s strokes,
    stepped on the MuJoCo state ``d`` of the model ``m`` (slide joint ``jx``, press joint
    ``jz``) as :meth:`~.runner.Runner.coast` steps it (MuJoCo's warnings checked at each
    sample's end), or None where the press joint moved.

    The steps up to the first at which a stroke turns or stops run in MuJoCo's own loop
    (:func:`_rolled`: their commands are the first stroke's ramp, known ahead); the rest one
    by one, each command read off the pad's position."""
    qpos, qvel, qfrc = d.qpos, d.qvel, d.qfrc_applied
    z = float(qpos[jz])
    strokes = Strokes(window, speed_m_s, dt)
    x0 = window.x_start_m
    x_joint = np.empty(total)
    vx = np.empty(total)
    cmd = np.empty(total)
    x_after = np.empty(total)
    qvel[jz] = 0.0
    qfrc[jz] = 0.0
    qfrc[jx] = 0.0
    k = _rolled(d, m, jx, jz, strokes, (x_joint, vx, cmd, x_after), x0)
    if k < 0:
        return None
    for i in range(k, total):
        x = float(qpos[jx])
        v = strokes.command(x0 + x)
        x_joint[i], vx[i], cmd[i] = x, float(qvel[jx]), v
        coast(m, d, jx, jz, v)
        x_after[i] = x0 + float(qpos[jx])
        if i % n_sub == n_sub - 1:
            check_mujoco(d)
    if float(qpos[jz]) != z or float(qvel[jz]) != 0.0:
        return None
    return Path(x_joint, vx, cmd, x_after, strokes)


#: MuJoCo's state that :func:`_rolled` rolls out from and restores.
_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


def _rolled(d, m, jx, jz, strokes: Strokes, out, x0: float) -> int:
    """Step ``d`` in MuJoCo's rollout loop while the commands are the first stroke's ramp
    (``sign speed min(1, t / ramp)``, its time summed step by step as
    :class:`~.strokes.Strokes` sums it), write the path of those steps into ``out`` and
    leave ``d`` and ``strokes`` after them: returns how many (-1 where the press joint
    moved)."""
    from mujoco import rollout

    x_joint, vx, cmd, x_after = out
    total = x_joint.size
    w = strokes.w
    sign, speed = strokes.sign, strokes.speed
    t = np.concatenate([[0.0], np.cumsum(np.full(total, strokes.dt))])  # before each call
    v = sign * speed * np.minimum(1.0, t[:total] / SPEED_RAMP_S)
    nq, nv = m.nq, m.nv
    state0 = np.empty(mujoco.mj_stateSize(m, _STATE))
    mujoco.mj_getState(m, d, state0, _STATE)
    control = np.repeat(d.ctrl[None, :], total, axis=0)
    control[:, 0] = v
    with rollout.Rollout(nthread=0) as ro:
        states, _ = ro.rollout(m, d, state0[None], control[None])
    states = states[0]
    qpos = states[:, 1 : 1 + nq]
    qvel = states[:, 1 + nq : 1 + nq + nv]
    if (qpos[:, jz] != state0[1 + jz]).any() or (qvel[:, jz] != 0.0).any():
        return -1
    x_joint[0], vx[0] = state0[1 + jx], state0[1 + nq + jx]
    x_joint[1:], vx[1:] = qpos[:-1, jx], qvel[:-1, jx]
    x = x0 + x_joint
    turn = sign * x >= w.x_limit_m
    if len(w.strokes) > 1:
        turn |= sign * (x - w.strokes[0][1]) >= 0
    k = int(np.argmax(turn)) if turn.any() else total
    cmd[:k] = v[:k]
    x_after[:k] = x0 + qpos[:k, jx]
    check_mujoco(d)
    if k < total:  # back to the state after step k - 1, for the step-by-step loop
        mujoco.mj_setState(m, d, states[k - 1] if k else state0, _STATE)
    strokes.t = strokes.t_stroke = float(t[k])
    if k:
        strokes.v = float(v[k - 1])
    return k


def held_steps(runner: Runner, path: Path, steps: np.ndarray, force_n: float, loads, forces):
    """The runner's held steps ``steps`` (increasing indices of ``path``) in one compiled
    call, each from the height the one before it found (the first from the runner's), their
    loads and forces written at those indices; the runner's drag sums and height updated as
    its own steps update them, and its errors raised at the first step that fails."""
    hold = runner.hold
    tops = np.empty(loads.shape[0])
    zs = np.empty(loads.shape[0])
    qpos = runner._qpos.copy()
    total_pa = force_n / runner._area
    bounds = (runner.max_pen_allowed, runner.z0, runner.max_depth)
    args = hold.kernel_args()
    st, j, M2, S2, updates, rebuilds, rowsum2 = _held_steps(
        path.x_joint[steps],
        qpos,
        (hold.bone0, hold.jx, runner._jz),
        *args,
        total_pa,
        (hold.pen, hold.f, hold.W, hold.area),
        bounds,
        (loads, forces, tops, zs, steps),
    )
    if M2 is not args[3][0]:  # the set changed
        hold.solver.adopt(M2, S2, updates, rebuilds, rowsum2)
    if st:
        i = int(steps[j])
        if st != CHECK:
            hold.fail(st, total_pa)
        runner._after_skin(float(forces[i]), float(tops[i]), force_n, 0.0)
        runner._check_depth(force_n, float(forces[i]), float(zs[i]))
        raise PhysicsError(f"the held step {i} failed its checks (status {st})")  # not reached
    _drag(runner, forces[steps], path.vx[steps], path.cmd[steps])
    runner._qpos[runner._jz] = zs[steps[-1]]


def _drag(runner: Runner, forces, vx, cmd) -> None:
    """The friction drag of the solved steps, summed as the runner sums it
    (:meth:`~.runner.Runner._after_skin`), step after step."""
    mu = runner._friction
    drag_sum, steps = runner.drag_sum, runner.n_slide_steps
    for f, v, c in zip(forces.tolist(), vx.tolist(), cmd.tolist(), strict=True):
        if c != 0.0:
            drag_sum += abs(-mu * f * math.tanh(v / V_STICK))
            steps += 1
    runner.drag_sum, runner.n_slide_steps = drag_sum, steps


@njit
def _held_steps(xs, qpos, pose, probe, reduced, skin, state, limits, total, out, bounds, rec):
    """The held steps at the slide joint's positions ``xs``, each from the height the one
    before it found: :func:`~.held._held_kernel` in a loop, the contact set carried along.

    ``pose``: ``(bone0, jx, jz)``; ``out``: ``(pen, f, W, area)``; ``bounds``:
    ``(max_pen, z0, max_depth)``: the runner's checks of a step (a node deeper than the skin,
    the pad below what the skin carries, a runaway); ``rec``: ``(loads, forces, tops, zs,
    steps)``: the records, written at the steps' indices ``steps``. Returns ``(status, k, M,
    S, updates, rebuilds, rowsum)``: status 0 done, else the kernel's status (or
    :data:`CHECK`) at the ``k``-th position."""
    bone0, jx, jz = pose
    M, S, in_set, cu, rowsum, updates, refresh = state
    pen, f, W, area = out
    max_pen, z0, max_depth = bounds
    loads, forces, tops, zs, steps = rec
    rebuilds = 0
    for k in range(xs.shape[0]):
        i = steps[k]
        qpos[jx] = xs[k]
        st, force, top, M, S, updates, rb, rowsum = _held_kernel(
            (bone0, qpos, jx, jz),
            probe,
            reduced,
            skin,
            (M, S, in_set, cu, rowsum, updates, refresh),
            limits,
            total,
            (pen, f, W, area, loads[i]),
        )
        rebuilds += rb
        z = qpos[jz]
        forces[i], tops[i], zs[i] = force, top, z
        if st != 0:
            return st, k, M, S, updates, rebuilds, rowsum
        if not np.isfinite(force) or top > max_pen:
            return CHECK, k, M, S, updates, rebuilds, rowsum
        if z0 + z < -max_depth or not (np.isfinite(z) and abs(z) < 0.05):
            return CHECK, k, M, S, updates, rebuilds, rowsum
    return 0, xs.shape[0], M, S, updates, rebuilds, rowsum
