"""The press-and-slide protocol: approach, press under force control, settle, slide, record.

:func:`simulate` runs one slide and returns a :class:`~sim_tactile.records.Recording` of each
taxel's output: the sensor's transducer and seeded imperfections on the normal load, or with
``ideal=True`` the noise-free normal load [N]. Each sample is the load averaged over its
period (:class:`~.step.sampling.SampleAverager`: anti-aliasing from the full simulation rate). The phases are
named functions over one :class:`~.step.runner.Runner`; every step checks for NaN, runaway and a
skin pressed to the bottom, every sample checks MuJoCo's warnings, and any of these stops the
run with a PhysicsError naming the cause.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError, PhysicsError
from ..plates import Plate, get_plate
from ..records import Recording
from ..scene.model import give_back
from ..sensors import Finger, Layout, Sensor, check_pad
from .micro import micro_loads
from .plan.fidelity import Fidelity
from .plan.options import StepOptions
from .plan.protocol import (
    APPROACH_SPEED,
    Protocol,
    SlideWindow,
)
from .plan.slide import Slide
from .step.build import runner_for
from .step.held_run import held_slide
from .step.phase_table import SETTLE_M, SETTLE_STEPS
from .step.runner import Runner, drag_factor, drag_warning
from .step.sampling import (
    SampleAverager,
    SimResult,
    fill_between,
    sample_means,
    sample_x,
    sensor_output,
    solved_steps,
    versions,
)
from .step.strokes import Strokes
from .step.tabled import slide_on_table

#: A slide whose mean normal force strays further than this from the target is flagged.
FORCE_TOLERANCE = 0.05
#: Halvings of an approach step that find the touch under position control (2 ms steps at
#: 10 mm/s: 20 um / 2^30, below a nanometre).
TOUCH_ITER = 30
#: Longest approach [s] before the run stops (the pad never reached the plate).
APPROACH_TIMEOUT_S = 2.0
#: Longest extra settling [s] after the settle phase, and the settled band (force within
#: 1% of the command, the bone slower than 0.1 mm/s).
SETTLE_EXTRA_S = 2.0
SETTLE_FORCE_TOL = 0.01
SETTLE_SPEED_M_S = 1e-4


def simulate(
    plate: Plate | str,
    sensor: Sensor | Layout | str = "grid3x3",
    *,
    protocol: Protocol | None = None,
    finger: Finger | None = None,
    fidelity: str | Fidelity = "auto",
    seed: int = 0,
    pitch_m: float | None = None,
    dt_s: float | None = None,
    ideal: bool = False,
    options: StepOptions | None = None,
    cache=None,
) -> SimResult:
    """Run one press-and-slide of ``sensor`` (a sensor, a sensor name, or a bare layout: its
    taxels, pad, transducer and rate) over ``plate`` and record each taxel: the
    :class:`~.plan.slide.Slide` of these arguments, :func:`run`.

    protocol: the slide (its rate defaults to the sensor's; jitters are drawn from ``seed``).
    finger: replaces the sensor's pad. fidelity: ``auto``, ``L0``-``L2`` or a Fidelity;
    ``pitch_m`` / ``dt_s`` force the node pitch and time step. ideal: record the noise-free
    normal loads [N] instead of the sensor's output. options: how each part of a step is
    computed (:class:`~.plan.options.StepOptions`).
    """
    return run(
        Slide(
            get_plate(plate) if isinstance(plate, str) else plate,
            sensor,
            protocol or Protocol(),
            seed,
            fidelity,
            ideal,
            finger,
            pitch_m,
            dt_s,
            options=options or StepOptions(),
        ),
        cache=cache,
    )


def run(slide: Slide, cache=None) -> SimResult:
    """Run the press-and-slide of ``slide`` on the finger scene and record each taxel (a
    slide on the probe rig runs by :func:`~.rig_sim.run_rig`). ``cache``: where the plate's
    artefacts and the skin's matrices are kept (an
    :class:`~sim_tactile.cache.ArtefactCache`; None: the default).

    BLAS runs single-threaded inside: the skin's systems are small, and threads only contend.
    """
    from ..hashing import one_blas_thread

    if slide.rig is not None:
        raise ConfigError(
            f"slide of {slide.named()} names a probe rig: run it with sim.rig_sim.run_rig"
        )
    with one_blas_thread():
        return _run(slide, cache)


@dataclass
class _Slide:
    """What the slide phase recorded: the sample means (T, N) and forces (T,), the pad's x at
    each sample's centre, when the stroke stopped at the plate's end, the loop's wall time."""

    loads: np.ndarray
    forces: np.ndarray
    x_pad: np.ndarray
    stopped_at_s: float | None
    wall_s: float
    drag_sum: float = 0.0
    drag_steps: int = 0


@dataclass
class Pressed:
    """A slide's set-up after the approach and the press, ready to slide (:func:`prepare`):
    the slide, its drawn protocol, fidelity and window, the runner and the warnings so far."""

    slide: Slide
    protocol: Protocol
    fidelity: Fidelity
    window: SlideWindow
    runner: Runner
    warnings: list[str]


def prepare(slide: Slide | Plate | str, *args, cache=None, **kwargs) -> Pressed:
    """The phases of :func:`run` before the slide: the scene, its skin and runner, the
    approach, the press and the settling; the runner is left pressed at the window's start.
    For benchmarks and scripts that drive the steps themselves. ``prepare(plate, sensor,
    **keywords)`` (as :func:`simulate` takes them) still works for one release, with a
    DeprecationWarning."""
    if not isinstance(slide, Slide):
        warnings.warn(
            "prepare(plate, sensor, ...) is deprecated; pass a Slide: "
            "prepare(Slide(plate, sensor, protocol, ...))",
            DeprecationWarning,
            stacklevel=2,
        )
        opts = kwargs.pop("options", None) or StepOptions()
        plate = get_plate(slide) if isinstance(slide, str) else slide
        sensor = args[0] if args else kwargs.pop("sensor", "grid3x3")
        protocol = kwargs.pop("protocol", None) or Protocol()
        slide = Slide(plate, sensor, protocol, options=opts, **kwargs)
    proto, fid, window = _planned(slide)
    return _press(slide, proto, fid, window, cache)


def _planned(slide: Slide) -> tuple[Protocol, Fidelity, SlideWindow]:
    """The slide's drawn protocol, its fidelity and its window."""
    check_pad(slide.layout, slide.pad)
    return slide.drawn(), slide.resolved, slide.window


def _press(slide: Slide, proto: Protocol, fid: Fidelity, window: SlideWindow, cache) -> Pressed:
    """The scene at the window's start, approached, pressed and settled."""
    runner = runner_for(slide, proto, fid, window.x_start_m, cache)
    warnings_ = list(fid.warnings)
    if proto.force_control == "position":
        _touch(runner, proto.force_n)  # then held at that height
    elif slide.held_press and runner.hold is not None:
        _held_press(runner, proto.force_n)
    else:
        _approach(runner, proto.force_n)
        warnings_ += _press_and_settle(runner, proto)
    return Pressed(slide, proto, fid, window, runner, warnings_)


def _run(slide: Slide, cache) -> SimResult:
    t_wall = time.perf_counter()
    plate, sensor, finger = slide.plate, slide.sensor_def, slide.pad
    proto, fid, window = _planned(slide)
    layout = sensor.layout
    opts = slide.how
    every = opts.solve_every
    plan = slide.table_plan()
    if plan is not None:
        press = lambda: _press(slide, proto, fid, window, cache)  # noqa: E731
        tabled = slide_on_table(slide, proto, fid, window, plan, press, cache)
        path, runner, warnings = tabled.describe(), tabled.runner, tabled.warnings
        slide_rec = _Slide(*tabled.record)
        every = 1
    else:
        pressed = _press(slide, proto, fid, window, cache)
        runner, warnings = pressed.runner, pressed.warnings
        runner.stepwise()
        path = "per-step"
        held = runner.hold is not None and proto.force_control != "position"
        compiled = held_slide(runner, window, proto, fid.steps_per_sample, every) if held else None
        if compiled is not None:
            slide_rec = _Slide(*compiled)
        elif every > 1 and held:
            slide_rec = _slide_sampled(runner, window, proto, fid.steps_per_sample, every)
        else:
            every = 1
            slide_rec = _slide(runner, window, proto, fid.steps_per_sample)
        slide_rec.drag_sum, slide_rec.drag_steps = runner.drag_sum, runner.n_slide_steps
    sim_s = window.n_samples / proto.rate_hz
    if slide_rec.stopped_at_s is not None:
        warnings.append(
            f"the stroke stopped at the plate's end after {slide_rec.stopped_at_s:.3g} s of the "
            f"{sim_s:.3g} s window ({proto.speed_m_s * 1e3:.3g} mm/s): the pad rested on flat "
            f"ground for the rest; a window of at most {slide_rec.stopped_at_s:.3g} s (duration_s), "
            "or a slower speed, keeps it on the plate"
        )
    if proto.force_control != "position":  # there the load follows the texture
        warnings += _force_warnings(slide_rec.forces, proto.force_n, proto.speed_m_s)
    warnings += [w for w in (drag_warning(proto.speed_m_s),) if w]
    out = slide_rec.loads
    # micro-roughness acts through the contact patch on top of the finger's simulation
    micro = micro_loads(plate, layout, slide_rec.x_pad, out > 1e-9, finger.e_star_pa, proto.rate_hz)
    if micro.any():
        out = np.maximum(out + micro, 0.0)
    out, units, transducer = sensor_output(out, sensor, proto.rate_hz, slide.seed, slide.ideal)
    times = (np.arange(window.n_samples) + 0.5) / proto.rate_hz
    wall = time.perf_counter() - t_wall
    meta = {
        **slide.meta_head(),
        "fidelity": fid.to_json(),
        "skin_problem": path if plan is not None else runner.describe(),
        "solve_every": every,
        "rate_hz": proto.rate_hz,
        "dt_s": fid.dt_s,
        "transducer": transducer,
        "micro_roughness": bool(micro.any()),
        "x_pad_m": slide_rec.x_pad.tolist(),
        "normal_force_n": slide_rec.forces.tolist(),
        "mean_drag_n": slide_rec.drag_sum / max(slide_rec.drag_steps, 1),
        "drag_factor": drag_factor(proto.speed_m_s),
        "drag_regularised": drag_warning(proto.speed_m_s) is not None,
        "versions": versions(),
        # the spectral solve's tolerance where it is not its reference (older recordings' meta
        # is unchanged)
        **({"solve_tol": opts.solve_tol} if opts.solve_tol is not None else {}),
        "warnings": warnings,
        "sim_s": sim_s,
        "wall_s": wall,
        "x_start_m": window.x_start_m,
        "slide_wall_s": slide_rec.wall_s,
        "steps": window.n_samples * fid.steps_per_sample,
    }
    rec = Recording(out.astype(np.float32), times, layout.positions, units=units, meta=meta)
    if runner is not None:  # it steps no more: the next slide of its scene places its models
        give_back(runner.s, runner.d_dyn)
    return SimResult(rec, fid, sim_s, wall, warnings)


def _approach(runner: Runner, force_n: float, touch: float = 0.2) -> None:
    """Lower the pad at :data:`APPROACH_SPEED` until the skin carries ``touch`` times the
    force (a fifth before a press; the whole of it under position control)."""
    t = 0.0
    while True:
        Fs = runner.step(z_vel=-APPROACH_SPEED, force_cmd=force_n, slide_v=0.0)
        t += runner.dt
        if Fs >= touch * force_n:
            return
        if t > APPROACH_TIMEOUT_S:
            raise PhysicsError(
                f"the pad did not reach the plate within {APPROACH_TIMEOUT_S:g} s of approach"
            )


def _touch(runner: Runner, force_n: float) -> None:
    """Lower the pad until the skin carries ``force_n``, then bisect its height to where it
    carries that force within :data:`TOUCH_ITER` halvings of an approach step (the approach
    alone stops up to a whole step, 20 um at 2 ms, past it: under position control that
    height is the slide's, and a marginal contact's load moves with it)."""
    _approach(runner, force_n, touch=1.0)
    h, above = APPROACH_SPEED * runner.dt, True
    for _ in range(TOUCH_ITER):
        h /= 2
        Fs = runner.step(z_vel=(h if above else -h) / runner.dt, force_cmd=force_n, slide_v=0.0)
        above = Fs >= force_n
    if not above:  # end on the side that carries the force
        runner.step(z_vel=-h / runner.dt, force_cmd=force_n, slide_v=0.0)


def _held_press(runner: Runner, force_n: float) -> None:
    """The press under quasi-static force control as one equilibrium: the held step at the
    force, from above the plate, taken again from the height it ends at until that height
    holds (:data:`~.step.phase_table.SETTLE_M`). The approach, the ramp and the settling
    reach the same equilibrium step by step (the skin keeps no history at rest, and the pad
    does not move along the slide), at some 150-300 held steps of a slide's cost."""
    for _ in range(SETTLE_STEPS):
        z = runner.z_m
        runner.step(force_cmd=force_n)
        if abs(runner.z_m - z) <= SETTLE_M:
            return


def _press_and_settle(runner: Runner, proto: Protocol) -> list[str]:
    """Ramp the force from a fifth to the command over ``press_s``, hold it for
    ``settle_s``, then until it settles; a warning if it does not."""
    F, dt = proto.force_n, runner.dt
    n_press = max(1, round(proto.press_s / dt))
    for k in range(n_press):
        runner.step(force_cmd=F * (0.2 + 0.8 * (k + 1) / n_press))
    for _ in range(max(1, round(proto.settle_s / dt))):
        Fs = runner.step(force_cmd=F)
    for _ in range(round(SETTLE_EXTRA_S / dt)):
        if abs(Fs - F) <= SETTLE_FORCE_TOL * F and abs(runner.z_speed_m_s) < SETTLE_SPEED_M_S:
            return []
        Fs = runner.step(force_cmd=F)
    return [f"press force did not settle within {SETTLE_FORCE_TOL:.0%} of {F:g} N (now {Fs:.4g} N)"]


def _slide(runner: Runner, window: SlideWindow, proto: Protocol, n_sub: int) -> _Slide:
    """Slide along the window's strokes under the held force, averaging each sample."""
    n = window.n_samples
    avg = SampleAverager(n, runner.s.layout.n, n_sub)
    x_pad = np.empty(n)
    strokes = Strokes(window, proto.speed_m_s, runner.dt)
    now = np.zeros(runner.s.layout.n)  # this step's taxel loads
    F, x0 = proto.force_n, window.x_start_m
    # under position control the pad keeps its height (moved kinematically by nothing)
    z_vel = 0.0 if proto.force_control == "position" else None

    def step() -> float:
        v = strokes.command(x0 + runner.x_m)
        return runner.step(force_cmd=F, slide_v=v, z_vel=z_vel, taxel_out=now)

    t0 = time.perf_counter()
    for s in range(n):
        for k in range(n_sub):
            f = step()
            avg.add(s, k, now, f)
        avg.end_sample()
        x_pad[s] = x0 + runner.x_m - 0.5 * strokes.v / proto.rate_hz
        runner.check_warnings()
    avg.finish(now, step())  # the last period's end point
    return _Slide(avg.loads, avg.forces, x_pad, strokes.stopped_at_s, time.perf_counter() - t0)


def _slide_sampled(
    runner: Runner, window: SlideWindow, proto: Protocol, n_sub: int, every: int
) -> _Slide:
    """:func:`_slide` with the skin solved at every ``every``-th step only: the finger's
    dynamics steps at every step (:meth:`~.step.runner.Runner.coast` between solves, the
    bone holding the height the last solve found), and the taxel loads and the force of the
    steps between two solves lie on the line between them (in the step's index: the pad's
    travel, which the arm's servo keeps even). The samples average the same steps as
    :func:`_slide`'s; the error of the line against the per-step solve is measured per task
    scene (``perf/bench_response.py``)."""
    n = window.n_samples
    n_tax = runner.s.layout.n
    total = n * n_sub + 1  # the steps the samples read (the last one closes the last sample)
    loads = np.empty((total, n_tax))
    forces = np.empty(total)
    x_after = np.empty(total)  # the pad's x on the plate after each step
    v_after = np.empty(total)  # the stroke's speed command of each step
    strokes = Strokes(window, proto.speed_m_s, runner.dt)
    F, x0 = proto.force_n, window.x_start_m
    t0 = time.perf_counter()
    solved = solved_steps(total, every)
    g = -1  # the last step solved
    for j in solved.tolist():
        for i in range(g + 1, j):  # the dynamics alone
            runner.coast(strokes.command(x0 + runner.x_m))
            x_after[i], v_after[i] = x0 + runner.x_m, strokes.v
        forces[j] = runner.step(
            force_cmd=F, slide_v=strokes.command(x0 + runner.x_m), taxel_out=loads[j]
        )
        x_after[j], v_after[j] = x0 + runner.x_m, strokes.v
        runner.check_warnings()
        g = j
    fill_between(loads, forces, solved)  # the steps between on the line between solves
    means, mean_forces = sample_means(loads, forces, n, n_sub)  # as _slide averages them
    x_pad = sample_x(x_after, v_after, n, n_sub, proto.rate_hz)
    return _Slide(means, mean_forces, x_pad, strokes.stopped_at_s, time.perf_counter() - t0)


def _force_warnings(forces: np.ndarray, target_n: float, speed_m_s: float) -> list[str]:
    """Say when the press force was not held during the slide: the force loop lets the pad
    leave the plate behind sharp features and skim their tops at high speed, so the taxels
    then feel another load than the protocol's (measured, not hidden)."""
    out = []
    mean = float(np.mean(forces))
    off = float(np.mean(forces < 0.1 * target_n))
    if abs(mean / target_n - 1.0) > FORCE_TOLERANCE:
        out.append(
            f"mean normal force over the slide {mean:.3g} N is {100 * (mean / target_n - 1):+.0f}% "
            f"off the target {target_n:g} N at {speed_m_s * 1e3:g} mm/s: the force loop does not "
            f"hold the press (the pad skims the features or bounces); slow down or compare "
            f"recordings by their per-sample normal force (meta normal_force_n)"
        )
    if off > 0.02:
        out.append(
            f"the pad was off the plate (normal force < 10% of {target_n:g} N) in "
            f"{100 * off:.1f}% of the samples; a slower speed or a larger force keeps it on"
        )
    return out
