"""The probe rig of the multilayer paper (seed 003): what it is and where the probe goes.

In that rig the sensor lies flat on the rig's rigid loading bed and stays there; a rigid
probe carrying a 36 x 36 mm texture presses on it with a set force and slides across it, in
both directions, pausing at each end of the track (the paper's Fig. 3). :class:`ProbeRig`
holds the rig's own choices, each with its source or marked as an assumption;
:class:`ProbePass` is one window's pass of the probe over the sensor: where it starts and
stops, when it moves, and its speed command at any time. This module imports no simulator
(the task and data-set layers describe slides with it); :mod:`.rig_sim` simulates them.

Coordinates: the sensor's frame, x along the slide, the sensor's centre at the origin; the
probe's position is its face's centre. The probe's face is the plate's textured area, its
features facing down onto the sensor.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ... import _validate as v
from ...errors import ConfigError
from .protocol import SPEED_RAMP_S, START_MARGIN_M

#: Where the pass sits in the window (``ProbeRig.pass_at``): ``centre``: the pause before
#: and the pause after it are equal (the paper segments each cycle at the pauses, so a
#: window holds one pass between two pauses; how the 5 s were split is not given).
PASS_PLACES = ("centre",)
#: Which way a slide's probe goes (``ProbeRig.direction``): ``both``: drawn from the
#: slide's seed, half of the slides each way (the paper slides in both directions and keeps
#: every pass); ``+x`` / ``-x``: every slide one way.
DIRECTIONS = ("both", "+x", "-x")


@dataclass(frozen=True)
class ProbeRig:
    """The multilayer paper's rig (see the module docstring), SI units.

    node_pitch_m: the probe face's node lattice [m] (both directions), on which the contact
        is solved (measured convergence: ``docs/probe_rig.md``).
    probe_mass_kg: the probe and its carriage, which MuJoCo moves (assumption: not given;
        under the held force it only sets how closely the carriage follows its speed
        command, within micrometres here).
    margin_m: how far past the sensor's outermost elements the probe's edge starts and
        stops, beyond :data:`~.protocol.START_MARGIN_M` plus twice the sensor's thickness
        (where the stress of the probe's edge has died out); None: that.
    direction: :data:`DIRECTIONS`. pass_at: :data:`PASS_PLACES`.
    """

    node_pitch_m: float = 0.25e-3
    probe_mass_kg: float = 0.3
    margin_m: float | None = None
    direction: str = "both"
    pass_at: str = "centre"

    def __post_init__(self) -> None:
        v.in_range("rig node_pitch_m", self.node_pitch_m, 50e-6, 2e-3, unit="m")
        v.in_range("rig probe_mass_kg", self.probe_mass_kg, 1e-3, 100.0, unit="kg")
        if self.margin_m is not None:
            v.in_range("rig margin_m", self.margin_m, 0.0, 0.1, unit="m")
        v.one_of("rig direction", self.direction, DIRECTIONS)
        v.one_of("rig pass_at", self.pass_at, PASS_PLACES)

    def to_json(self) -> dict:
        return asdict(self)

    @classmethod
    def from_json(cls, d: dict) -> ProbeRig:
        v.known_keys("rig", d, cls.__dataclass_fields__)
        return cls(**d)

    def sign(self, seed: int) -> float:
        """The direction of the slide seeded ``seed``: +1 (along +x) or -1. With ``both``,
        drawn from ``default_rng([seed, 2])`` (the transducer's noise takes stream 1)."""
        if self.direction != "both":
            return 1.0 if self.direction == "+x" else -1.0
        return 1.0 if np.random.default_rng([int(seed), 2]).integers(2) == 0 else -1.0


@dataclass(frozen=True)
class ProbePass:
    """One window's pass (see the module docstring): the probe's centre goes from
    ``x_from_m`` to ``x_to_m`` at ``speed_m_s``, ramped up and down over
    :data:`~.protocol.SPEED_RAMP_S`, starting ``t_start_s`` into the window; it rests at
    either end before and after."""

    x_from_m: float
    x_to_m: float
    speed_m_s: float
    t_start_s: float
    ramp_s: float

    @classmethod
    def of(
        cls,
        rig: ProbeRig,
        probe_length_m: float,
        reach_m: float,
        sheet_m: float,
        speed_m_s: float,
        duration_s: float,
        sign: float,
    ) -> ProbePass:
        """The pass of a probe ``probe_length_m`` long over elements reaching ``reach_m`` from
        the sensor's centre (their outer edges), on a sensor ``sheet_m`` thick, at
        ``speed_m_s``, in a window of ``duration_s``, along ``sign`` (+1 or -1)."""
        if not speed_m_s > 0:
            raise ConfigError(f"speed_m_s = {speed_m_s:g}; valid: > 0 m/s for the rig's pass")
        margin = rig.margin_m if rig.margin_m is not None else START_MARGIN_M + 2 * sheet_m
        half = reach_m + probe_length_m / 2 + margin
        ramp = SPEED_RAMP_S
        moving = 2 * half / speed_m_s + ramp  # a trapezoid: ramps of `ramp` s at both ends
        if moving > duration_s:
            raise ConfigError(
                f"duration_s = {duration_s:g} s is too short for the probe's pass of "
                f"{2 * half * 1e3:.3g} mm at {speed_m_s * 1e3:.3g} mm/s ({moving:.3g} s); "
                f"valid: duration_s >= {moving:.3g} s"
            )
        return cls(-sign * half, sign * half, speed_m_s, (duration_s - moving) / 2, ramp)

    @property
    def sign(self) -> float:
        return math.copysign(1.0, self.x_to_m - self.x_from_m)

    @property
    def moving_s(self) -> float:
        return abs(self.x_to_m - self.x_from_m) / self.speed_m_s + self.ramp_s

    def speed(self, t: float | np.ndarray) -> np.ndarray:
        """The speed command [m/s] (signed) at window time ``t`` [s]: zero while it rests,
        ramped linearly up over ``ramp_s``, held, and ramped down to rest at ``x_to_m``."""
        tau = np.asarray(t, float) - self.t_start_s
        up = np.clip(tau / self.ramp_s, 0.0, 1.0)
        down = np.clip((self.moving_s - tau) / self.ramp_s, 0.0, 1.0)
        return self.sign * self.speed_m_s * np.minimum(up, down)

    def position(self, t: float | np.ndarray) -> np.ndarray:
        """The commanded position [m] at window time ``t``: the integral of :meth:`speed`."""
        tau = np.clip(np.asarray(t, float) - self.t_start_s, 0.0, self.moving_s)
        r, T = self.ramp_s, self.moving_s
        up = np.minimum(tau, r) ** 2 / (2 * r)
        mid = np.clip(tau - r, 0.0, T - 2 * r)
        down_t = np.clip(tau - (T - r), 0.0, r)
        down = down_t - down_t**2 / (2 * r)
        return self.x_from_m + self.sign * self.speed_m_s * (up + mid + down)
