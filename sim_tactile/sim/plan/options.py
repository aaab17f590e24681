"""How a slide is computed, as opposed to what it is: every knob of :class:`StepOptions`,
declared once with its range (:data:`KNOBS`), in scikit-learn's ``_param_validation``
manner.

The declaration is read by everything that takes a knob: :class:`StepOptions` checks its
fields against it; a slide's description (:meth:`~.slide.Slide.describe`, so its cache key)
records the knobs set away from their defaults (:func:`keyed`); configuration files
(:mod:`sim_tactile.slides.config`) and the command line (``simulate``'s flags) take the
public ones by their names, with the help and range written here; the file-format reference
is generated from it. A new knob is one :class:`Knob` here, its field on
:class:`StepOptions`, and the code that reads it.

This module imports neither MuJoCo nor numba (the planner's floor).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

from ... import _validate as v
from ...errors import ConfigError

#: Most steps one held solve may stand for (``StepOptions.solve_every``): a sample of the
#: slowest sensors spans about 20 steps.
MAX_SOLVE_EVERY = 64
#: The range a spectral contact solve's tolerance may be set in (``StepOptions.solve_tol``;
#: its default, the reference, is :data:`~sim_tactile.sim.skin.contact.spectral.TOL`).
SOLVE_TOL_RANGE = (1e-12, 1e-3)
#: The node pitch [m] and the time step [s] a slide may force (``pitch_m``, ``dt_s`` of a
#: slide, a set or a configuration file; :func:`check_forced`).
PITCH_RANGE_M = (20e-6, 5e-3)
DT_RANGE_S = (1e-6, 1e-2)
#: Where a node pitch of one's own is set (the warnings that ask for one name them).
OWN_PITCH = "a data set's pitch_m, simulate --node-pitch, Python's pitch_m"


def check_forced(pitch_m: float | None, dt_s: float | None) -> None:
    """Refuse a forced node pitch or time step (None: not forced) outside its range
    (:data:`PITCH_RANGE_M`, :data:`DT_RANGE_S`), naming it."""
    if pitch_m is not None:
        v.in_range("pitch_m", pitch_m, *PITCH_RANGE_M, unit="m")
    if dt_s is not None:
        v.in_range("dt_s", dt_s, *DT_RANGE_S, unit="s")


#: What ``path = auto`` takes where a slide is solved step by step with a spectral skin (the
#: dear solve: tens of FFT products a step) and its knobs are at their defaults: the
#: spectral solve to this tolerance, the loosest its range allows. Measured on
#: textures20-icub60-v1 (slides 0 and 1 at every 2nd step, against the same at 1e-7): the
#: taxel loads of boxes-3.0mm and 4.5mm, cylinders-3.0mm and 4.5mm, hemispheres-3.0mm and
#: 6.0mm and rough-ra25 move by 5e-5 to 1.5e-4 rel L2 (largest taxel 5.3e-4), against 5e-6
#: to 1.2e-5 at 1e-4, which was 1.8x faster than the reference (perf/bench_response.py);
#: 1e-3 is 1.1-1.25x faster again on those slides, and 1.14x on the icub60-v1 data set ...
AUTO_SOLVE_TOL = 1e-3
#: What ``auto`` takes for a phase table's solves on a spectral skin (and the table along a
#: slide): a table's phases converge from their neighbours' answers, and at 1e-3 they took
#: no less time (the icub60-v2 data set 0.99x), so its entries keep the tighter tolerance
#: whose loads agree with the reference's to better than 5e-6.
AUTO_TABLE_TOL = 1e-4
#: ... and the skin solved at every this-many steps of a held slide, the loads between on
#: the line between two solves, where a sample spans at least this many steps. Measured
#: against the per-step solve on every spectral plate of textures20-icub60-v1 (the first
#: slide of each, and three of the five worst): at every 2nd step at most 1.62% rel L2
#: (0.15-0.34% on the v2 strips' rough plates); at every 4th, five plates beyond 2% (boxes,
#: cylinders and hemispheres of 3-4.5 mm, the drafted grating: up to 2.91%), where a wall's
#: jump is smeared over four steps' travel. The same on a held slide's dense skin solved as a
#: full problem (:func:`~.solver.dense_step_is_dear`), measured on every plate where auto
#: takes it (perf/bench_every_plate.py --dense, slides 0-2): multilayer3-v1's hemispheres
#: 0.95-1.10% (every 3rd: 1.92-2.21%), textures20-biotac19-v1's seven grids 0.11-1.06%.
AUTO_SOLVE_EVERY = 2
#: How a held slide's taxel loads are computed (``StepOptions.path``): ``auto`` (the phase
#: table where the scene allows it, its measured error is within target and it pays, else
#: the per-step solve), ``per-step`` (the skin solved at every step: the reference) or
#: ``phase-table`` (asked for: refused where the scene does not allow it).
PATHS = ("auto", "per-step", "phase-table")
#: Where the batched solves run (``StepOptions.device``): the CPU, or a GPU through torch.
DEVICES = ("cpu", "cuda")
#: How a dense skin's held step finds the height that carries the force where its contact
#: set changes (``StepOptions.held_solve``): ``newton``, Newton's iteration on the height
#: with the set solved to convergence at each trial height (the reference), or ``joint``,
#: the set and the height solved together (the same solution, in fewer block updates of the
#: set's inverse; what ``auto`` takes on a dense skin).
HELD_SOLVES = ("newton", "joint")


@dataclass(frozen=True)
class Knob:
    """One knob of :class:`StepOptions`: its ``name``, what it does (``help``), its ``kind``
    (``bool``, ``int``, ``float`` or ``choice``), its range (``lo``, ``hi``; ``choices``),
    whether None is allowed (``optional``: the reference), and whether configuration files
    and the command line take it (``public``). Every knob away from its default enters a
    slide's description, so its cache key (``keyed``), or the slide records what the knob
    resolves to (``path``: the path it takes)."""

    name: str
    help: str
    kind: str
    lo: float | None = None
    hi: float | None = None
    choices: tuple[str, ...] = ()
    optional: bool = False
    public: bool = False
    #: whether a slide's description records it as set (else the slide records what it
    #: resolves to: ``path``)
    keyed: bool = True

    def check(self, value: Any) -> Any:
        """``value`` checked against the declaration and in its canonical type (a float
        that reads as one, an int, a bool, a choice); a ConfigError names the knob, the
        value and the valid range."""
        if value is None and self.optional:
            return None
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise ConfigError(f"{self.name} must be true or false, got {value!r}")
            return value
        if self.kind == "int":
            lo = None if self.lo is None else int(self.lo)
            hi = None if self.hi is None else int(self.hi)
            return v.integer(self.name, value, lo, hi)
        if self.kind == "float":
            if isinstance(value, bool):
                raise ConfigError(f"{self.name} must be a number, got {value!r}")
            return v.in_range(self.name, value, self.lo, self.hi)
        return v.one_of(self.name, value, self.choices)

    def valid(self) -> str:
        """The valid values, as messages and the reference print them."""
        if self.kind == "bool":
            out = "true or false"
        elif self.kind == "choice":
            out = ", ".join(self.choices)
        else:
            what = "integer" if self.kind == "int" else "number"
            out = f"{what} in [{self.lo:g}, {self.hi:g}]"
        return out + (" (absent: the reference)" if self.optional else "")


#: Every knob of :class:`StepOptions`, in its field order (see the module docstring).
KNOBS: tuple[Knob, ...] = (
    Knob(
        "primitive_collider",
        "the compiled collider of the plate (its features, a roughness profile or a height "
        "map), else MuJoCo's collider, the reference",
        "bool",
    ),
    Knob(
        "compiled_hold",
        "the held step as one compiled call where the compiled collider serves (else the "
        "plain loop, the reference)",
        "bool",
    ),
    Knob(
        "reduce_skin",
        "the compiled held step on the smallest exact problem (columns, mirror half)",
        "bool",
    ),
    Knob(
        "skin_solver",
        "the coupled skin's contact solve: auto (spectral above DENSE_MAX_NODES nodes), "
        "dense or spectral",
        "choice",
        choices=("auto", "dense", "spectral"),
    ),
    Knob(
        "held_solve",
        "a dense skin's held step where its contact set changes: newton (Newton's iteration "
        "on the height, the reference) or joint (the set and the height solved together, "
        "the same solution in fewer updates; auto takes it)",
        "choice",
        choices=HELD_SOLVES,
    ),
    Knob(
        "solve_every",
        "the skin solved at every n-th step of a slide held at its force, the taxel loads "
        "between read off the line between two solves (1: every step, the reference)",
        "int",
        1,
        MAX_SOLVE_EVERY,
        public=True,
    ),
    Knob(
        "solve_tol",
        "the spectral contact solve's tolerance (the pressures' relative change in one "
        "iteration at which it stops; absent: 1e-10, the reference)",
        "float",
        *SOLVE_TOL_RANGE,
        optional=True,
        public=True,
    ),
    Knob(
        "path",
        "how a held slide's taxel loads are computed: auto (the phase table where the plate "
        "repeats along the slide and its measured error allows, a table along the slide "
        "where no period serves but the plate does not vary across the pad (a rough "
        "profile, ridges) and the set has slides of the plate enough to pay for it, else "
        "per step), per-step (the reference) or phase-table (the table wherever the scene "
        "allows one)",
        "choice",
        choices=PATHS,
        public=True,
        keyed=False,
    ),
    Knob(
        "device",
        "where a phase table's phases are solved on a spectral skin: cpu, one after another, "
        "or cuda, all of a grid at once on a GPU (torch with CUDA; asked for where there is "
        "none, one error and nothing run)",
        "choice",
        choices=DEVICES,
        public=True,
    ),
)
#: The knobs by name.
KNOB = {k.name: k for k in KNOBS}


@dataclass(frozen=True)
class StepOptions:
    """How each part of a slide is computed (all fast by default); each field is a knob of
    :data:`KNOBS`, whose ``help`` says what it does and whose range it is checked against.

    primitive_collider, compiled_hold, reduce_skin, skin_solver: which implementation of
        each part of a step runs (each against its plain reference, tested equal);
    held_solve: ``newton`` or ``joint`` (:data:`HELD_SOLVES`): how the compiled held step
        solves a contact set that changes (``newton``: the reference);
    solve_every: under quasi-static force control, the skin solved at every n-th step, the
        taxel loads between on the line between two solves (1: every step, the reference);
    solve_tol: the spectral contact solve's tolerance (None: the reference, 1e-10);
    path: ``auto``, ``per-step`` or ``phase-table`` (:data:`PATHS`).
    device: ``cpu`` or ``cuda`` (:data:`DEVICES`): where a phase table's phases are solved.
    """

    primitive_collider: bool = True
    compiled_hold: bool = True
    reduce_skin: bool = True
    skin_solver: str = "auto"
    held_solve: str = "newton"
    solve_every: int = 1
    solve_tol: float | None = None
    path: str = "auto"
    device: str = "cpu"

    def __post_init__(self) -> None:
        for f in fields(self):  # each kept as the value it reads as (a float, an int)
            object.__setattr__(self, f.name, KNOB[f.name].check(getattr(self, f.name)))

    @classmethod
    def from_table(cls, table: dict[str, Any], where: str = "") -> StepOptions:
        """The options of a configuration's public knobs (``table``: name -> value; the
        others at their defaults); an unknown name is refused."""
        public = [k.name for k in KNOBS if k.public]
        v.known_keys(where, table, public)
        return cls(**{k: table[k] for k in public if k in table})


#: The defaults, to tell which knobs a slide sets.
_DEFAULT = StepOptions()


def keyed(options: StepOptions) -> dict[str, Any]:
    """The knobs of ``options`` away from their defaults, as JSON data: what a slide's
    description records of them (a slide at the defaults records none, so its key is the one
    it had before any knob existed)."""
    out = {}
    for k in (k for k in KNOBS if k.keyed):
        val = getattr(options, k.name)
        if val != getattr(_DEFAULT, k.name):
            out[k.name] = (
                val
                if k.kind in ("bool", "choice")
                else (int(val) if k.kind == "int" else float(val))
            )
    return out


def reference_rows() -> list[str]:
    """The public knobs as rows of the file-format reference's configuration table (key,
    unit, valid: the range, then what it does): the page holds these rows as written (a test
    compares them), so it follows this declaration."""
    return [f"| `{k.name}` | | {k.valid()}: {k.help} |" for k in KNOBS if k.public]
