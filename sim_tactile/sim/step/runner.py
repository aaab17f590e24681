"""One simulation step of the finger: collision query, skin solve, forces on the bone, MuJoCo.

:class:`Runner` owns the moving parts of one slide: the scene's MuJoCo model stepping the bone
(``m_dyn``), the collider (:func:`~sim_tactile.sim.collide.choose.make_collider`), the skin model
(:func:`~sim_tactile.sim.skin.models.make_skin`) and, under quasi-static force control, the
held step (:func:`~.choose.make_held_step`). Every step checks for a non-finite load, a skin pressed to the bottom and a
runaway pad, and under the dynamic force loop the coupling's stability limit; any of these
stops the run with a :class:`~sim_tactile.errors.PhysicsError` naming the cause.

:class:`~sim_tactile.sim.plan.options.StepOptions`, which switches each fast path off for its
plain reference, lives in the planner now; importing it from here still works for one release.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ...errors import PhysicsError
from ...plates import Plate
from ...scene.model import Scene
from ...sensors.pad import Finger
from ..plan.fidelity import MAX_OMEGA_DT, Fidelity
from ..plan.options import StepOptions  # noqa: F401  (its old home, for one release)
from ..skin.models import SkinModel, SpectralSkin
from .held import HeldStep
from .sampling import check_mujoco

#: Velocity of the friction regularisation [m/s]: Coulomb drag mu*N*tanh(v / V_STICK).
V_STICK = 1e-3
#: A slide whose drag carries less than this share of mu*N (:func:`drag_factor`) is reported
#: as regularised: below V_STICK * atanh(DRAG_FULL), 4.95 mm/s.
DRAG_FULL = 0.9999


def drag_factor(speed_m_s: float) -> float:
    """The share of the Coulomb drag mu*N that the regularised drag carries at a steady
    slide speed ``speed_m_s`` [m/s]: tanh(|v| / V_STICK) (0.0997 at 0.1 mm/s, 0.9999 at
    4.95 mm/s)."""
    return math.tanh(abs(speed_m_s) / V_STICK)


def drag_warning(speed_m_s: float) -> str | None:
    """The warning for a slide at ``speed_m_s`` [m/s] whose drag the regularisation holds
    below :data:`DRAG_FULL` of mu*N (None where it does not, or where nothing slides)."""
    f = drag_factor(speed_m_s)
    if speed_m_s == 0 or f >= DRAG_FULL:
        return None
    return (
        f"the slide's friction drag is regularised: at {abs(speed_m_s) * 1e3:.3g} mm/s, "
        f"{abs(speed_m_s) / V_STICK:.3g} V_STICK (V_STICK = {V_STICK * 1e3:g} mm/s), "
        f"mu N tanh(v / V_STICK) carries {f:.4g} of mu N, so meta mean_drag_n is "
        f"{1 / f:.3g}x low (meta drag_factor); slide faster than "
        f"{V_STICK * math.atanh(DRAG_FULL) * 1e3:.3g} mm/s for the full drag"
    )


#: Steps between checks of the dynamic coupling's omega * dt.
_STIFFNESS_CHECK_STEPS = 50


def coast(m, d, jx: int, jz: int, slide_v: float) -> None:
    """One step of the finger's dynamics ``m`` on the state ``d`` without a skin solve, under
    quasi-static force control: the press joint ``jz`` keeps its height (no speed, no force
    on it) while MuJoCo slides the slide joint ``jx`` at ``slide_v`` (:meth:`Runner.coast`,
    a table's :class:`~.tabled.Glide`, :func:`~.held_run.glide`)."""
    d.qvel[jz] = 0.0
    d.qfrc_applied[jz] = 0.0
    d.qfrc_applied[jx] = 0.0
    d.ctrl[0] = slide_v
    mujoco.mj_step(m, d)


class Runner:
    """Steps the finger of ``scene`` (see the module docstring). ``z0_m``: the pad's lowest
    point at ``qpos = 0`` above the plate's base surface [m]."""

    def __init__(
        self,
        scene: Scene,
        skin: SkinModel,
        fid: Fidelity,
        finger: Finger,
        dt: float,
        *,
        collider,
        z0_m: float,
        plate: Plate,
        quasi_static: bool,
        hold: HeldStep | None = None,
    ):
        self.s, self.skin, self.fid, self.finger = scene, skin, fid, finger
        self.quasi_static = quasi_static
        self.dt = dt
        self.d_dyn = scene.dynamics_data()
        self.d_dyn.qpos[:] = 0.0
        self.collider = collider
        self._area = scene.grid.area_m2
        #: the held step under quasi-static force control (:func:`~.choose.make_held_step`)
        self.hold = hold
        self._taxel_tmp = np.zeros(scene.layout.n)
        self._qpos, self._qvel = self.d_dyn.qpos, self.d_dyn.qvel
        self._qfrc, self._ctrl = self.d_dyn.qfrc_applied, self.d_dyn.ctrl
        self._jx, self._jz = scene.jx, scene.jz
        self._m_dyn = scene.m_dyn
        self._friction = finger.friction
        self.pen = np.zeros(scene.n_nodes)
        self.loads = np.zeros(scene.n_nodes)
        self.drag_sum = 0.0
        self.n_slide_steps = 0
        self.max_pen_allowed = finger.thickness_m
        # The pad's lowest point starts at z0 (qpos 0); the plate's base surface is at 0. Where
        # MuJoCo collides (a plate neither compiled collider takes), a node pressed into a
        # feature narrower than the skin is thick, or deeper than half the base box, is
        # measured to the nearest other face, so its depth is no longer read right (the
        # compiled colliders read the height map); the pad's own depth below the base is
        # checked against both limits.
        self.z0 = z0_m
        self.max_depth = finger.thickness_m
        self.depth_limit = "the skin thickness"
        if plate.thickness_m / 2 < self.max_depth:
            self.max_depth = plate.thickness_m / 2
            self.depth_limit = (
                f"half the plate's {plate.thickness_m * 1e3:g} mm base, below which the "
                "collider reads depths from the base's bottom face"
            )
        self._stiff_check = 0

    # ------------------------------------------------------------------ the pad's state
    @property
    def x_m(self) -> float:
        """The pad's travel along the slide since the start [m]."""
        return float(self._qpos[self._jx])

    @property
    def z_m(self) -> float:
        """The press joint's position [m] (the pad's lowest point is ``z0 + z_m`` above
        the plate's base surface)."""
        return float(self._qpos[self._jz])

    @property
    def z_speed_m_s(self) -> float:
        return float(self._qvel[self._jz])

    def stepwise(self) -> None:
        """This runner steps a whole slide, each solve started from the last step's (not a
        phase table's phases): a spectral skin's warm start that cycles gives way sooner
        (:meth:`~sim_tactile.sim.skin.contact.spectral.Spectral.stepwise`)."""
        if isinstance(self.skin, SpectralSkin):
            self.skin.solver.stepwise()

    def describe(self) -> str:
        """Which skin problem the held step solves (``full problem`` without one)."""
        return self.hold.describe() if self.hold is not None else "full problem"

    # ------------------------------------------------------------------ steps
    def step(
        self,
        *,
        force_cmd: float,
        slide_v: float = 0.0,
        z_vel: float | None = None,
        taxel_out: np.ndarray | None = None,
    ) -> float:
        """One step; returns the skin's normal load [N]. ``z_vel``: move the pad down at
        this speed (the approach: no force control; ``force_cmd`` is then the force it
        approaches, named in errors only), else hold ``force_cmd`` [N] (quasi-static:
        exactly; dynamic: through the damped bone). ``slide_v``: the slide's speed command
        [m/s]. ``taxel_out``: receives the taxel loads [N]."""
        if self.hold is not None and z_vel is None and force_cmd > 0:
            return self._step_held(force_cmd, slide_v, taxel_out)
        s, dd = self.s, self.d_dyn
        if z_vel is not None:  # kinematic approach
            dd.qpos[s.jz] += z_vel * self.dt
            dd.qvel[s.jz] = 0.0
        pen = self.pen
        n = self.collider.depths_at(self._qpos, pen)
        p = self.skin.solve(pen)
        loads = self.loads
        np.multiply(p, s.grid.area_m2, out=loads)
        Fs = float(loads.sum())
        self._after_skin(Fs, pen.max() if n else -math.inf, force_cmd, slide_v)
        if not self.quasi_static and z_vel is None:  # a pad moved kinematically has none
            self._check_coupling(Fs, p)
        dd.qfrc_applied[s.jz] = 0.0 if z_vel is not None else Fs - force_cmd
        dd.qfrc_applied[s.jx] = 0.0  # the arm holds its speed: it reacts the drag
        dd.ctrl[0] = slide_v
        mujoco.mj_step(s.m_dyn, dd)
        self._check_depth(force_cmd, Fs)
        if taxel_out is not None:
            np.matmul(s.W, loads, out=taxel_out)
        return Fs

    def _step_held(self, force_cmd, slide_v, taxel_out) -> float:
        """:meth:`step` under quasi-static force control: the held step moves the pad to the
        height that carries the force; the bone holds it there while MuJoCo slides it."""
        qpos, qvel, jz = self._qpos, self._qvel, self._jz
        out = taxel_out if taxel_out is not None else self._taxel_tmp
        Fs, top = self.hold.step(qpos, jz, force_cmd / self._area, out)
        self._after_skin(Fs, top, force_cmd, slide_v)
        qvel[jz] = 0.0
        frc = self._qfrc
        frc[jz] = 0.0
        frc[self._jx] = 0.0  # the arm holds its speed: it reacts the drag
        self._ctrl[0] = slide_v
        mujoco.mj_step(self._m_dyn, self.d_dyn)
        z = qpos[jz]
        if self.z0 + z < -self.max_depth or not (math.isfinite(z) and abs(z) < 0.05):
            self._check_depth(force_cmd, Fs)
        return Fs

    def coast(self, slide_v: float) -> None:
        """One step of the finger's dynamics without a skin solve, under quasi-static force
        control: the bone keeps its height (the held step set it) while MuJoCo slides it at
        ``slide_v``; the skin's answer for this step is read elsewhere (``solve_every``)."""
        coast(self._m_dyn, self.d_dyn, self._jx, self._jz, slide_v)

    def _after_skin(self, Fs: float, top: float, force_cmd: float, slide_v: float) -> float:
        """Check the skin's load and depth; returns the friction drag on the bone [N]. The
        drag is recorded (``mean_drag_n``), not applied to the slide joint: a robot arm
        holds its commanded speed and reacts the drag (applied, it slowed the pad behind
        the velocity servo by mu N / kv: 0.9% on finger7 at 45 mm/s, 3.1% on multilayer3)."""
        if not math.isfinite(Fs):
            raise PhysicsError("the skin load is not finite (NaN or infinity)")
        if top > self.max_pen_allowed:
            raise PhysicsError(
                f"skin pressed to the bottom: a node is {top * 1e3:.3g} mm deep, beyond the "
                f"skin thickness {self.max_pen_allowed * 1e3:.3g} mm (lower the force or use a thicker skin)"
            )
        if slide_v == 0.0:
            return 0.0
        drag = -self._friction * Fs * math.tanh(self._qvel[self._jx] / V_STICK)
        self.drag_sum += abs(drag)
        self.n_slide_steps += 1
        return drag

    def _check_coupling(self, Fs: float, p: np.ndarray) -> None:
        """The dynamic loop couples skin and bone explicitly: refuse a step beyond its
        stability limit (checked every few steps)."""
        self._stiff_check -= 1
        if self._stiff_check > 0 or Fs <= 0:
            return
        k = self.skin.stiffness(p, self._area)
        w_dt = math.sqrt(k / self.finger.bone_mass_kg) * self.dt
        if w_dt > MAX_OMEGA_DT:
            raise PhysicsError(
                f"time step too coarse: the skin-bone coupling has omega*dt = {w_dt:.2f} "
                f"(contact stiffness {k:.3g} N/m, dt {self.dt:g} s); valid: omega*dt <= {MAX_OMEGA_DT} "
                f"(dt <= {self.dt * MAX_OMEGA_DT / w_dt:.3g} s)"
            )
        self._stiff_check = _STIFFNESS_CHECK_STEPS

    def check_held(self, z: float, force_cmd: float, load_n: float, top: float) -> None:
        """The checks of a held step at the press joint's position ``z`` [m] (a phase
        table's, solved off this runner's own state): a finite load, no node deeper than the
        skin (``top`` [m]), the pad above what the skin carries and not run away."""
        self._after_skin(load_n, top, force_cmd, 0.0)
        self._check_depth(force_cmd, load_n, z)

    def _check_depth(self, force_cmd: float, load_n: float, z: float | None = None) -> None:
        """Raise if the pad is below what the skin carries, or ran away. ``force_cmd``: the
        force commanded (or approached) [N]; ``load_n``: the skin's load at this depth [N];
        ``z``: the press joint's position (None: this runner's)."""
        z = self._qpos[self._jz] if z is None else z
        low = self.z0 + z
        if low < -self.max_depth:
            raise PhysicsError(
                f"skin pressed to the bottom: the pad's lowest point is {-low * 1e3:.3g} mm below "
                f"the plate's base surface, beyond {self.max_depth * 1e3:.3g} mm "
                f"({self.depth_limit}; the skin is {self.max_pen_allowed * 1e3:.3g} mm thick), "
                f"where the pad carries {load_n:.3g} N of the {force_cmd:g} N commanded: more "
                "than this pad carries here; lower the force or use a thicker or stiffer skin"
            )
        if not (math.isfinite(z) and abs(z) < 0.05):
            raise PhysicsError(f"the finger ran away (z = {z:.3g} m): the simulation diverged")

    def check_warnings(self) -> None:
        """Raise if MuJoCo warned while stepping or colliding (the run is not trustworthy)."""
        check_mujoco(self.d_dyn, self.collider.warnings())
