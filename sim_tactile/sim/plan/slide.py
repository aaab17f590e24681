"""One slide, described once: :class:`Slide`.

A slide is a plate, a sensor (or another pad for it), a nominal protocol and the seed that
draws its speed, force and offset, the fidelity it asks for, whether it records the ideal
loads, the probe rig where it is made on one, and how it is computed
(:class:`~.options.StepOptions`). Every layer reads this one value: the simulator runs it
(:func:`sim_tactile.sim.run`), a data set's jobs are slides (:mod:`sim_tactile.slides`),
a bench scene names one. :meth:`Slide.describe` is the one description behind its cache
key, its recording's meta and a store's attributes.

Like a Tonic transform, it holds the description and nothing else: what it resolves
(:attr:`Slide.sensor_def`, :attr:`Slide.pad`, :attr:`Slide.surface`, :meth:`Slide.drawn`,
:attr:`Slide.window`) is derived from its fields, once, and is not logic. This module loads
neither MuJoCo nor numba.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

from ... import _validate as v
from ...plates.define.spec import Plate
from ...plates.define.surface import Surface, surface_of
from ...sensors import Finger, Layout, Sensor, resolve_sensor
from .fidelity import Fidelity, choose_fidelity, solved_spectrally
from .options import (
    AUTO_SOLVE_EVERY,
    AUTO_SOLVE_TOL,
    AUTO_TABLE_TOL,
    StepOptions,
    check_forced,
    keyed,
)
from .phase import PhasePlan, depths_by_column, table_pays, travel
from .protocol import Protocol, SlideWindow
from .rig import ProbeRig
from .solver import dense_is_dear, dense_step_is_dear, smooth_relief
from .span import span_pays, table_plan
from .vibration import reports_vibration, vibration_warning


@dataclass(frozen=True)
class Slide:
    """One slide (see the module docstring).

    plate: the plate itself (its parameters, not a name).
    sensor: the whole sensor, a sensor name or file, or a bare layout (resolved by
        :attr:`sensor_def`).
    protocol: nominal, with its per-slide jitters (its rate defaults to the sensor's);
        :meth:`drawn` is the protocol the slide runs.
    seed: draws the slide's speed, force and offset and seeds the sensor's imperfections.
    fidelity: ``auto``, ``L0``-``L2`` or a resolved Fidelity.
    ideal: record the noise-free normal loads [N] instead of the sensor's output.
    finger: a pad that replaces the sensor's (None: the sensor's own).
    pitch_m, dt_s: the node pitch along the slide and the time step [m, s] where they are
        forced (None: the fidelity's).
    rig: the probe rig that makes the slide (:mod:`~.rig`), else the finger scene.
    options: how it is computed (:class:`~.options.StepOptions`).
    label: what the slide is called in messages (its plate's name and place in a set).
    plate_slides: how many slides of its plate its set makes (1: a slide alone): ``path =
        auto`` takes a table that pays over many slides of a plate only (a table along the
        slide, :func:`~.span.span_pays`) where they are that many. Not a part of what the
        slide is: its description records the path it takes.
    """

    plate: Plate
    sensor: Sensor | Layout | str
    protocol: Protocol = field(default_factory=Protocol)
    seed: int = 0
    fidelity: Any = "auto"
    ideal: bool = False
    finger: Finger | None = None
    pitch_m: float | None = None
    dt_s: float | None = None
    rig: ProbeRig | None = None
    options: StepOptions = field(default_factory=StepOptions)
    label: str = field(default="", compare=False)
    plate_slides: int = 1

    def __post_init__(self) -> None:
        v.integer("plate_slides", self.plate_slides, 1, None)
        check_forced(self.pitch_m, self.dt_s)

    # ------------------------------------------------------------------ resolved once
    @cached_property
    def sensor_def(self) -> Sensor:
        """The sensor (a name, file or bare layout resolved)."""
        return resolve_sensor(self.sensor)

    @property
    def layout(self) -> Layout:
        return self.sensor_def.layout

    @property
    def pad(self) -> Finger:
        """The pad the slide is made with: ``finger``, else the sensor's."""
        return self.finger or self.sensor_def.finger

    @property
    def surface(self) -> Surface:
        """The plate's surface (:func:`~sim_tactile.plates.define.surface.surface_of`): what the
        planner asks of the plate."""
        return surface_of(self.plate)

    @cached_property
    def nominal(self) -> Protocol:
        """The nominal protocol at its rate (the sensor's unless it has its own)."""
        return self.protocol.at_rate(self.sensor_def.rate_hz)

    def drawn(self) -> Protocol:
        """The slide's own speed, force and offset, as the simulation draws them from
        ``seed`` (:meth:`~.protocol.Protocol.drawn`), at the nominal rate."""
        return self._drawn

    @cached_property
    def _drawn(self) -> Protocol:
        """:meth:`drawn`, drawn once (a frozen protocol: the planner asks for it a dozen
        times a slide)."""
        return self.nominal.drawn(self.seed)

    @cached_property
    def window(self) -> SlideWindow:
        """Where the slide starts and stops on its plate and its samples (the finger
        scene's; the rig records ``duration_s``)."""
        return SlideWindow.of(self.plate, self.pad.patch_m[0], self.drawn())

    def n_samples(self) -> int:
        """Samples the slide records (its window; on the rig, ``duration_s`` at its rate)."""
        if self.rig is not None:
            return max(1, round(self.nominal.duration_s * self.nominal.rate_hz))
        return SlideWindow.of(self.plate, self.pad.patch_m[0], self.nominal).n_samples

    @cached_property
    def resolved(self) -> Fidelity:
        """The fidelity the slide runs at (:func:`~.fidelity.choose_fidelity` of its
        ``fidelity``, ``pitch_m`` and ``dt_s`` for its drawn protocol), with the sensor's
        own warning where its transducer asks more of the step
        (:func:`~.vibration.vibration_warning`)."""
        fid = choose_fidelity(
            self.plate,
            self.layout,
            self.pad,
            self.drawn(),
            self.fidelity,
            pitch_m=self.pitch_m,
            dt_s=self.dt_s,
        )
        warn = vibration_warning(self.plate, self.sensor_def.transducers, fid)
        return fid if warn is None else replace(fid, warnings=(*fid.warnings, warn))

    def table_plan(self) -> PhasePlan | None:
        """The phase plan where the slide's loads are read off a phase table, else None: the
        per-step slide (:attr:`route`)."""
        return self.route[0]

    @cached_property
    def route(self) -> tuple[PhasePlan | None, StepOptions]:
        """``(plan, options)``: how the slide is computed, its ``options`` resolved.

        ``path`` ``phase-table`` takes the table wherever the scene allows it
        (:func:`~.span.table_plan`). ``auto`` chooses only where no other knob was set by
        hand (else it is ``per-step``, the knobs as given): the table where the whole window
        lies on the repeating
        texture (the slide then needs no press and no step solved on its own), or where it
        lies there for part of it and the table pays (:func:`~.phase.table_pays`: a uniform
        stretch's table is one solve, and tables the set's slides share cost a few a plate)
        or each step's solve is dear (a spectral skin: a table costs tens of solves, the
        stretch it replaces hundreds; a cheap dense or plate-anchored step of a slide's own
        table is as quick solved as read; a spectral table's solves run to
        :data:`~.options.AUTO_TABLE_TOL`). Elsewhere the slide is solved step
        by step; under ``auto`` with a spectral skin, to
        :data:`~.options.AUTO_SOLVE_TOL` and at every :data:`~.options.AUTO_SOLVE_EVERY`-th
        step where the force is held (their errors measured within 2% on the task scenes);
        where the force is held on a flat pad whose dense problem would be full and large
        (:func:`~.solver.dense_is_dear`), spectrally to :data:`~.options.AUTO_SOLVE_TOL`
        instead (the same problem, within 0.005% of the dense solve), at every step, or at
        every :data:`~.options.AUTO_SOLVE_EVERY`-th on a texture of smooth caps
        (:func:`~.solver.smooth_relief`); where
        it is held on a dense skin solved as a full problem (:func:`~.solver.dense_step_is_dear`),
        at every :data:`~.options.AUTO_SOLVE_EVERY`-th step;
        ``per-step`` is the reference, the knobs as given. A sensor that reports the load's
        vibration (:func:`~.vibration.reports_vibration`) is solved at every step under
        ``auto``: the fast paths' errors were measured on the loads, and they smooth the
        vibration between their points. The resolved options say which (``path``
        ``phase-table`` or ``per-step``). The probe rig has its own slide."""
        opts = self.options
        # auto chooses only where no knob of the numbers was set by hand (the device says
        # where the batched solves run, not what they give)
        default = replace(opts, device="cpu") == StepOptions()
        vibration = opts.path == "auto" and reports_vibration(self.sensor_def.transducers)
        if self.rig is not None or (opts.path == "auto" and not default):
            return None, replace(opts, path="per-step")
        if vibration:
            return None, self._joint(replace(opts, path="per-step"))
        proto = self.drawn()
        auto = opts.path == "auto"
        plan = table_plan(
            self.plate,
            self.pad.patch_m,
            proto,
            self.window,
            opts.path,
            opts.solve_every,
            span=auto and self.plate_slides > 1,
        )
        if plan is not None and auto:
            lo, hi = travel(self.window, proto)
            if plan.span:
                plan = plan if self._span_pays(plan) else None
            elif not (
                (plan.covers(lo) and plan.covers(hi))
                or self.spectral
                or table_pays(plan, self.protocol)
            ):
                plan = None
        if plan is not None:
            tol = AUTO_TABLE_TOL if auto and self.spectral else opts.solve_tol
            tabled = replace(opts, path="phase-table", solve_tol=tol)
            return plan, self._joint(tabled) if auto else tabled
        held = proto.force_control == "quasi-static"
        if auto and held and self._dense_is_dear():
            smooth = smooth_relief(self.plate)
            every = AUTO_SOLVE_EVERY if smooth and self._every_fits else 1
            return None, replace(
                opts,
                path="per-step",
                skin_solver="spectral",
                solve_tol=AUTO_SOLVE_TOL,
                solve_every=every,
            )
        if auto and held and self._dense_step_is_dear():
            return None, self._joint(replace(opts, path="per-step", solve_every=AUTO_SOLVE_EVERY))
        if not (auto and self.spectral):
            stepped = replace(opts, path="per-step")
            return None, self._joint(stepped) if auto else stepped
        every = AUTO_SOLVE_EVERY if held and self._every_fits else 1
        return None, replace(opts, path="per-step", solve_every=every, solve_tol=AUTO_SOLVE_TOL)

    def _joint(self, opts: StepOptions) -> StepOptions:
        """``opts`` with ``held_solve = "joint"`` where ``auto`` takes it: where the held step
        is the compiled dense one (a coupled skin solved densely under quasi-static force
        control, neither anchored to the plate's walls nor clipped); elsewhere the knob would
        not act, and is left out of the slide's key."""
        fid = self.resolved
        compiled = (
            opts.compiled_hold
            and self.drawn().force_control == "quasi-static"
            and fid.level != "L0"
            and fid.wall_m is None
            and not fid.clipped
            and not self.spectral
        )
        return replace(opts, held_solve="joint") if compiled else opts

    @property
    def _every_fits(self) -> bool:
        """Whether a sample spans at least :data:`~.options.AUTO_SOLVE_EVERY` steps."""
        return self.resolved.steps_per_sample >= AUTO_SOLVE_EVERY

    def _span_pays(self, plan: PhasePlan) -> bool:
        """Whether ``auto`` takes a table along the slide (:func:`~.span.span_pays`) for the
        :attr:`plate_slides` slides of the set, against the solves each would take step by
        step (its own route alone says at which steps), counted on the set's nominal slide:
        every slide of a plate in a set decides alike."""
        nominal = replace(
            self,
            protocol=replace(
                self.protocol, speed_jitter=0.0, force_jitter=0.0, offset_jitter_m=0.0
            ),
            plate_slides=1,
        )
        fid = nominal.resolved
        steps = nominal.window.n_samples * fid.steps_per_sample
        every = nominal.how.solve_every
        return span_pays(
            plan,
            self.plate,
            self.pad.patch_m,
            self.protocol,
            fid.pitch_m,
            steps / every,
            self.plate_slides,
            nominal.spectral,
        )

    @cached_property
    def _by_column(self) -> bool:
        """Whether the pad's depths do not depend on their y at the drawn offset
        (:func:`~.phase.depths_by_column`), as both solver choices below ask."""
        return depths_by_column(self.plate, self.pad.patch_m, self.drawn().offset_y_m)

    def _dense_is_dear(self) -> bool:
        """Whether ``auto`` takes the spectral solve for a skin it would solve densely
        (:func:`~.solver.dense_is_dear`: a flat pad's full problem of many nodes)."""
        if self.spectral or not self.resolved.coupled:
            return False
        return dense_is_dear(self.resolved, self.pad, self._by_column)

    def _dense_step_is_dear(self) -> bool:
        """Whether ``auto`` solves the slide's dense skin at every
        :data:`~.options.AUTO_SOLVE_EVERY`-th step (:func:`~.solver.dense_step_is_dear`)."""
        return dense_step_is_dear(self.resolved, self.pad, self._by_column, self.spectral)

    @property
    def held_press(self) -> bool:
        """Whether the slide's press is one held equilibrium rather than the approach, the
        ramp and the settling step by step: ``path = auto`` with no knob set by hand, under
        quasi-static force control (the per-step reference presses step by step)."""
        opts = self.options
        return (
            self.rig is None
            and opts.path == "auto"
            and replace(opts, device="cpu") == StepOptions()
            and self.drawn().force_control == "quasi-static"
        )

    @property
    def spectral(self) -> bool:
        """Whether the slide's skin is solved spectrally (:func:`~.fidelity.solved_spectrally`)."""
        return solved_spectrally(self.resolved, self.pad, self.options.skin_solver)

    @property
    def how(self) -> StepOptions:
        """The options the slide runs with (:attr:`route`'s)."""
        return self.route[1]

    # ------------------------------------------------------------------ described once
    def describe(self) -> dict:
        """Everything that determines the slide, as JSON data: the one dict behind its cache
        key, its recording's meta and a store's attributes. ``rig``, ``pitch_m``, ``dt_s``
        and the knobs appear only where they are set, so the descriptions of slides that
        leave them at their defaults are unchanged: the knobs as the slide runs them
        (:attr:`route`: those ``path = auto`` chose, as if they were set), and ``path``
        ``phase-table`` where the slide is read off a phase table, so that nothing another
        path made is served for it."""
        d = {
            "kind": "slide",
            "plate": self.plate.params(),
            "sensor": self.sensor_def.to_json(),
            "protocol": self.protocol.to_json(),
            "seed": int(self.seed),
            "fidelity": self.fidelity
            if isinstance(self.fidelity, str)
            else self.fidelity.to_json(),
            "ideal": bool(self.ideal),
            "finger": None if self.finger is None else self.finger.to_json(),
        }
        if self.rig is not None:
            d["rig"] = self.rig.to_json()
        if self.pitch_m is not None:
            d["pitch_m"] = self.pitch_m
        if self.dt_s is not None:
            d["dt_s"] = self.dt_s
        d.update(keyed(self.how))  # the knobs as the slide runs them
        if self.table_plan() is not None:  # another path, another key
            d["path"] = "phase-table"
        if self.held_press:
            d["press"] = "held"
        return d

    def meta_head(self) -> dict:
        """The keys a simulated window's recording meta starts with: the plate, the sensor,
        the pad, the drawn and nominal protocols and the seed."""
        sensor = self.sensor_def
        return {
            "plate": self.plate.name or self.plate.hash,
            "plate_hash": self.plate.hash,
            "plate_params": self.plate.params(),
            "layout": sensor.layout.name,
            "sensor": sensor.name,
            "channel_names": list(sensor.layout.names),
            "finger": self.pad.to_json(),
            "protocol": self.drawn().to_json(),
            "protocol_nominal": self.nominal.to_json(),
            "seed": self.seed,
        }

    def named(self) -> str:
        """How messages name the slide: its label, else its plate's name or hash."""
        return self.label or self.plate.name or self.plate.hash
