"""A held slide read off its phase table where the pad is on the repeating texture
(:func:`slide_tabled`), and solved step by step elsewhere.

MuJoCo still steps the finger's dynamics at every step (the arm's velocity servo moves the
pad along the slide; nothing else does while the force is held), so the pad's positions are
the per-step slide's; a step in the plan's interior takes its taxel loads, force and depth
from the table (:meth:`~.phase_table.PhaseTable.at`) instead of a collision query and a
contact solve. A step outside it (the approach onto the texture and the exit, on a slide
that starts on flat ground) is the per-step held step, started from the table's height for
its pose. Each sample is the trapezoid mean of its steps, as the per-step slide averages
them (:func:`~.sampling.sample_means`, as :class:`~.sampling.SampleAverager` does).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from ...errors import PhysicsError
from ...hashing import blas_kernel, code_version, content_hash
from ..plan.fidelity import Fidelity, solved_spectrally
from ..plan.options import keyed
from ..plan.phase import PhasePlan, force_levels, mirror_centre, tables_shared, travel
from ..plan.protocol import Protocol, SlideWindow
from ..plan.slide import Slide
from ..plan.span import span_fraction
from .batched_held import batched_held
from .build import dynamics_for, runner_for
from .held import CompiledHeldStep
from .held_run import glide, glide_runner, held_steps
from .mirror import mirrored_loads
from .phase_table import PhaseTable, tabulate
from .runner import V_STICK, Runner, coast
from .sampling import check_mujoco, sample_means, sample_x
from .shared_tables import Blend, kept_table
from .strokes import Strokes


class Glide:
    """The finger's slide joint alone, for a slide read wholly off its table: a fresh
    MuJoCo state of the scene's dynamics model ``m_dyn`` at rest (the pad where the held
    press leaves it: no travel, no speed), stepped with the servo's command and the press
    joint held, as :meth:`~.runner.Runner.coast` steps a pressed runner."""

    def __init__(self, m_dyn, jx: int, jz: int) -> None:
        self.m, self.jx, self.jz = m_dyn, jx, jz
        self.d = mujoco.MjData(m_dyn)
        self.d.qpos[:] = 0.0

    @property
    def x_m(self) -> float:
        return float(self.d.qpos[self.jx])

    @property
    def vx(self) -> float:
        return float(self.d.qvel[self.jx])

    def coast(self, slide_v: float) -> None:
        coast(self.m, self.d, self.jx, self.jz, slide_v)

    def check_warnings(self) -> None:
        check_mujoco(self.d)


def slide_tabled(
    table: PhaseTable,
    dyn: Runner | Glide,
    window: SlideWindow,
    proto: Protocol,
    n_sub: int,
    dt: float,
    friction: float,
    max_pen_m: float,
):
    """Slide along the window's strokes under the held force, each step read off ``table``
    where the pad lies in its plan's interior, else solved by ``dyn`` (a pressed
    :class:`~.runner.Runner`; a :class:`Glide` where every step lies in the interior).

    Returns ``(loads (T, N), forces (T,), x_pad (T,), stopped_at_s, wall_s, drag_sum,
    n_slide_steps, tabled_steps)``, as the per-step slide records them.

    The pad's path is stepped first (:func:`~.held_run.glide`; on a runner's own MuJoCo
    state, put back afterwards: :func:`~.held_run.glide_runner`); the steps off the table,
    where the runner's held step is the compiled one, then run in one compiled call a
    stretch (:func:`~.held_run.held_steps`), each stretch from the table's height where it
    starts; elsewhere (another held step, a press joint that moves under the dynamics
    alone) step by step (:func:`_stepped`). Both record the same numbers bit for bit."""
    if float(np.max(table.top)) > max_pen_m:
        raise PhysicsError(
            f"skin pressed to the bottom: a node is {table.top.max() * 1e3:.3g} mm deep, beyond "
            f"the skin thickness {max_pen_m * 1e3:.3g} mm (lower the force or use a thicker skin)"
        )
    args = (table, dyn, window, proto, n_sub, dt, friction)
    held = dyn if isinstance(dyn, Runner) else None
    if held is not None and not isinstance(held.hold, CompiledHeldStep):
        return _stepped(*args)
    t0 = time.perf_counter()
    n = window.n_samples
    total = n * n_sub + 1  # the steps the samples read (the last one closes the last sample)
    if held is None:
        path = glide(dyn.d, dyn.m, dyn.jx, dyn.jz, window, proto.speed_m_s, dt, total, n_sub)
    else:  # on the runner's own state, put back: it stays where the press left it
        path = glide_runner(held, window, proto.speed_m_s, dt, total, n_sub)
    if path is None:
        return _stepped(*args)
    plan = table.plan
    x = window.x_start_m + path.x_joint  # the pad's x on the plate as each step reads its loads
    inside = (plan.x_lo <= x) & (x <= plan.x_hi)
    loads = np.empty((total, table.n_taxels))
    forces = np.empty(total)
    off = np.flatnonzero(~inside)
    if off.size and held is None:
        raise _left(x[off[0]], plan)
    for run in np.split(off, np.flatnonzero(np.diff(off) != 1) + 1) if off.size else ():
        if run[0] > 0:  # back from the table: start from its height here
            held._qpos[held._jz] = table.at(x[run[0] : run[0] + 1])[3][0] - held.z0
        held_steps(held, path, run, proto.force_n, loads, forces)
    if inside.any():
        loads[inside], forces[inside] = table.at(x[inside])[:2]
    drag_sum, n_steps = _drag(forces, path.vx, path.cmd, inside, friction)
    if held is not None:
        drag_sum += held.drag_sum
        n_steps += held.n_slide_steps
    means, mean_forces = sample_means(loads, forces, n, n_sub)
    x_pad = path.x_pad(n, n_sub, proto.rate_hz)
    wall = time.perf_counter() - t0
    stopped = path.strokes.stopped_at_s
    return means, mean_forces, x_pad, stopped, wall, drag_sum, n_steps, int(inside.sum())


def _left(x: float, plan: PhasePlan) -> PhysicsError:
    return PhysicsError(
        f"the pad left the repeating texture at x = {x * 1e3:.4g} mm "
        f"(the table serves {plan.describe()})"
    )


def _stepped(table, dyn, window, proto, n_sub, dt, friction):
    """:func:`slide_tabled` step by step: the dynamics stepped, and each step read off the
    table or solved by the runner, in turn."""
    n = window.n_samples
    n_tax = table.n_taxels
    total = n * n_sub + 1  # the steps the samples read (the last one closes the last sample)
    loads = np.empty((total, n_tax))
    forces = np.empty(total)
    x_before = np.empty(total)  # the pad's x on the plate as each step reads its loads
    vx = np.empty(total)  # its speed then (the drag's)
    cmd = np.empty(total)  # the stroke's speed command of each step
    x_after = np.empty(total)
    inside = np.zeros(total, dtype=bool)
    strokes = Strokes(window, proto.speed_m_s, dt)
    plan, x0, F = table.plan, window.x_start_m, proto.force_n
    held = dyn if isinstance(dyn, Runner) else None
    t0 = time.perf_counter()
    for i in range(total):
        x = x0 + dyn.x_m
        v = strokes.command(x)
        x_before[i], cmd[i] = x, v
        if plan.covers(x):
            inside[i] = True
            vx[i] = dyn.vx if held is None else float(held._qvel[held._jx])
            dyn.coast(v)
        elif held is None:
            raise _left(x, plan)
        else:
            if i and inside[i - 1]:  # back from the table: start from its height here
                held._qpos[held._jz] = table.at(np.array([x]))[3][0] - held.z0
            vx[i] = np.nan  # the runner records its own drag
            forces[i] = held.step(force_cmd=F, slide_v=v, taxel_out=loads[i])
        x_after[i] = x0 + dyn.x_m
        if i % n_sub == n_sub - 1:
            dyn.check_warnings()
    if inside.any():
        tl, tf, _, _ = table.at(x_before[inside])
        loads[inside], forces[inside] = tl, tf
    drag_sum, n_steps = _drag(forces, vx, cmd, inside, friction)
    if held is not None:
        drag_sum += held.drag_sum
        n_steps += held.n_slide_steps
    means, mean_forces = sample_means(loads, forces, n, n_sub)
    x_pad = sample_x(x_after, cmd, n, n_sub, proto.rate_hz)
    wall = time.perf_counter() - t0
    return (
        means,
        mean_forces,
        x_pad,
        strokes.stopped_at_s,
        wall,
        drag_sum,
        n_steps,
        int(inside.sum()),
    )


def _drag(forces, vx, cmd, inside, friction) -> tuple[float, int]:
    """The tabled steps' friction drag, summed as the runner sums it (``mu N tanh(v /
    V_STICK)`` at the pad's speed, on steps that slide), and their count."""
    moving = inside & (cmd != 0.0)
    drag = friction * forces[moving] * np.tanh(vx[moving] / V_STICK)
    return float(np.abs(drag).sum()), int(moving.sum())


# ------------------------------------------------------------------ a slide on its table
#: The modules whose source a table depends on (with what they import): its cache key's.
TABLE_MODULES = (__name__,)
#: The libraries whose versions change a table.
TABLE_LIBRARIES = ("mujoco", "numba", "numpy", "scipy")


@dataclass
class OnTable:
    """A slide stepped along its phase table (:func:`slide_on_table`): the table (or the
    blend of two), the runner of the steps solved off it (None where every step was read
    off), the warnings so far and the record (loads, forces, x_pad, stopped_at_s, wall_s,
    drag_sum, drag_steps), with how many of ``steps`` were read off the table."""

    table: PhaseTable | Blend
    runner: Runner | None
    warnings: list[str]
    record: tuple
    tabled: int
    steps: int
    made: int

    def describe(self) -> str:
        t = self.table
        made = f"{self.made} of its tables solved for it" if self.made else "its tables reused"
        out = f"{t.describe()}, {t.solves} solves ({made}); {self.tabled} of {self.steps} steps read off it"
        return out + ("" if self.runner is None else f", the rest: {self.runner.describe()}")


def slide_on_table(
    slide: Slide,
    proto: Protocol,
    fid: Fidelity,
    window: SlideWindow,
    plan: PhasePlan,
    press: Callable,
    cache,
) -> OnTable:
    """Step ``slide`` (drawn as ``proto``, at ``fid``) along its phase table
    (:func:`table_for`); ``press()`` approaches and presses the slide's own runner as the
    per-step slide does (called only where the window leaves the plan's interior)."""
    table, made = table_for(slide, proto, fid, plan, cache)
    lo, hi = travel(window, proto)
    over = 2 * proto.speed_m_s * fid.dt_s  # a stroke stops on the step past its limit
    if plan.covers(lo - over) and plan.covers(hi + over):
        runner, warnings = None, list(fid.warnings)
        dyn = Glide(*dynamics_for(slide, proto, fid, window.x_start_m, cache))
    else:
        pressed = press()
        runner = dyn = pressed.runner
        warnings = pressed.warnings
    record = slide_tabled(
        table,
        dyn,
        window,
        proto,
        fid.steps_per_sample,
        fid.dt_s,
        slide.pad.friction,
        slide.pad.thickness_m,
    )
    steps = window.n_samples * fid.steps_per_sample + 1
    return OnTable(table, runner, warnings, record[:7], record[7], steps, made)


def table_for(
    slide: Slide, proto: Protocol, fid: Fidelity, plan: PhasePlan, cache
) -> tuple[PhaseTable | Blend, int]:
    """``(table, made)``: the slide's phase table at its force, and how many tables were
    solved for it (the rest came from this process or ``cache``). Where the slides of a set
    share tables (:func:`~sim_tactile.sim.plan.phase.tables_shared`), the line between the
    tables at the two force levels on either side of the slide's force
    (:func:`~sim_tactile.sim.plan.phase.force_levels`), else the table at its own force."""
    levels = (
        force_levels(proto.force_n)
        if tables_shared(plan, slide.protocol)
        else [(proto.force_n, 1.0)]
    )
    tables, made = [], 0
    for force, _ in levels:
        key = table_key(slide, fid, plan, force)
        build = lambda f=force: solve_table(slide, proto, fid, plan, f, cache)  # noqa: E731
        table, new = kept_table(key, build, cache)
        tables.append(table)
        made += new
    if len(tables) == 1 and levels[0][0] == proto.force_n:
        return tables[0], made
    return Blend(tuple(tables), tuple(w for _, w in levels), tuple(f for f, _ in levels)), made


def table_key(slide: Slide, fid: Fidelity, plan: PhasePlan, force_n: float) -> str:
    """The content key of a table: everything it depends on (the plate, the sensor and pad,
    the node grid and skin model, the knobs of how a step is solved, the plan, the force),
    the code that solves it and the BLAS kernel; nothing of the slide's speed, step, seed or
    window, which the table does not depend on."""
    opts = {k: v for k, v in keyed(slide.how).items() if k not in ("path", "solve_every")}
    if not solved_spectrally(fid, slide.pad, slide.how.skin_solver):
        opts.pop("device", None)  # a dense skin's table is solved on the CPU either way
    grid = {
        k: getattr(fid, k)
        for k in ("level", "pitch_m", "pitch_y_m", "winkler_k_pa_per_m", "clipped", "wall_m")
    }
    return content_hash(
        {
            "what": "phase table",
            "plate": slide.plate.params(),
            "sensor": slide.sensor_def.to_json(),
            "pad": slide.pad.to_json(),
            "grid": grid,
            "options": opts,
            "plan": [plan.period_m, plan.x_lo, plan.x_hi, plan.x_ref, plan.y_m, plan.span],
            "force_n": float(force_n),
            "code": code_version(*TABLE_MODULES, libraries=TABLE_LIBRARIES),
            "blas": blas_kernel(),
        }
    )


def solve_table(
    slide: Slide, proto: Protocol, fid: Fidelity, plan: PhasePlan, force_n: float, cache
) -> PhaseTable:
    """The table of ``plan`` at ``force_n``, solved in a scene of its own: the pad at the
    plan's reference and offset, a fresh held step (so the table does not depend on which
    slide asks for it)."""
    at = replace(proto, offset_y_m=plan.y_m, force_n=force_n)
    scene = runner_for(slide, at, fid, plan.x_ref, cache)
    many = batched_held(scene.hold, slide.how.device)
    mirror = None
    centre = mirror_centre(slide.plate, plan)
    write = None if centre is None else mirrored_loads(scene.hold, scene.collider, scene.skin)
    if write is not None:
        mirror = (centre - plan.x_ref, write)
    return tabulate(
        scene.hold,
        scene.d_dyn.qpos,
        scene._jx,
        scene._jz,
        plan.x_ref,
        scene.z0,
        plan,
        force_n / scene.s.grid.area_m2,
        scene.s.layout.n,
        fid.pitch_m,
        check=lambda z, f, top: scene.check_held(z, force_n, f, top),
        many=many,
        mirror=mirror,
        finest=span_fraction(slide.plate),
    )
