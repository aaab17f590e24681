"""The press-and-slide protocol: approach, press under force control, settle, slide, record.

:func:`simulate` runs one slide and returns a :class:`~sim_tactile.records.Recording` of the
normal load on each taxel [N], averaged over each sample period (anti-aliasing from the full
simulation rate). Every step checks for NaN, runaway and a skin pressed to the bottom; every
sample checks MuJoCo's warnings; the coupling of the quasi-static skin to the bone is checked
against its stability limit. Any of these stops the run with a PhysicsError naming the cause.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field, replace

import mujoco
import numpy as np

from .. import __version__
from .. import _validate as v
from ..errors import ConfigError, PhysicsError
from ..plates import Plate, get_plate
from ..records import Recording
from ..scene.model import build_scene
from ..scene.nodes import skin_grid
from ..sensors import Finger, Layout, Sensor, resolve_sensor
from . import contact
from ._readout import penetration_map
from .collide import PrimitiveCollider
from .fidelity import Fidelity, choose_fidelity, flat_stiffness
from .held import _QS_COLLISIONS, HeldSkin
from .micro import micro_loads

#: Largest omega * dt of the explicit skin-to-bone coupling before the run is refused; the
#: semi-implicit scheme is stable below 2, this keeps a margin of 2.
MAX_OMEGA_DT = 1.0
#: Approach speed [m/s] and the clearance the pad starts at above the plate [m].
APPROACH_SPEED = 0.01
APPROACH_CLEARANCE_M = 0.3e-3
#: Velocity of the friction regularisation [m/s]: Coulomb drag mu*N*tanh(v / V_STICK).
V_STICK = 1e-3


#: How the press force is held during press, settle and slide (``Protocol.force_control``):
#:
#: - ``dynamic``: the bone is a mass on the press joint, pushed by the commanded force against
#:   the skin's load, with damping critical at the flat pad's stiffness (MuJoCo integrates
#:   it). The force overshoots where the load changes fast (a ridge's edge) and the pad leaves
#:   the plate behind tall features; the coupling limits the time step (omega * dt).
#: - ``quasi-static``: an ideal force controller: every step the pad is moved to the height at
#:   which the skin carries exactly the commanded force (:meth:`contact.ActiveSet.solve_force`
#:   on the collider's depths, a margin of :data:`QS_MARGIN_M` lets nodes join), so the
#:   load is a function of the pad's position alone: no transients and no step limit from
#:   the coupling. Needs the coupled skin (L1, L2).
FORCE_CONTROLS = ("dynamic", "quasi-static")
#: Collider margin [m] of the skin nodes under quasi-static force control: nodes this far
#: above the plate are reported, so they can join the contact when the pad sinks; a step
#: that would move the pad further than this is re-collided at the new height.
QS_MARGIN_M = 0.5e-3
#: The margin where MuJoCo's collider serves (meshes, cylinders, height fields): each node
#: within it is a contact MuJoCo must generate, which on a height field filled the contact
#: buffer at 0.5 mm; a step that sinks further is re-collided.
QS_MARGIN_MUJOCO_M = 0.1e-3


@dataclass(frozen=True)
class Protocol:
    """The slide protocol, SI units. ``duration_s`` None: cross the whole textured area,
    starting and ending with the pad on flat ground."""

    speed_m_s: float = 0.06
    force_n: float = 1.0
    duration_s: float | None = None
    rate_hz: float = 100.0
    press_s: float = 0.1
    settle_s: float = 0.2
    passes: int = 1
    return_stroke: bool = False
    offset_y_m: float = 0.0
    speed_jitter: float = 0.0  # relative standard deviation, per repetition
    force_jitter: float = 0.0
    offset_jitter_m: float = 0.0
    force_control: str = "quasi-static"

    def __post_init__(self) -> None:
        v.in_range("speed_m_s", self.speed_m_s, 0.0, 1.0, unit="m/s")
        v.in_range("force_n", self.force_n, 1e-3, 50.0, lo_open=False, unit="N")
        if self.duration_s is not None:
            v.in_range("duration_s", self.duration_s, 1e-3, 600.0, unit="s")
        v.in_range("rate_hz", self.rate_hz, 1.0, 100_000.0, unit="Hz")
        v.in_range("press_s", self.press_s, 0.0, 10.0, unit="s")
        v.in_range("settle_s", self.settle_s, 0.0, 10.0, unit="s")
        v.integer("passes", self.passes, 1, 100)
        v.in_range("offset_y_m", self.offset_y_m, -0.05, 0.05, unit="m")
        v.in_range("speed_jitter", self.speed_jitter, 0.0, 0.5)
        v.in_range("force_jitter", self.force_jitter, 0.0, 0.5)
        v.in_range("offset_jitter_m", self.offset_jitter_m, 0.0, 0.01, unit="m")
        v.one_of("force_control", self.force_control, FORCE_CONTROLS)

    def varied(self, rng: np.random.Generator) -> Protocol:
        """This protocol with speed, force and offset drawn around their nominal values."""
        return replace(
            self,
            speed_m_s=self.speed_m_s
            * float(np.clip(1 + self.speed_jitter * rng.standard_normal(), 0.2, 2)),
            force_n=self.force_n
            * float(np.clip(1 + self.force_jitter * rng.standard_normal(), 0.2, 2)),
            offset_y_m=self.offset_y_m + self.offset_jitter_m * float(rng.standard_normal()),
            speed_jitter=0.0,
            force_jitter=0.0,
            offset_jitter_m=0.0,
        )


@dataclass
class SimResult:
    recording: Recording
    fidelity: Fidelity
    sim_s: float
    wall_s: float
    warnings: list[str] = field(default_factory=list)


def _skin_pressure(scene, fid: Fidelity, pen: np.ndarray):
    if scene.C is None:
        return contact.winkler(pen, fid.winkler_k_pa_per_m)
    p, _ = scene.solver.solve(pen)
    return p


def _contact_stiffness(scene, fid: Fidelity, p: np.ndarray) -> float:
    """dF/dz of the skin at the current contact set [N/m]."""
    A = scene.grid.area_m2
    if scene.C is None:
        return fid.winkler_k_pa_per_m * A * float(np.count_nonzero(p))
    return A * scene.solver.stiffness_per_area()


def simulate(
    plate: Plate | str,
    layout: Sensor | Layout | str = "grid3x3",
    *,
    protocol: Protocol | None = None,
    finger: Finger | None = None,
    fidelity: str | Fidelity = "auto",
    seed: int = 0,
    pitch_m: float | None = None,
    dt_s: float | None = None,
    ideal: bool = False,
    cache=None,
) -> SimResult:
    """Run one press-and-slide and record each taxel: its sensor's output (``ideal=False``,
    a named sensor: transducer and seeded imperfections) or the noise-free normal load [N].
    A named sensor also brings its pad (``finger``, unless given).

    BLAS runs single-threaded inside: the skin's systems are small, and threads only contend.
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        return _simulate(
            plate,
            layout,
            protocol=protocol,
            finger=finger,
            fidelity=fidelity,
            seed=seed,
            pitch_m=pitch_m,
            dt_s=dt_s,
            ideal=ideal,
            cache=cache,
        )


def _simulate(
    plate, layout, *, protocol, finger, fidelity, seed, pitch_m, dt_s, ideal, cache
) -> SimResult:
    t_wall = time.perf_counter()
    plate = get_plate(plate) if isinstance(plate, str) else plate
    sensor = resolve_sensor(layout)
    layout = sensor.layout
    finger = finger or sensor.finger
    protocol = protocol or Protocol(rate_hz=layout.rate_hz)
    v.integer("seed", seed, 0, 2**63 - 1)
    rng = np.random.default_rng(seed)
    proto = protocol.varied(rng)
    ex, ey = layout.extent_m
    px, py = finger.patch_m
    if ex > px / 2 + 1e-9 or ey > py / 2 + 1e-9:
        raise ConfigError(
            f"layout {layout.name!r} spans +-({ex:g}, {ey:g}) m, beyond the pad's "
            f"+-({px / 2:g}, {py / 2:g}) m; valid: taxels on the pad"
        )
    fid = choose_fidelity(plate, layout, finger, proto, fidelity, pitch_m=pitch_m, dt_s=dt_s)
    warnings = list(fid.warnings)
    grid = skin_grid(finger, fid.pitch_m, fid.pitch_y_m)
    n_sub = fid.steps_per_sample
    dt = 1.0 / (proto.rate_hz * n_sub)

    # where the slide starts and ends: pad on flat ground on both sides of the texture
    margin = 2e-3
    x_start = -(plate.area_length_m / 2 + px / 2 + margin)
    x_end = -x_start
    if plate.length_m / 2 < x_end + 1e-9:
        raise ConfigError(
            f"plate {plate.name or plate.hash} ({plate.length_m:g} m long) is too short for a "
            f"{px:g} m pad to enter and leave the textured area on flat ground"
        )
    # a stroke that would carry the pad off the plate (a long window, a fast draw of the
    # speed) stops there: the pad rests on flat ground for the rest of the window
    x_limit = max(x_end, plate.length_m / 2 - px / 2)
    z0 = APPROACH_CLEARANCE_M + max(
        0.0, float(np.nanmax(_plate_heights(plate, grid, x_start, proto.offset_y_m)))
    )
    omega_guess = math.sqrt(
        flat_stiffness(finger, fid.coupled, fid.winkler_k_pa_per_m) / finger.bone_mass_kg
    )
    z_damp = 2.0 * 1.0 * omega_guess * finger.bone_mass_kg  # critical at the flat-pad stiffness
    scene = build_scene(
        plate,
        finger,
        grid,
        layout,
        dt_s=dt,
        x0_m=x_start,
        z0_m=z0,
        z_damping=z_damp,
        coupled=fid.coupled,
        node_margin_m=_qs_margin(plate) if proto.force_control == "quasi-static" else 0.0,
        cache=cache,
    )
    scene.solver = contact.ActiveSet(scene.C, scene.K) if fid.coupled else None
    scene.m_col.body("bone")  # validate name
    d_col = mujoco.MjData(scene.m_col)
    d_dyn = mujoco.MjData(scene.m_dyn)
    d_dyn.qpos[:] = 0.0
    d_dyn.qpos[scene.jz] = 0.0
    bone_y = proto.offset_y_m
    scene.m_dyn.body_pos[scene.m_dyn.body("bone").id, 1] = bone_y
    scene.m_col.body_pos[scene.m_col.body("bone").id, 1] = bone_y

    runner = _Runner(
        scene,
        fid,
        finger,
        d_col,
        d_dyn,
        dt,
        z0_m=z0,
        plate=plate,
        quasi_static=proto.force_control == "quasi-static",
    )
    # --- approach (kinematic descent) and press (force ramp), then settle
    F = proto.force_n
    t = 0.0
    while True:
        Fs = runner.step(z_vel=-APPROACH_SPEED, force_cmd=0.0, slide_v=0.0)
        t += dt
        if Fs >= 0.2 * F:
            break
        if t > 2.0:
            raise PhysicsError("the pad did not reach the plate within 2 s of approach")
    t_press = 0.0
    n_press = max(1, round(proto.press_s / dt))
    for k in range(n_press):
        runner.step(force_cmd=F * (0.2 + 0.8 * (k + 1) / n_press))
        t_press += dt
    settle_steps = max(1, round(proto.settle_s / dt))
    for _ in range(settle_steps):
        Fs = runner.step(force_cmd=F)
    for _ in range(round(2.0 / dt)):  # extra settling if needed
        if abs(Fs - F) <= 0.01 * F and abs(d_dyn.qvel[scene.jz]) < 1e-4:
            break
        Fs = runner.step(force_cmd=F)
    else:
        warnings.append(f"press force did not settle within 1% of {F:g} N (now {Fs:.4g} N)")

    # --- strokes
    strokes = []
    for _ in range(proto.passes):
        strokes.append((x_start, x_end, 1.0))
        if proto.return_stroke:
            strokes.append((x_end, x_start, -1.0))
    if proto.duration_s is not None:
        n_samples = max(1, round(proto.duration_s * proto.rate_hz))
    else:
        length = sum(abs(b - a) for a, b, _ in strokes)
        n_samples = max(1, math.ceil(length / max(proto.speed_m_s, 1e-9) * proto.rate_hz))
        if proto.speed_m_s == 0:
            raise ConfigError("speed_m_s = 0 needs a duration_s")
    out = np.empty((n_samples, layout.n), dtype=np.float64)
    forces = np.empty(n_samples)
    x_pad = np.empty(n_samples)
    acc = np.zeros(layout.n)
    stroke_i, (xa, xb, sgn) = 0, strokes[0]
    v_slide = proto.speed_m_s
    t_ramp = 0.02  # speed ramp at the start of each stroke [s]
    t_stroke = 0.0
    t_slide = time.perf_counter()
    # Each sample is the mean load over its period by the trapezoid rule on the steps: half
    # the load at the period's start, the steps inside, half the load at its end (the next
    # period's first step); so a sample is centred on its time at any step.
    now = np.zeros(layout.n)  # this step's taxel loads
    first = np.zeros(layout.n)  # the load at the start of the current sample period
    prev_sum = np.zeros(layout.n)
    prev_first = np.zeros(layout.n)
    f_first = f_prev_first = f_prev_sum = 0.0

    stopped_at = None  # time the stroke stopped at the plate's end

    def slide_step() -> float:
        nonlocal stroke_i, xa, xb, sgn, t_stroke, vcmd, stopped_at
        x = x_start + d_dyn.qpos[scene.jx]
        if sgn * (x - xb) >= 0 and stroke_i + 1 < len(strokes):
            stroke_i += 1
            xa, xb, sgn = strokes[stroke_i]
            t_stroke = 0.0
        vcmd = sgn * v_slide * min(1.0, t_stroke / t_ramp)
        if sgn * x >= x_limit:
            vcmd = 0.0
            if stopped_at is None:
                stopped_at = t_slide_sim[0]
        t_slide_sim[0] += dt
        f = runner.step(force_cmd=F, slide_v=vcmd, taxel_out=now)
        t_stroke += dt
        return f

    def close(s: int, f_end: float) -> None:  # sample s ends where the current step starts
        out[s] = (prev_sum + 0.5 * (now - prev_first)) / n_sub
        forces[s] = (f_prev_sum + 0.5 * (f_end - f_prev_first)) / n_sub

    vcmd = 0.0
    t_slide_sim = [0.0]
    for s in range(n_samples):
        acc[:] = 0.0
        fsum = 0.0
        for k in range(n_sub):
            f = slide_step()
            if k == 0:
                if s:
                    close(s - 1, f)
                first[:] = now
                f_first = f
            acc += now
            fsum += f
        prev_sum[:], prev_first[:] = acc, first
        f_prev_sum, f_prev_first = fsum, f_first
        x_pad[s] = x_start + d_dyn.qpos[scene.jx] - 0.5 * vcmd / proto.rate_hz
        runner.check_warnings()
    close(n_samples - 1, slide_step())  # the last period's end point
    slide_wall = time.perf_counter() - t_slide
    sim_window = n_samples / proto.rate_hz
    if stopped_at is not None:
        warnings.append(
            f"the stroke stopped at the plate's end after {stopped_at:.3g} s of the {sim_window:.3g} s "
            f"window ({proto.speed_m_s * 1e3:.3g} mm/s): the pad rested on flat ground for the rest"
        )
    warnings += _force_warnings(forces, F, proto.speed_m_s)
    # micro-roughness acts through the contact patch on top of the finger's simulation
    micro = micro_loads(plate, layout, x_pad, out > 1e-9, finger.e_star_pa, proto.rate_hz)
    if micro.any():
        out = np.maximum(out + micro, 0.0)
    units, transducer = "N", "ideal"
    if not ideal and sensor.transducer is not None:
        out = sensor.transduce(out, proto.rate_hz, np.random.default_rng([seed, 1]))
        units, transducer = sensor.units, sensor.transducer_json()
    times = (np.arange(n_samples) + 0.5) / proto.rate_hz
    wall = time.perf_counter() - t_wall
    sim_s = n_samples / proto.rate_hz
    meta = {
        "plate": plate.name or plate.hash,
        "plate_hash": plate.hash,
        "plate_params": plate.params(),
        "layout": layout.name,
        "finger": finger.to_json(),
        "protocol": asdict(proto),
        "protocol_nominal": asdict(protocol),
        "seed": seed,
        "fidelity": fid.to_json(),
        "skin_problem": runner.held.describe() if runner.held is not None else "full problem",
        "rate_hz": proto.rate_hz,
        "dt_s": dt,
        "transducer": transducer,
        "micro_roughness": bool(micro.any()),
        "x_pad_m": x_pad.tolist(),
        "normal_force_n": forces.tolist(),
        "mean_drag_n": runner.drag_sum / max(runner.n_slide_steps, 1),
        "versions": {
            "sim_tactile": __version__,
            "mujoco": mujoco.__version__,
            "numpy": np.__version__,
        },
        "warnings": warnings,
        "sim_s": sim_s,
        "wall_s": wall,
        "x_start_m": x_start,
        "slide_wall_s": slide_wall,
        "steps": n_samples * n_sub,
    }
    rec = Recording(out.astype(np.float32), times, layout.positions, units=units, meta=meta)
    return SimResult(rec, fid, sim_s, wall, warnings)


#: a slide whose mean normal force strays further than this from the target is flagged
FORCE_TOLERANCE = 0.05


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
            f"{100 * off:.1f}% of the samples"
        )
    return out


def _qs_margin(plate: Plate) -> float:
    """The skin nodes' collider margin under quasi-static force control: wide where the
    primitive collider serves (it costs nothing there), narrow where MuJoCo collides."""
    from ..plates import features
    from ..plates.spec import Roughness

    if isinstance(plate.texture, Roughness):
        return QS_MARGIN_MUJOCO_M
    if all(f.kind in ("box", "cap") for f in features(plate)):
        return QS_MARGIN_M
    return QS_MARGIN_MUJOCO_M


def _plate_heights(plate: Plate, grid, x: float, y: float) -> np.ndarray:
    from ..plates import height_at

    return height_at(plate, grid.xy[:, 0] + x, grid.xy[:, 1] + y) - grid.z


class _Runner:
    """One simulation step: collision query, skin solve, forces on the bone, MuJoCo step."""

    def __init__(
        self,
        scene,
        fid: Fidelity,
        finger: Finger,
        d_col,
        d_dyn,
        dt: float,
        z0_m: float = 0.0,
        plate: Plate | None = None,
        quasi_static: bool = False,
        use_primitive_collider: bool = True,
        reduce_skin: bool = True,
    ):
        self.s, self.fid, self.finger = scene, fid, finger
        self.quasi_static = quasi_static
        self.d_col, self.d_dyn, self.dt = d_col, d_dyn, dt
        bone = scene.m_col.body("bone").id
        self.collider = (
            PrimitiveCollider.from_model(scene.m_col, scene.node_of_geom, bone)
            if use_primitive_collider
            else None
        )
        nodes = np.flatnonzero(scene.node_of_geom >= 0)
        self._margin = float(scene.m_col.geom_margin[nodes[0]]) if nodes.size else 0.0
        if quasi_static and not self._margin > 0:
            raise ConfigError("quasi-static force control needs skin nodes with a collider margin")
        self._bone0 = scene.m_col.body_pos[bone].copy()
        self._bone_pos = self._bone0.copy()
        # the held-force step's lookups, done once (MuJoCo's arrays are views of d_dyn)
        self.held = (
            HeldSkin(
                scene,
                self.collider,
                float(self._bone0[1]),
                self._margin,
                reduce_skin,
                winkler_k_pa_per_m=None if scene.C is not None else fid.winkler_k_pa_per_m,
            )
            if quasi_static and self.collider is not None
            else None
        )
        self._taxel_tmp = np.zeros(scene.layout.n)
        self._qpos, self._qvel = d_dyn.qpos, d_dyn.qvel
        self._qfrc, self._ctrl = d_dyn.qfrc_applied, d_dyn.ctrl
        self._jx, self._jz = scene.jx, scene.jz
        self._area = scene.grid.area_m2
        self._m_dyn = scene.m_dyn
        self._friction = finger.friction
        self.pen = np.zeros(scene.n_nodes)
        self.loads = np.zeros(scene.n_nodes)
        self.drag_sum = 0.0
        self.n_slide_steps = 0
        self.z_ref = None
        self.max_pen_allowed = finger.thickness_m
        # The pad's lowest point starts at z0 (qpos 0); the plate's base surface is at 0. A
        # node pressed into a feature narrower than the skin is thick, or deeper than half the
        # base box, is measured to the nearest other face, so its depth is no longer read
        # right; the pad's own depth below the base is checked against both limits.
        self.z0 = z0_m
        self.max_depth = finger.thickness_m
        self.depth_limit = "the skin thickness"
        if plate is not None and plate.thickness_m / 2 < self.max_depth:
            self.max_depth = plate.thickness_m / 2
            self.depth_limit = (
                f"half the plate's {plate.thickness_m * 1e3:g} mm base, below which the "
                "collider reads depths from the base's bottom face"
            )
        self._stiff_check = 0

    def step(
        self,
        *,
        force_cmd: float,
        slide_v: float = 0.0,
        z_vel: float | None = None,
        taxel_acc: np.ndarray | None = None,
        taxel_out: np.ndarray | None = None,
    ) -> float:
        if self.held is not None and z_vel is None and force_cmd > 0:
            return self._step_held(force_cmd, slide_v, taxel_acc, taxel_out)
        s, dd = self.s, self.d_dyn
        if z_vel is not None:  # kinematic approach
            dd.qpos[s.jz] += z_vel * self.dt
            dd.qvel[s.jz] = 0.0
        quasi = self.quasi_static and z_vel is None and force_cmd > 0
        pen = self.pen
        if quasi:
            p, n = self._hold(force_cmd), True
        else:
            n = self._depths(pen)
            p = _skin_pressure(s, self.fid, pen)
        loads = self.loads
        np.multiply(p, s.grid.area_m2, out=loads)
        Fs = float(loads.sum())
        if not math.isfinite(Fs):
            raise PhysicsError("the skin load is not finite (NaN or infinity)")
        if n and pen.max() > self.max_pen_allowed:
            raise PhysicsError(
                f"skin pressed to the bottom: a node is {pen.max() * 1e3:.3g} mm deep, beyond the "
                f"skin thickness {self.max_pen_allowed * 1e3:.3g} mm (lower the force or use a thicker skin)"
            )
        self._stiff_check -= 1
        if self._stiff_check <= 0 and Fs > 0 and not self.quasi_static:
            k = _contact_stiffness(s, self.fid, p)
            w_dt = math.sqrt(k / self.finger.bone_mass_kg) * self.dt
            if w_dt > MAX_OMEGA_DT:
                raise PhysicsError(
                    f"time step too coarse: the skin-bone coupling has omega*dt = {w_dt:.2f} "
                    f"(contact stiffness {k:.3g} N/m, dt {self.dt:g} s); valid: omega*dt <= {MAX_OMEGA_DT} "
                    f"(dt <= {self.dt * MAX_OMEGA_DT / w_dt:.3g} s)"
                )
            self._stiff_check = 50
        drag = 0.0
        if slide_v != 0.0:
            drag = -self.finger.friction * Fs * math.tanh(dd.qvel[s.jx] / V_STICK)
            self.drag_sum += abs(drag)
            self.n_slide_steps += 1
        if quasi:  # the pad holds the height found above
            dd.qvel[s.jz] = 0.0
            dd.qfrc_applied[s.jz] = 0.0
        else:
            dd.qfrc_applied[s.jz] = 0.0 if z_vel is not None else Fs - force_cmd
        dd.qfrc_applied[s.jx] = drag
        dd.ctrl[0] = slide_v
        mujoco.mj_step(s.m_dyn, dd)
        self._check_depth(force_cmd)
        if taxel_acc is not None:
            taxel_acc += s.W @ loads
        if taxel_out is not None:
            np.matmul(s.W, loads, out=taxel_out)
        return Fs

    def _step_held(self, force_cmd, slide_v, taxel_acc, taxel_out) -> float:
        """:meth:`step` under quasi-static force control with the primitive collider: the
        skin's part in one compiled call on the reduced problem (:class:`HeldSkin`)."""
        qpos, qvel, jx, jz = self._qpos, self._qvel, self._jx, self._jz
        h = self.held
        out = taxel_out if taxel_out is not None else self._taxel_tmp
        total = force_cmd / self._area
        Fs, top = h.step(self._bone0, qpos, jx, jz, total, out)
        if not math.isfinite(Fs):
            raise PhysicsError("the skin load is not finite (NaN or infinity)")
        if top > self.max_pen_allowed:
            raise PhysicsError(
                f"skin pressed to the bottom: a node is {top * 1e3:.3g} mm deep, beyond the "
                f"skin thickness {self.max_pen_allowed * 1e3:.3g} mm (lower the force or use a thicker skin)"
            )
        drag = 0.0
        if slide_v != 0.0:
            drag = -self._friction * Fs * math.tanh(qvel[jx] / V_STICK)
            self.drag_sum += abs(drag)
            self.n_slide_steps += 1
        qvel[jz] = 0.0
        frc = self._qfrc
        frc[jz] = 0.0
        frc[jx] = drag
        self._ctrl[0] = slide_v
        mujoco.mj_step(self._m_dyn, self.d_dyn)
        z = qpos[jz]
        if self.z0 + z < -self.max_depth or not (math.isfinite(z) and abs(z) < 0.05):
            self._check_depth(force_cmd)
        if taxel_acc is not None:
            taxel_acc += out
        return Fs

    def _hold(self, force_cmd: float) -> np.ndarray:
        """Move the pad to the height where the skin carries ``force_cmd``; returns the
        pressures there and leaves the depths there in ``self.pen``. Re-collides when the
        pad moves further than the collider's margin (nodes beyond it could not join)."""
        qpos, jz, pen, solver = self._qpos, self._jz, self.pen, self.s.solver
        total = force_cmd / self._area
        for _ in range(_QS_COLLISIONS):
            if not self._depths(pen):  # nothing within the margin: sink by most of it, look again
                qpos[jz] -= 0.9 * self._margin
                continue
            if solver is None:  # L0: the Winkler bed
                p, dz = contact.winkler_force(pen, self.fid.winkler_k_pa_per_m, total)
            else:
                p, dz = solver.solve_force(pen, total)
            qpos[jz] -= dz
            pen += dz  # the depths at the new height (for the checks)
            if abs(dz) <= self._margin:
                return p
        raise PhysicsError(
            f"quasi-static force control: the pad found no height carrying {force_cmd:g} N "
            f"within {_QS_COLLISIONS} collision queries (it fell more than "
            f"{_QS_COLLISIONS * self._margin * 1e3:g} mm in one step)"
        )

    def _check_depth(self, force_cmd: float) -> None:
        """Raise if the pad is below what the skin carries, or ran away."""
        s, dd = self.s, self.d_dyn
        low = self.z0 + dd.qpos[s.jz]
        if low < -self.max_depth:
            raise PhysicsError(
                f"skin pressed to the bottom: the pad's lowest point is {-low * 1e3:.3g} mm below "
                f"the plate's base surface, beyond {self.max_depth * 1e3:.3g} mm "
                f"({self.depth_limit}; the skin is {self.max_pen_allowed * 1e3:.3g} mm thick): "
                f"{force_cmd:g} N is more than this pad carries here; lower the force or use a "
                "thicker or stiffer skin"
            )
        if not (math.isfinite(dd.qpos[s.jz]) and abs(dd.qpos[s.jz]) < 0.05):
            raise PhysicsError(
                f"the finger ran away (z = {dd.qpos[s.jz]:.3g} m): the simulation diverged"
            )

    def _depths(self, pen: np.ndarray) -> bool:
        """The skin's penetration-depth map at the bone's current position into ``pen``;
        whether any node lies within the collider's margin. The primitive collider when the
        plate allows it (equal to MuJoCo's, tested), else MuJoCo's."""
        s, dd = self.s, self.d_dyn
        if self.collider is not None:
            b = self._bone_pos
            b[0] = self._bone0[0] + dd.qpos[s.jx]
            b[2] = self._bone0[2] + dd.qpos[s.jz]
            return self.collider.depths(b, pen)
        dc = self.d_col
        dc.qpos[:] = dd.qpos
        mujoco.mj_kinematics(s.m_col, dc)
        mujoco.mj_collision(s.m_col, dc)
        if dc.ncon:
            con = dc.contact
            penetration_map(con.geom, con.dist, s.node_of_geom, pen)
            return True
        pen[:] = -np.inf
        return False

    def check_warnings(self) -> None:
        for d in (self.d_dyn,) if self.collider is not None else (self.d_dyn, self.d_col):
            if d.warning.number.any():
                bad = [mujoco.mjtWarning(i).name for i, w in enumerate(d.warning) if w.number]
                raise PhysicsError(
                    f"MuJoCo warning(s) {', '.join(bad)}: the simulation is not trustworthy"
                )
