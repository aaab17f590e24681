"""What a speed-against-error run sweeps: scenes, levels, time steps and node pitches."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from .. import _validate as v
from ..errors import ConfigError
from ..sim.fidelity import LEVELS
from ..sim.protocol import FORCE_CONTROLS
from .scenes import default_left_out, scenes

#: Every scene's key, in order.
ALL_SCENES = tuple(scenes())


@dataclass(frozen=True)
class Sweep:
    """What to run.

    scenes: keys of :data:`ALL_SCENES`. levels: which levels are swept (the L2 reference always
    runs, the errors need it). dt_factors / pitch_factors: multiples of each level's auto
    time step and node pitch for L0 and L1 (1 = the auto setting); l2_*: the same for L2,
    never finer than the reference. duration_s: slide duration [s] (None: cross the whole
    textured area); periods: if given (and no duration), slide until the whole pad has been
    over the texture for this many feature spacings (enough for the period check).
    press_pitches_m: node pitches of the press's L0 and L1 rows; press_ref_pitch_m: the
    reference's. physics: also measure each configuration's error against physics (an
    independent half-space solver, :mod:`~sim_tactile.bench.physics`) at
    ``physics_offsets`` pad offsets.
    """

    scenes: tuple[str, ...] = ALL_SCENES
    levels: tuple[str, ...] = LEVELS
    dt_factors: tuple[float, ...] = (4.0, 2.0, 1.0, 0.5)
    pitch_factors: tuple[float, ...] = (1.5, 1.0, 0.75)
    l2_dt_factors: tuple[float, ...] = (4.0, 2.0)
    l2_pitch_factors: tuple[float, ...] = (1.5,)
    duration_s: float | None = None
    periods: int | None = None
    press_pitches_m: tuple[float, ...] = (0.5e-3, 0.35e-3, 0.25e-3, 0.2e-3)
    press_ref_pitch_m: float = 0.1e-3
    quick: bool = False
    force_control: str = "quasi-static"
    physics: bool = True
    physics_offsets: int = 4

    def __post_init__(self) -> None:
        if not self.scenes:
            raise ConfigError(f"scenes is empty; valid: one or more of {', '.join(ALL_SCENES)}")
        for s in self.scenes:
            v.one_of("scene", s, ALL_SCENES)
        if len(set(self.scenes)) != len(self.scenes):
            raise ConfigError(f"scenes = {list(self.scenes)} names a scene twice")
        for lv in self.levels:
            v.one_of("level", lv, LEVELS)
        v.one_of("force_control", self.force_control, FORCE_CONTROLS)
        v.integer("physics_offsets", self.physics_offsets, 1, 16)

        for name in ("dt_factors", "pitch_factors", "l2_dt_factors", "l2_pitch_factors"):
            for f in getattr(self, name):
                v.in_range(name, f, 0.0, 16.0, lo_open=True)
        for f in self.l2_dt_factors + self.l2_pitch_factors:
            if f < 1.0:
                raise ConfigError(
                    f"l2 factor {f:g} would be finer than the L2 reference; valid: >= 1"
                )
        if self.duration_s is not None:
            v.in_range("duration_s", self.duration_s, 0.05, 60.0, unit="s")
        if self.periods is not None:
            v.integer("periods", self.periods, 2, 1000)
        for p in self.press_pitches_m:
            v.in_range("press_pitches_m", p, 0.05e-3, 2e-3, unit="m")
        v.in_range("press_ref_pitch_m", self.press_ref_pitch_m, 0.05e-3, 2e-3, unit="m")
        if self.press_pitches_m and self.press_ref_pitch_m > min(self.press_pitches_m):
            raise ConfigError(
                f"press_ref_pitch_m = {self.press_ref_pitch_m:g} m is coarser than a swept "
                f"pitch ({min(self.press_pitches_m):g} m); valid: the finest pitch"
            )


#: The full benchmark: every task's scene but those a task leaves out by default (see
#: :data:`LEFT_OUT`), every level, steps from 1/2 to 4x auto and pitches from 3/4 to 1.5x
#: auto, whole crossings.
FULL = Sweep(scenes=tuple(k for k in ALL_SCENES if k not in default_left_out()))

#: ``--quick`` (about a minute on two cores): three scenes, auto and 2x steps, short slides.
QUICK = Sweep(
    scenes=("finger7", "textures20", "hertz"),
    dt_factors=(2.0, 1.0),
    pitch_factors=(1.0,),
    l2_dt_factors=(),
    l2_pitch_factors=(),
    periods=3,
    press_pitches_m=(0.5e-3, 0.25e-3),
    press_ref_pitch_m=0.15e-3,
    quick=True,
    physics_offsets=2,
)

#: Why a sweep leaves a scene out (printed in its document, never silent).
LEFT_OUT = {
    "multilayer3": "left out of --quick: its L2 reference (0.4 mm nodes under 5 N) runs at "
    "about 1/40 of real time, minutes",
    "roughness8": "left out of --quick: no closed form to check; its 1 kHz L2 reference "
    "takes about 10 s",
    **{k: f"left out by default: {why}" for k, why in default_left_out().items()},
}


def sweep_for(
    quick: bool,
    scenes: Sequence[str] | None = None,
    levels: Sequence[str] | None = None,
    duration_s: float | None = None,
    physics: bool = True,
) -> Sweep:
    """The full or quick sweep, restricted to ``scenes`` and ``levels`` if given;
    ``physics=False`` leaves out the error against physics."""
    base = QUICK if quick else FULL
    changes: dict = {}
    if scenes is not None:
        changes["scenes"] = tuple(scenes)
    if levels is not None:
        changes["levels"] = tuple(levels)
    if duration_s is not None:
        changes["duration_s"] = duration_s
    if not physics:
        changes["physics"] = False
    return replace(base, **changes)
