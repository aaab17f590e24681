"""One slide of the probe rig (:mod:`.plan.rig`): a rigid textured probe held at a force, sliding
over a flat sensor that lies on a rigid bed, and what the sensor's elements read.

**The scene.** MuJoCo carries the probe: a body on two slide joints above the static bed and
sensor sheet, ``slide_x`` driven by a velocity actuator along the pass's speed command,
``press_z`` held at the height where the sensor carries the commanded force (the held force
of :data:`~.plan.protocol.FORCE_CONTROLS` ``quasi-static``, the only control the rig takes). The
probe's position in each step is MuJoCo's.

**The contact is stationary in the probe's frame.** The sensor's skin is a stack of
homogeneous layers on the bed (the sensor's ``finger.stack``), wider than the probe and
covering the track (an assumption, ``docs/probe_rig.md``), so its response does not depend
on where on it the probe is: under a held force and without friction, the probe's contact
pressure in its own frame is the same at every step. It is solved once per slide, on the
probe face's node lattice (:class:`~.skin.models.SpectralSkin`: the stack's compliance applied by
FFT, the contact set found exactly). An element then reads the stress field that the probe
carries along: :func:`reading_lines` convolves the node loads with each element's kernel
(the stack's vertical stress at the element's depth, integrated over its area:
:func:`~sim_tactile.scene.layered.layered_subsurface_weights`) by FFT, on lines at a quarter
of the node pitch along the slide, and each step reads it where the element is.

Each sample is the trapezoid mean over its period (:class:`~.step.sampling.SampleAverager`); the
sensor's transducer and seeded imperfections follow, as in :func:`~.slide.simulate`.
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from .._jit import njit
from ..cache import memoized
from ..errors import ConfigError, PhysicsError
from ..plates import Plate, get_plate, surface_of
from ..records import Recording
from ..scene.elastic import subsurface_weights
from ..scene.layered import layered_subsurface_weights
from ..scene.model import add_velocity_servo
from ..scene.nodes import SkinGrid
from ..sensors import Finger, Sensor
from .collide.height import interp_at
from .plan.protocol import Protocol
from .plan.rig import ProbePass, ProbeRig
from .plan.slide import Slide
from .skin.models import SpectralSkin
from .step.sampling import SampleAverager, SimResult, sensor_output, versions

#: Sub-positions per node pitch at which the reading lines are computed (linear between).
LINE_SUBSTEPS = 4
#: Velocity actuator gain of the carriage [N s/m].
CARRIAGE_KV = 2000.0
#: The probe moves at most this fraction of a node pitch per step.
STEP_FRACTION = 0.5
#: Thickness of the probe's block [m] (its geometry in MuJoCo; it carries no contact there).
PROBE_BLOCK_M = 10e-3


def probe_grid(plate: Plate, pitch_m: float) -> SkinGrid:
    """Nodes at ``pitch_m`` tiling the probe's face (the plate's textured area), centred on
    it, node ``iy * nx + ix``."""
    L, W = plate.area_length_m, plate.area_width_m
    nx, ny = round(L / pitch_m), round(W / pitch_m)
    if abs(nx * pitch_m - L) > 1e-9 or abs(ny * pitch_m - W) > 1e-9:
        raise ConfigError(
            f"rig node_pitch_m = {pitch_m:g} m does not tile the probe's face "
            f"{L * 1e3:g} x {W * 1e3:g} mm; valid: a pitch that divides both"
        )
    xs = (np.arange(nx) + 0.5) * pitch_m - L / 2
    ys = (np.arange(ny) + 0.5) * pitch_m - W / 2
    X, Y = np.meshgrid(xs, ys, indexing="xy")
    return SkinGrid(pitch_m, np.column_stack([X.ravel(), Y.ravel()]), np.zeros(nx * ny))


def probe_contact(plate: Plate, finger: Finger, grid: SkinGrid, force_n: float):
    """The probe's contact pressure [Pa] on ``grid`` (its face pressed on the finger's skin
    with ``force_n``), its approach [m] (how far the face's base plane sits below the
    sensor's surface less the tallest feature) and the skin's description. A node where a
    height map holds no material (NaN) is out of reach."""
    skin = _skin(grid.lattice, grid.pitch_m, finger)
    pen = surface_of(plate).height(grid.xy[:, 0], grid.xy[:, 1])
    pen = np.where(np.isnan(pen), -np.inf, pen)
    p, dz = skin.solve_force(pen - pen.max(), force_n / grid.area_m2)
    return p, float(dz), skin.describe()


@memoized("probe-face skins", maxsize=4)
def _skin(lattice: tuple[int, int], pitch_m: float, finger: Finger) -> SpectralSkin:
    """The skin on the probe face's lattice, kept per process: its compliance table takes a
    second, and every slide of a plate family has the same face."""
    nx, ny = lattice
    xs, ys = (np.arange(nx) + 0.5) * pitch_m, (np.arange(ny) + 0.5) * pitch_m
    X, Y = np.meshgrid(xs, ys, indexing="xy")
    grid = SkinGrid(pitch_m, np.column_stack([X.ravel(), Y.ravel()]), np.zeros(nx * ny))
    return SpectralSkin.of(grid, finger)


def reading_lines(
    grid: SkinGrid,
    loads_n: np.ndarray,
    finger: Finger,
    sizes: np.ndarray,
    depths: np.ndarray,
    y_rel: np.ndarray,
    reach_m: float,
) -> tuple[np.ndarray, np.ndarray]:
    """What an element reads [N] at each position along the slide relative to the probe.

    ``loads_n``: the face's node loads (N,) on ``grid``; element ``m`` has size ``sizes[m]``,
    depth ``depths[m]`` and sits ``y_rel[m]`` across the slide from the probe's centre.
    Returns ``(u, R)``: positions ``u`` [m] (element x less probe x) every pitch /
    :data:`LINE_SUBSTEPS` out to ``reach_m`` past the face's ends, and ``R`` (M, len(u)).
    Exact at those positions: the convolution of the loads with the element's kernel, by
    FFT along the slide."""
    from scipy.signal import fftconvolve

    nx, ny = grid.lattice
    h, hy = grid.pitch_xy
    x0 = grid.xy[0, 0]
    ys = grid.xy[::nx, 1]
    L = loads_n.reshape(ny, nx)
    A = int(math.ceil(reach_m / h)) + 1
    d = np.arange(-(nx - 1 + A), nx + A)  # lattice offsets of the kernel along x
    shifts = np.arange(LINE_SUBSTEPS) * h / LINE_SUBSTEPS
    a = np.arange(-A, nx + A)  # output positions x0 + a h + shift
    u = (x0 + a[:, None] * h + shifts[None, :]).ravel()
    R = np.empty((len(sizes), len(u)))
    # nodes at x = -d h, y = ys: an element at (s, y_rel) reads k(d h + s, y_rel - y) of them
    nodes = np.column_stack([np.tile(-d * h, ny), np.repeat(ys, len(d))])
    rows: dict[tuple, list[int]] = {}
    for m in range(len(sizes)):
        key = (float(sizes[m][0]), float(sizes[m][1]), float(depths[m]), float(y_rel[m]))
        rows.setdefault(key, []).append(m)
    keys = list(rows)
    # every distinct element row at every sub-position, in one call (one FFT per depth and size)
    virt = np.array([[s, k[3]] for k in keys for s in shifts])
    vsize = np.array([k[:2] for k in keys for _ in shifts])
    vdepth = np.array([k[2] for k in keys for _ in shifts])
    W = _weights(nodes, grid, virt, vsize, vdepth, finger.stack)
    for i, key in enumerate(keys):
        line = np.empty((len(a), LINE_SUBSTEPS))
        for k in range(LINE_SUBSTEPS):
            kern = W[i * LINE_SUBSTEPS + k].reshape(ny, len(d))
            full = fftconvolve(L, kern, mode="full", axes=1).sum(axis=0)
            # output index c of the full convolution is position a = c - (nx - 1 + A)
            line[:, k] = full[nx - 1 : nx - 1 + len(a)]
        R[rows[key]] = line.ravel()
    return u, R


#: The stack's stress tables reach the elements' offsets rounded up to this [m], and a
#: process keeps them: every slide of a task draws its own offset across the slide, and one
#: table now serves the slides whose offsets round alike (most of a slide's time had gone
#: into making the table again).
REACH_QUANTUM_M = 2e-3


def _weights(nodes, grid, taxel_xy, sizes, depths, stack) -> np.ndarray:
    """(M, N) readings of the taxels from unit loads on the nodes' patches: the stack's,
    else the half-space's."""
    h, hy = grid.pitch_xy
    if stack is None:
        return subsurface_weights(nodes, h, taxel_xy, sizes, depths, pitch_y_m=hy)
    return layered_subsurface_weights(
        nodes, h, taxel_xy, sizes, depths, stack, pitch_y_m=hy, reach_quantum_m=REACH_QUANTUM_M
    )


def rig_model(plate: Plate, sensor: Sensor, rig: ProbeRig, x0_m: float, y0_m: float, dt_s: float):
    """The rig in MuJoCo: the bed and the sensor sheet (static, with a site at each element)
    and the probe on ``slide_x`` (velocity actuator) and ``press_z``; contacts off (the skin
    model carries the contact). Returns the model and the dof indices of the two joints."""
    L, W = plate.area_length_m, plate.area_width_m
    sheet = (
        sensor.finger.thickness_m
        if sensor.finger.stack is None
        else sensor.finger.stack.thickness_m
    )
    spec = mujoco.MjSpec()
    spec.modelname = f"sim_tactile probe rig {plate.name or plate.hash}"
    spec.option.timestep = dt_s
    spec.option.gravity = (0.0, 0.0, 0.0)  # the held force is the whole press (the scale's)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    T = mujoco.mjtGeom
    track = abs(x0_m) + L
    wb = spec.worldbody
    wb.add_geom(name="bed", type=T.mjGEOM_BOX, size=(track, W, 5e-3), pos=(0, 0, -sheet - 5e-3))
    wb.add_geom(
        name="sensor",
        type=T.mjGEOM_BOX,
        size=(track, W / 2, sheet / 2),
        pos=(0, 0, -sheet / 2),
        rgba=(0.3, 0.3, 0.8, 1),
    )
    for i, (x, y, z) in enumerate(sensor.layout.positions):
        wb.add_site(name=f"element{i}", pos=(x, y, z))
    probe = wb.add_body(name="probe", pos=(x0_m, y0_m, PROBE_BLOCK_M / 2))
    probe.add_joint(name="slide_x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=(1, 0, 0))
    probe.add_joint(name="press_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=(0, 0, 1))
    probe.add_geom(
        name="probe",
        type=T.mjGEOM_BOX,
        size=(L / 2, W / 2, PROBE_BLOCK_M / 2),
        mass=rig.probe_mass_kg,
        rgba=(0.7, 0.7, 0.7, 1),
    )
    add_velocity_servo(spec, "carriage", "slide_x", CARRIAGE_KV)
    m = spec.compile()
    jx = int(m.jnt_dofadr[m.joint("slide_x").id])
    jz = int(m.jnt_dofadr[m.joint("press_z").id])
    return m, jx, jz


def simulate_rig(
    plate: Plate | str,
    sensor: Sensor | str,
    *,
    rig: ProbeRig,
    protocol: Protocol,
    finger: Finger | None = None,
    seed: int = 0,
    ideal: bool = False,
) -> SimResult:
    """:func:`run_rig` of the :class:`~.plan.slide.Slide` of these arguments."""
    plate = get_plate(plate) if isinstance(plate, str) else plate
    return run_rig(Slide(plate, sensor, protocol, seed, ideal=ideal, finger=finger, rig=rig))


def run_rig(slide: Slide) -> SimResult:
    """One window of the probe rig (see the module docstring) of ``slide`` (its ``rig``):
    the probe, pressed on the sensor with the slide's force, rests, crosses the sensor along
    the slide's direction (:meth:`ProbeRig.sign`), and rests again; the elements' outputs,
    or with ``ideal`` their noise-free loads [N]. ``finger``: the sensor's skin (its stack
    on the bed), else the sensor's own. ``protocol.duration_s`` is the window."""
    t_wall = time.perf_counter()
    plate, sensor, finger, rig, seed = (
        slide.plate,
        slide.sensor_def,
        slide.pad,
        slide.rig,
        slide.seed,
    )
    protocol, ideal = slide.protocol, slide.ideal
    sheet = _check_rig_inputs(plate, sensor, finger, protocol)
    layout = sensor.layout
    proto = slide.drawn()
    sign = rig.sign(seed)
    reach = float(np.max(np.abs(layout.positions[:, 0]) + layout.sizes[:, 0] / 2))
    pas = ProbePass.of(
        rig, plate.area_length_m, reach, sheet, proto.speed_m_s, proto.duration_s, sign
    )
    rate = proto.rate_hz
    n_samples = max(1, round(proto.duration_s * rate))
    n_sub = max(1, math.ceil(proto.speed_m_s / (rate * STEP_FRACTION * rig.node_pitch_m)))
    dt = 1.0 / (rate * n_sub)
    grid = probe_grid(plate, rig.node_pitch_m)
    p, approach, what, u, R = _face(plate, finger, grid, proto, layout, pas)
    m, jx, jz = rig_model(plate, sensor, rig, pas.x_from_m, proto.offset_y_m, dt)
    t0 = time.perf_counter()
    out, x_probe = _carry(
        m, jx, jz, pas, -approach, (u, R), layout, proto.force_n, n_sub, n_samples
    )
    slide_wall = time.perf_counter() - t0
    warnings = _lag_warnings(x_probe, pas, rate, rig.node_pitch_m)
    out, units, transducer = sensor_output(out, sensor, rate, seed, ideal)
    wall = time.perf_counter() - t_wall
    meta = {
        **slide.meta_head(),
        "scene": "probe rig",
        "rig": rig.to_json(),
        "direction": sign,
        "fidelity": {"node_pitch_m": rig.node_pitch_m, "line_substeps": LINE_SUBSTEPS},
        "skin_problem": f"{what}; the probe's face, {grid.n} nodes, solved once",
        "rate_hz": rate,
        "dt_s": dt,
        "transducer": transducer,
        "micro_roughness": False,
        "x_probe_m": x_probe.tolist(),
        "approach_m": approach,
        "contact_area_m2": float(np.count_nonzero(p > 0) * grid.area_m2),
        "normal_force_n": [proto.force_n] * n_samples,
        "mean_drag_n": 0.0,
        "versions": versions(),
        "warnings": warnings,
        "sim_s": n_samples / rate,
        "wall_s": wall,
        "x_start_m": pas.x_from_m,
        "pass_start_s": pas.t_start_s,
        "pass_s": pas.moving_s,
        "slide_wall_s": slide_wall,
        "steps": n_samples * n_sub,
    }
    times = (np.arange(n_samples) + 0.5) / rate
    rec = Recording(out.astype(np.float32), times, layout.positions, units=units, meta=meta)
    return SimResult(rec, None, n_samples / rate, wall, warnings)


def _face(plate, finger, grid, proto, layout, pas):
    """The probe face's contact (pressure [Pa], approach [m], the skin's description) and the
    elements' reading lines ``u, R`` (:func:`reading_lines`) out to the pass's reach."""
    from ..hashing import one_blas_thread

    y_rel = layout.positions[:, 1] - proto.offset_y_m
    reach = abs(pas.x_from_m) + float(np.max(np.abs(layout.positions[:, 0])))
    with one_blas_thread():
        p, approach, what = probe_contact(plate, finger, grid, proto.force_n)
        u, R = reading_lines(
            grid, p * grid.area_m2, finger, layout.sizes, layout.depth_m, y_rel, reach
        )
    return p, approach, what, u, R


def _lag_warnings(x_probe: np.ndarray, pas: ProbePass, rate: float, pitch_m: float) -> list[str]:
    """A warning when the carriage ran more than a node pitch from its commanded path."""
    t = (np.arange(len(x_probe)) + 0.5) / rate
    lag = float(np.max(np.abs(x_probe - pas.position(t))))
    if lag <= pitch_m:
        return []
    return [
        f"the carriage ran {lag * 1e3:.3g} mm from its commanded path (more than a node "
        "pitch): a heavier probe or a faster pass than its actuator holds"
    ]


def _check_rig_inputs(plate: Plate, sensor: Sensor, finger: Finger, protocol: Protocol) -> float:
    """Refuse what the rig does not model; the sensor sheet's thickness [m]."""
    if finger.skin_tractions and finger.friction > 0:
        raise ConfigError(
            "the probe rig takes a frictionless skin (finger.skin_tractions with friction "
            f"{finger.friction:g}); valid: skin_tractions False"
        )
    if protocol.force_control != "quasi-static":
        raise ConfigError(
            f"force_control = {protocol.force_control!r}: the probe rig holds the force "
            "quasi-statically; valid: 'quasi-static'"
        )
    if protocol.duration_s is None:
        raise ConfigError("the probe rig needs the window: give duration_s")
    if surface_of(plate).profile is not None:
        raise ConfigError(
            f"plate {plate.name or plate.hash}: the probe rig does not model micro-roughness; "
            "valid: plates of ridges, gratings, bumps, height maps or flat"
        )
    layout = sensor.layout
    sheet = finger.thickness_m if finger.stack is None else finger.stack.thickness_m
    if np.any(layout.depth_m >= sheet):
        raise ConfigError(
            f"sensor {sensor.name}: elements {layout.depth_m.max() * 1e3:g} mm deep lie below "
            f"its {sheet * 1e3:g} mm skin; valid: depths < the skin's thickness"
        )
    return sheet


@njit
def _read_lines(xt, x, u, R, out):
    """``out[i] = np.interp(xt[i] - x, u, R[i], left=0, right=0)`` for every element, with
    numpy's arithmetic (:func:`~.collide.height.interp_at`; the same numbers bit for bit, tested),
    in one call: the slide's steps had spent most of their time in 18 calls of
    ``np.interp`` each."""
    for i in range(xt.size):
        out[i] = interp_at(xt[i] - x, u, R[i], 0.0, 0.0)


def _carry(m, jx, jz, pas, z_held, lines, layout, force_n, n_sub, n_samples):
    """Step MuJoCo's carriage along the pass, the probe held at ``z_held`` [m] (its face's
    lowest point below the sensor's surface), each element reading its line (``lines``:
    ``(u, R)`` of :func:`reading_lines`) where it is. Returns the sample means (T, M) and the
    probe's x over each sample, averaged as the loads are (trapezoid over its steps)."""
    u, R = lines
    dt = m.opt.timestep
    d = mujoco.MjData(m)
    avg = SampleAverager(n_samples, layout.n, n_sub)
    x_steps = np.empty(n_samples * n_sub + 1)  # the probe at each step's start
    now = np.empty(layout.n)
    xt = layout.positions[:, 0]

    # each step's start time, accumulated as the loop did, and the speed command of the step
    # that follows, at its middle: one vectorised call instead of one a step
    n_steps = n_samples * n_sub
    starts = np.empty(n_steps + 1)
    t = 0.0
    for i in range(n_steps + 1):
        starts[i] = t
        t += dt
    commands = pas.speed(starts + 0.5 * dt)

    def read(i: int) -> float:
        d.qpos[jz] = z_held
        d.qvel[jz] = 0.0
        d.ctrl[0] = commands[i]
        x = pas.x_from_m + float(d.qpos[jx])
        _read_lines(xt, x, u, R, now)
        return x

    for s in range(n_samples):
        for k in range(n_sub):
            i = s * n_sub + k
            x_steps[i] = read(i)
            avg.add(s, k, now, force_n)
            mujoco.mj_step(m, d)
            if not np.isfinite(d.qpos[jx]):
                raise PhysicsError(
                    f"the probe's position became non-finite at {starts[i + 1]:.3g} s"
                )
        avg.end_sample()
    x_steps[-1] = read(n_steps)
    avg.finish(now, force_n)
    xs = x_steps[:-1].reshape(n_samples, n_sub)
    x_probe = (xs.sum(axis=1) + 0.5 * (x_steps[n_sub::n_sub] - xs[:, 0])) / n_sub
    return avg.loads, x_probe
