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

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import PhysicsError
from ..plates import Plate, get_plate, height_at, surface_of
from ..records import Recording
from ..scene.model import build_scene
from ..scene.nodes import SkinGrid, skin_grid
from ..sensors import Finger, Layout, Sensor, check_pad, resolve_sensor
from .collide.choose import make_collider
from .micro import micro_loads
from .plan.fidelity import Fidelity, choose_fidelity, flat_stiffness
from .plan.protocol import (
    APPROACH_CLEARANCE_M,
    APPROACH_SPEED,
    SPEED_RAMP_S,
    Protocol,
    SlideWindow,
)
from .skin.models import make_skin
from .step.choose import make_held_step
from .step.runner import Runner, StepOptions, drag_factor, drag_warning
from .step.sampling import SampleAverager, SimResult, sensor_output, versions, window_meta

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
    taxels, pad, transducer and rate) over ``plate`` and record each taxel.

    protocol: the slide (its rate defaults to the sensor's; jitters are drawn from ``seed``).
    finger: replaces the sensor's pad. fidelity: ``auto``, ``L0``-``L2`` or a Fidelity;
    ``pitch_m`` / ``dt_s`` force the node pitch and time step. ideal: record the noise-free
    normal loads [N] instead of the sensor's output. options: which implementation of each
    part of a step runs (:class:`~.step.runner.StepOptions`).

    BLAS runs single-threaded inside: the skin's systems are small, and threads only contend.
    """
    from ..hashing import one_blas_thread

    with one_blas_thread():
        return _simulate(
            plate,
            sensor,
            protocol=protocol,
            finger=finger,
            fidelity=fidelity,
            seed=seed,
            pitch_m=pitch_m,
            dt_s=dt_s,
            ideal=ideal,
            options=options or StepOptions(),
            cache=cache,
        )


@dataclass
class _Slide:
    """What the slide phase recorded: the sample means (T, N) and forces (T,), the pad's x at
    each sample's centre, when the stroke stopped at the plate's end, the loop's wall time."""

    loads: np.ndarray
    forces: np.ndarray
    x_pad: np.ndarray
    stopped_at_s: float | None
    wall_s: float


@dataclass
class Pressed:
    """A slide's set-up after the approach and the press, ready to slide (:func:`prepare`):
    the plate, sensor, pad, nominal and drawn protocols, fidelity, window, the runner and the
    warnings so far."""

    plate: Plate
    sensor: Sensor
    finger: Finger
    nominal: Protocol
    protocol: Protocol
    fidelity: Fidelity
    window: SlideWindow
    runner: Runner
    warnings: list[str]


def prepare(
    plate: Plate | str,
    sensor: Sensor | Layout | str = "grid3x3",
    *,
    protocol: Protocol | None = None,
    finger: Finger | None = None,
    fidelity: str | Fidelity = "auto",
    seed: int = 0,
    pitch_m: float | None = None,
    dt_s: float | None = None,
    options: StepOptions | None = None,
    cache=None,
) -> Pressed:
    """The phases of :func:`simulate` before the slide (arguments as there): the scene, its
    skin and runner, the approach, the press and the settling; the runner is left pressed at
    the window's start. For benchmarks and scripts that drive the steps themselves."""
    plate = get_plate(plate) if isinstance(plate, str) else plate
    sensor = resolve_sensor(sensor)
    layout = sensor.layout
    finger = finger or sensor.finger
    nominal = (protocol or Protocol()).at_rate(sensor.rate_hz)
    proto = nominal.drawn(seed)
    check_pad(layout, finger)
    fid = choose_fidelity(plate, layout, finger, proto, fidelity, pitch_m=pitch_m, dt_s=dt_s)
    window = SlideWindow.of(plate, finger.patch_m[0], proto)
    runner = _setup(plate, layout, finger, proto, fid, window, options or StepOptions(), cache)
    warnings = list(fid.warnings)
    if proto.force_control == "position":
        _touch(runner, proto.force_n)  # then held at that height
    else:
        _approach(runner, proto.force_n)
        warnings += _press_and_settle(runner, proto)
    return Pressed(plate, sensor, finger, nominal, proto, fid, window, runner, warnings)


def _simulate(
    plate, sensor, *, protocol, finger, fidelity, seed, pitch_m, dt_s, ideal, options, cache
) -> SimResult:
    t_wall = time.perf_counter()
    pressed = prepare(
        plate,
        sensor,
        protocol=protocol,
        finger=finger,
        fidelity=fidelity,
        seed=seed,
        pitch_m=pitch_m,
        dt_s=dt_s,
        options=options,
        cache=cache,
    )
    plate, sensor, finger = pressed.plate, pressed.sensor, pressed.finger
    nominal, proto, fid = pressed.nominal, pressed.protocol, pressed.fidelity
    window, runner, warnings = pressed.window, pressed.runner, pressed.warnings
    layout = sensor.layout
    opts = options or StepOptions()
    every = opts.solve_every
    if every > 1 and runner.hold is not None and proto.force_control != "position":
        slide = _slide_sampled(runner, window, proto, fid.steps_per_sample, every)
    else:
        every = 1
        slide = _slide(runner, window, proto, fid.steps_per_sample)
    sim_s = window.n_samples / proto.rate_hz
    if slide.stopped_at_s is not None:
        warnings.append(
            f"the stroke stopped at the plate's end after {slide.stopped_at_s:.3g} s of the "
            f"{sim_s:.3g} s window ({proto.speed_m_s * 1e3:.3g} mm/s): the pad rested on flat "
            f"ground for the rest; a window of at most {slide.stopped_at_s:.3g} s (duration_s), "
            "or a slower speed, keeps it on the plate"
        )
    if proto.force_control != "position":  # there the load follows the texture
        warnings += _force_warnings(slide.forces, proto.force_n, proto.speed_m_s)
    warnings += [w for w in (drag_warning(proto.speed_m_s),) if w]
    out = slide.loads
    # micro-roughness acts through the contact patch on top of the finger's simulation
    micro = micro_loads(plate, layout, slide.x_pad, out > 1e-9, finger.e_star_pa, proto.rate_hz)
    if micro.any():
        out = np.maximum(out + micro, 0.0)
    out, units, transducer = sensor_output(out, sensor, proto.rate_hz, seed, ideal)
    times = (np.arange(window.n_samples) + 0.5) / proto.rate_hz
    wall = time.perf_counter() - t_wall
    meta = {
        **window_meta(plate, sensor, finger, proto, nominal, seed),
        "fidelity": fid.to_json(),
        "skin_problem": runner.describe(),
        "solve_every": every,
        "rate_hz": proto.rate_hz,
        "dt_s": fid.dt_s,
        "transducer": transducer,
        "micro_roughness": bool(micro.any()),
        "x_pad_m": slide.x_pad.tolist(),
        "normal_force_n": slide.forces.tolist(),
        "mean_drag_n": runner.drag_sum / max(runner.n_slide_steps, 1),
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
        "slide_wall_s": slide.wall_s,
        "steps": window.n_samples * fid.steps_per_sample,
    }
    rec = Recording(out.astype(np.float32), times, layout.positions, units=units, meta=meta)
    return SimResult(rec, fid, sim_s, wall, warnings)


def _setup(plate, layout, finger, proto, fid, window, options, cache) -> Runner:
    """The scene at the slide's start (the pad above the plate's highest point under it), its
    skin model and the runner that steps it."""
    grid = skin_grid(finger, fid.pitch_m, fid.pitch_y_m)
    z0 = APPROACH_CLEARANCE_M + max(
        0.0, float(np.nanmax(_plate_heights(plate, grid, window.x_start_m, proto.offset_y_m)))
    )
    omega_guess = math.sqrt(
        flat_stiffness(finger, fid.coupled, fid.winkler_k_pa_per_m) / finger.bone_mass_kg
    )
    quasi_static = proto.force_control == "quasi-static"
    scene = build_scene(
        plate,
        finger,
        grid,
        layout,
        dt_s=fid.dt_s,
        x0_m=window.x_start_m,
        y0_m=proto.offset_y_m,
        z0_m=z0,
        z_damping=2.0 * omega_guess * finger.bone_mass_kg,  # critical at the flat pad
        node_margin_m=surface_of(plate).margin_m if quasi_static else 0.0,
        cache=cache,
    )
    skin = make_skin(
        fid.level,
        grid,
        finger,
        winkler_k_pa_per_m=fid.winkler_k_pa_per_m,
        solver=options.skin_solver,
        tol=options.solve_tol,
        cache=cache,
    )
    collider = make_collider(scene, options.primitive_collider)
    hold = make_held_step(
        scene,
        skin,
        collider,
        fid,
        plate=plate,
        layout=layout,
        finger=finger,
        quasi_static=quasi_static,
        x0_m=window.x_start_m,
        y0_m=proto.offset_y_m,
        z0_m=z0,
        compiled=options.compiled_hold,
        reduce=options.reduce_skin,
    )
    return Runner(
        scene,
        skin,
        fid,
        finger,
        fid.dt_s,
        collider=collider,
        z0_m=z0,
        plate=plate,
        quasi_static=quasi_static,
        hold=hold,
    )


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


class _Strokes:
    """The slide's speed command along the window's strokes: ramped at the start of each
    stroke, zero once the pad reaches the plate's end (``stopped_at_s``)."""

    def __init__(self, window: SlideWindow, speed_m_s: float, dt: float) -> None:
        self.w, self.speed, self.dt = window, speed_m_s, dt
        self.i = 0
        self.sign = window.strokes[0][2]
        self.t_stroke = 0.0
        self.t = 0.0
        self.stopped_at_s: float | None = None
        self.v = 0.0

    def command(self, x: float) -> float:
        """The speed command [m/s] for the pad at ``x`` (the plate frame) for the next step."""
        w = self.w
        if self.sign * (x - w.strokes[self.i][1]) >= 0 and self.i + 1 < len(w.strokes):
            self.i += 1
            self.sign = w.strokes[self.i][2]
            self.t_stroke = 0.0
        v = self.sign * self.speed * min(1.0, self.t_stroke / SPEED_RAMP_S)
        if self.sign * x >= w.x_limit_m:
            v = 0.0
            if self.stopped_at_s is None:
                self.stopped_at_s = self.t
        self.t += self.dt
        self.t_stroke += self.dt
        self.v = v
        return v


def _slide(runner: Runner, window: SlideWindow, proto: Protocol, n_sub: int) -> _Slide:
    """Slide along the window's strokes under the held force, averaging each sample."""
    n = window.n_samples
    avg = SampleAverager(n, runner.s.layout.n, n_sub)
    x_pad = np.empty(n)
    strokes = _Strokes(window, proto.speed_m_s, runner.dt)
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
    strokes = _Strokes(window, proto.speed_m_s, runner.dt)
    F, x0 = proto.force_n, window.x_start_m
    t0 = time.perf_counter()
    g = -1  # the last step solved
    while g < total - 1:
        m = 1 if g < 0 else min(every, total - 1 - g)
        for i in range(g + 1, g + m):  # the dynamics alone
            runner.coast(strokes.command(x0 + runner.x_m))
            x_after[i], v_after[i] = x0 + runner.x_m, strokes.v
        j = g + m
        forces[j] = runner.step(
            force_cmd=F, slide_v=strokes.command(x0 + runner.x_m), taxel_out=loads[j]
        )
        x_after[j], v_after[j] = x0 + runner.x_m, strokes.v
        if g >= 0 and m > 1:  # the steps between on the line from g to j
            w = (np.arange(1, m) / m)[:, None]
            loads[g + 1 : j] = (1.0 - w) * loads[g] + w * loads[j]
            forces[g + 1 : j] = (1.0 - w[:, 0]) * forces[g] + w[:, 0] * forces[j]
        runner.check_warnings()
        g = j
    avg = SampleAverager(n, n_tax, n_sub)
    for i in range(total - 1):  # the samples as _slide averages them
        s, k = divmod(i, n_sub)
        avg.add(s, k, loads[i], forces[i])
        if k == n_sub - 1:
            avg.end_sample()
    avg.finish(loads[total - 1], forces[total - 1])
    last = np.arange(1, n + 1) * n_sub - 1  # each sample's last step
    x_pad = x_after[last] - 0.5 * v_after[last] / proto.rate_hz
    return _Slide(avg.loads, avg.forces, x_pad, strokes.stopped_at_s, time.perf_counter() - t0)


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


def _plate_heights(plate: Plate, grid: SkinGrid, x: float, y: float) -> np.ndarray:
    return height_at(plate, grid.xy[:, 0] + x, grid.xy[:, 1] + y) - grid.z
