"""The benchmark's scenes, derived from the task registry: each task that names a
:class:`~sim_tactile.tasks.registry.BenchScene` gives its plate, slid with the task's sensor at
its protocol's nominal speed and force; and the Hertz press, the closed form of a static
contact."""

from __future__ import annotations

from dataclasses import dataclass

from ..sensors import Finger
from ..slides import SlideSet
from ..tasks import get_task, task_ids


@dataclass(frozen=True)
class SlideScene:
    """A task's slide: plate, sensor (its layout, pad and rate), speed and normal force."""

    key: str
    task: str
    plate: str
    sensor: str
    speed_m_s: float
    force_n: float

    @property
    def name(self) -> str:
        return f"{self.plate} {self.sensor} {self.speed_m_s * 1e3:g} mm/s {self.force_n:g} N"


@dataclass(frozen=True)
class PressScene:
    """A static press of a spherical pad on a flat plate: Hertz's problem. ``pad_m`` is the
    side of the pad's node patch (more than the contact diameter), ``readout_pitch_m`` the
    pitch of the dense taxel grid whose pressure is compared."""

    key: str
    task: str
    radius_m: float = 8e-3
    young_pa: float = 0.3e6
    poisson: float = 0.5
    force_n: float = 1.0
    pad_m: float = 7e-3
    thickness_m: float = 5e-3
    readout_pitch_m: float = 0.25e-3

    @property
    def name(self) -> str:
        return (
            f"Hertz press: sphere R {self.radius_m * 1e3:g} mm, E {self.young_pa / 1e6:g} MPa, "
            f"{self.force_n:g} N"
        )

    def finger(self) -> Finger:
        return Finger(
            shape="sphere",
            radius_m=self.radius_m,
            size_m=(self.pad_m, self.pad_m),
            young_pa=self.young_pa,
            poisson=self.poisson,
            thickness_m=self.thickness_m,
        )


#: The Hertz press (not a task: the closed form of a spherical pad on a flat plate).
HERTZ = PressScene("hertz", "press (closed form)")


def scenes() -> dict[str, SlideScene | PressScene]:
    """Every scene by key: the registered tasks' (in registry order), then the press."""
    out: dict[str, SlideScene | PressScene] = {}
    for tid in task_ids():
        spec = get_task(tid)
        if spec.bench is None or not isinstance(spec.get_data, SlideSet):
            continue
        ss = spec.get_data
        out[spec.bench.key] = SlideScene(
            spec.bench.key,
            spec.id,
            spec.bench.plate,
            ss.sensor,
            ss.protocol.speed_m_s,
            ss.protocol.force_n,
        )
    out[HERTZ.key] = HERTZ
    return out


def default_left_out() -> dict[str, str]:
    """Scenes the full sweep leaves out by default, with the task's reason."""
    return {
        get_task(t).bench.key: get_task(t).bench.left_out
        for t in task_ids()
        if get_task(t).bench is not None and get_task(t).bench.left_out
    }
