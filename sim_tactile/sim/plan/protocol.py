"""The slide protocol and its window: what the pad does, where, and for how long.

:class:`Protocol` is the recipe of one slide (speed, force, window, rate, the phases before
the slide, and how much speed, force and offset vary from slide to slide);
:meth:`Protocol.drawn` is the one place where a slide's values are drawn from its seed. :class:`SlideWindow`
says where a slide starts and stops on a given plate, for a pad of a given length, and how
many samples it records. This module imports no simulator: the task and data-set layers
describe slides with it without loading MuJoCo.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from ... import _validate as v
from ...errors import ConfigError

#: Approach speed [m/s] and the clearance the pad starts at above the plate [m].
APPROACH_SPEED = 0.01
APPROACH_CLEARANCE_M = 0.3e-3
#: Flat ground [m] between the pad and the textured area where a crossing starts and ends.
START_MARGIN_M = 2e-3
#: The slide's speed ramps up over this time [s] at the start of each stroke.
SPEED_RAMP_S = 0.02
#: The longest window a slide may record [s]: ``duration_s``'s cap, and the default window's
#: (the time to cross the texture) too, so a slow speed cannot run a slide for hours or ask
#: for billions of samples.
MAX_DURATION_S = 600.0

#: How the press force is held during press, settle and slide (``Protocol.force_control``):
#:
#: - ``dynamic``: the bone is a mass on the press joint, pushed by the commanded force against
#:   the skin's load, with damping critical at the flat pad's stiffness (MuJoCo integrates
#:   it). The force overshoots where the load changes fast (a ridge's edge) and the pad leaves
#:   the plate behind tall features; the coupling limits the time step (omega * dt).
#: - ``quasi-static``: an ideal force controller: every step the pad is moved to the height at
#:   which the skin carries exactly the commanded force (the held step,
#:   :mod:`sim_tactile.sim.step.held`), so the load is a function of the pad's position alone: no
#:   transients and no step limit from the coupling.
#: - ``position``: no force control in the slide: the pad is lowered until the skin carries
#:   ``force_n`` (the touch: the soft finger of seed 002 was "brought down ... until the
#:   sensor array made physical contact"), then slides at that height, so the load follows
#:   the texture (a feature as tall as the skin is thick presses the skin to the bottom).
FORCE_CONTROLS = ("dynamic", "quasi-static", "position")

#: Where a slide starts (``Protocol.start``):
#:
#: - ``flat``: on flat ground before the textured area; with no ``duration_s`` the pad
#:   crosses the whole area and ends on flat ground past it;
#: - ``texture``: on the textured area, the pad's trailing edge :data:`START_MARGIN_M` inside
#:   its start, for ``duration_s`` (required); the stroke ends as far inside the area's other
#:   end, so the pad never leaves the texture (as on the 20 cm strips of seed 000). A slide
#:   that would run past it rests there, and says so.
STARTS = ("flat", "texture")


@dataclass(frozen=True)
class Protocol:
    """The slide protocol, SI units. ``duration_s`` None: cross the whole textured area,
    starting and ending with the pad on flat ground. ``rate_hz`` None: the sensor's rate.
    The jitters are relative standard deviations (speed, force) and one in metres (the
    offset across the slide), drawn once per slide (:meth:`drawn`)."""

    speed_m_s: float = 0.06
    force_n: float = 1.0
    duration_s: float | None = None
    rate_hz: float | None = None
    press_s: float = 0.1
    settle_s: float = 0.2
    passes: int = 1
    return_stroke: bool = False
    offset_y_m: float = 0.0
    speed_jitter: float = 0.0
    force_jitter: float = 0.0
    offset_jitter_m: float = 0.0
    force_control: str = "quasi-static"
    start: str = "flat"

    def __post_init__(self) -> None:
        v.in_range("speed_m_s", self.speed_m_s, 0.0, 1.0, unit="m/s")
        v.in_range("force_n", self.force_n, 1e-3, 50.0, lo_open=False, unit="N")
        if self.duration_s is not None:
            v.in_range("duration_s", self.duration_s, 1e-3, MAX_DURATION_S, unit="s")
        if self.rate_hz is not None:
            v.in_range("rate_hz", self.rate_hz, 1.0, 100_000.0, unit="Hz")
        v.in_range("press_s", self.press_s, 0.0, 10.0, unit="s")
        v.in_range("settle_s", self.settle_s, 0.0, 10.0, unit="s")
        v.integer("passes", self.passes, 1, 100)
        v.in_range("offset_y_m", self.offset_y_m, -0.05, 0.05, unit="m")
        v.in_range("speed_jitter", self.speed_jitter, 0.0, 0.5)
        v.in_range("force_jitter", self.force_jitter, 0.0, 0.5)
        v.in_range("offset_jitter_m", self.offset_jitter_m, 0.0, 0.01, unit="m")
        v.one_of("force_control", self.force_control, FORCE_CONTROLS)
        v.one_of("start", self.start, STARTS)
        if self.start == "texture" and self.duration_s is None:
            raise ConfigError(
                "start = 'texture' needs duration_s: the slide stays on the textured area, so "
                "its window cannot be the area's crossing"
            )

    def to_json(self) -> dict:
        """The protocol as JSON data (what slide keys are made from). ``start`` came later:
        at its default ``flat`` it is left out, so the keys of slides made before it stay."""
        d = asdict(self)
        if d["start"] == "flat":
            del d["start"]
        return d

    def at_rate(self, rate_hz: float) -> Protocol:
        """This protocol with its rate set (the sensor's ``rate_hz`` unless it has its own)."""
        return self if self.rate_hz is not None else replace(self, rate_hz=float(rate_hz))

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

    def drawn(self, seed: int) -> Protocol:
        """The protocol of the slide seeded ``seed``: speed, force and offset drawn from
        ``default_rng(seed)``, whoever simulates the slide and whoever records its values."""
        return self.varied(np.random.default_rng(v.integer("seed", seed, 0, 2**63 - 1)))


@dataclass(frozen=True)
class SlideWindow:
    """Where a slide starts and stops on a plate and how many samples it records.

    The pad (``pad_length_m`` along the slide) starts on flat ground with
    :data:`START_MARGIN_M` between its edge and the textured area, and a stroke ends as far
    past it on the other side; a stroke that would carry the pad off the plate stops at
    ``x_limit_m`` and the pad rests there. Positions are the pad centre's x [m]."""

    x_start_m: float
    x_end_m: float
    x_limit_m: float
    strokes: tuple[tuple[float, float, float], ...]
    n_samples: int

    @staticmethod
    def crossing_s(area_length_m: float, pad_length_m: float, speed_m_s: float) -> float:
        """Time [s] for a pad to cross a textured area from flat ground to flat ground."""
        return (area_length_m + pad_length_m + 2 * START_MARGIN_M) / speed_m_s

    @classmethod
    def window_s(
        cls, area_lengths_m, pad_length_m: float, speed_m_s: float, rate_hz: float
    ) -> float:
        """A window [s] that covers the crossing of the longest of the areas, whole samples
        (at most :data:`MAX_DURATION_S`, as an explicit ``duration_s``)."""
        if speed_m_s <= 0:
            raise ConfigError("speed_m_s = 0 needs a duration_s")
        longest = max(area_lengths_m)
        t = cls.crossing_s(longest, pad_length_m, speed_m_s)
        _default_duration(t, f"a {longest:g} m textured area", speed_m_s)
        return math.ceil(t * rate_hz) / rate_hz

    @classmethod
    def of(cls, plate, pad_length_m: float, protocol: Protocol) -> SlideWindow:
        """The window of ``protocol`` (its rate set) on ``plate`` for a pad this long."""
        if protocol.rate_hz is None:
            raise ConfigError("the slide window needs the protocol's rate; give rate_hz")
        if protocol.start == "texture":
            half = plate.area_length_m / 2 - pad_length_m / 2 - START_MARGIN_M
            if half <= 0:
                raise ConfigError(
                    f"plate {plate.name or plate.hash}: its textured area "
                    f"({plate.area_length_m:g} m) is too short for a {pad_length_m:g} m pad to "
                    f"start on it; valid: area_length_m > {pad_length_m + 2 * START_MARGIN_M:g} m"
                )
        else:
            half = plate.area_length_m / 2 + pad_length_m / 2 + START_MARGIN_M
        x_start = -half
        x_end = -x_start
        if plate.length_m / 2 < x_end + 1e-9:
            raise ConfigError(
                f"plate {plate.name or plate.hash} ({plate.length_m:g} m long) is too short for a "
                f"{pad_length_m:g} m pad to enter and leave the textured area on flat ground"
            )
        if protocol.start == "texture":
            x_limit = x_end
        else:
            x_limit = max(x_end, plate.length_m / 2 - pad_length_m / 2)
        strokes = []
        for _ in range(protocol.passes):
            strokes.append((x_start, x_end, 1.0))
            if protocol.return_stroke:
                strokes.append((x_end, x_start, -1.0))
        rate, speed = protocol.rate_hz, protocol.speed_m_s
        if protocol.duration_s is not None:
            n = max(1, round(protocol.duration_s * rate))
        else:
            if speed == 0:
                raise ConfigError("speed_m_s = 0 needs a duration_s")
            length = sum(abs(b - a) for a, b, _ in strokes)
            what = f"plate {plate.name or plate.hash}'s textured area"
            if len(strokes) > 1:
                what += f" {len(strokes)} times"
            t = _default_duration(length / speed, what, speed)
            n = max(1, math.ceil(t * rate))
        return cls(x_start, x_end, x_limit, tuple(strokes), n)


def _default_duration(t_s: float, what: str, speed_m_s: float) -> float:
    """``t_s``, a slide's default window (the time to cross ``what`` at ``speed_m_s``), if
    it obeys :data:`MAX_DURATION_S` as an explicit ``duration_s`` must; else a ConfigError
    naming the speed, the window and the cap."""
    if not t_s <= MAX_DURATION_S:  # (also NaN and inf)
        raise ConfigError(
            f"speed_m_s = {speed_m_s:g} m/s takes {t_s:.4g} s to cross {what} (the default "
            f"duration); valid: at most {MAX_DURATION_S:g} s, as for duration_s: raise "
            "speed_m_s or give duration_s"
        )
    return t_s
