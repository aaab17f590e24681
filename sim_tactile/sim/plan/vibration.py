"""What a sensor that reports the load's vibration asks beyond what the loads ask: its own
time step on a rough plate (:func:`vibration_warning`), and the per-step solve
(:func:`reports_vibration`: ``auto``'s fast paths were measured on the loads)."""

from __future__ import annotations

from ...plates.define.spec import Plate
from ...plates.define.surface import surface_of
from ...sensors.transducers import Piezoelectric
from .fidelity import Fidelity

#: Steps a sample at which a piezoelectric sensor's output on a rough plate is resolved to
#: a few percent. It reports the load's vibration (its high-pass reads a steady load as zero),
#: and a sample is the mean of its steps' loads, which the pad's fine roughness moves from
#: step to step: on roughness8's eight plates with pvdf2 (perf/bench_vibration.py, slides 0
#: and 5), against 16 steps a sample, the output is 15-81% off at one step a sample, 7-54% at
#: two, 3-15% at four and 1-8% at eight, while the raw loads are within 0.06-5.3% at one.
VIBRATION_STEPS = 8


def reports_vibration(transducers) -> bool:
    """Whether a sensor with these transducers reports the load's vibration (one is
    piezoelectric: its high-pass reads a steady load as zero). ``auto`` then solves such a
    slide at every step (:attr:`~.slide.Slide.route`): its tables and its solves at every
    n-th step smooth the vibration between their points, which their measured errors on the
    loads do not show (``pvdf2`` on roughness8's plates, perf/bench_vibration.py --paths
    --slides 0,5: every 2nd step moved the output by 2.4-62% and the table along the slide by
    0.7-77%, the loads by under 1% both)."""
    return any(isinstance(t, Piezoelectric) for t in transducers)


def vibration_warning(plate: Plate, transducers, fid: Fidelity) -> str | None:
    """The warning for a piezoelectric sensor (one of ``transducers``) on a rough plate at
    fewer than :data:`VIBRATION_STEPS` steps a sample (``fid``), else None: its output, the
    load's vibration, is then resolved to tens of percent only."""
    if surface_of(plate).ra_m is None or fid.steps_per_sample >= VIBRATION_STEPS:
        return None
    if not reports_vibration(transducers):
        return None
    n = fid.steps_per_sample
    finer = fid.dt_s * n / VIBRATION_STEPS
    return (
        f"a piezoelectric sensor reports the load's vibration, and on this rough plate a sample "
        f"of {n} step{'s' if n > 1 else ''} of {fid.dt_s * 1e3:.3g} ms resolves it to tens of "
        f"percent only (the loads themselves to a few); for a few percent: dt_s at most "
        f"{finer:.3g} s ({VIBRATION_STEPS} steps a sample, {VIBRATION_STEPS // n}x the steps: "
        "a data set's dt_s, simulate --dt, or dt_s in Python)"
    )


__all__ = ["VIBRATION_STEPS", "reports_vibration", "vibration_warning"]
