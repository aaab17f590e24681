"""Speed against error of the soft finger's fidelity levels, on each task's scene.

For every scene (the setup of a task: plate, sensor with its pad, speed and force) the sweep
runs each fidelity level (:mod:`sim_tactile.sim.fidelity`) at its auto setting and at
multiples of its auto time step and node pitch, and the Hertz press at a range of node
pitches. Each configuration is one row, all quantities SI:

- ``rtf``: simulated slide seconds per wall second of the slide loop (``slide_wall_s`` in
  the recording's metadata: approach, press and settling excluded), on one core
  (``simulate`` runs BLAS single-threaded); ``cost_s_per_s = 1 / rtf``. Wall times depend on
  the machine's load, which the document records.
- ``error_vs_reference``: ``||d - d_ref|| / ||d_ref||`` over the whole (time x taxel) ideal
  recording (``simulate(..., ideal=True)``: noise-free normal loads), where the reference is
  L2 at its own settings (half of L1's auto node pitch, a quarter of its auto step): the
  finest configuration of the sweep. For the press, the same norm over the pressure of a
  dense taxel grid, against the finest node pitch.
- ``error_vs_analytic``: ridges and gratings: ``|T / (s / v) - 1|``, the period ``T`` of the
  probe taxel's signal (the shallowest taxel nearest the pad's centre) while the whole pad
  is over the texture, against the feature spacing ``s`` over the pad's measured speed
  ``v``. The slide servo lags its command under the drag; that lag is
  ``analytic.speed_error``, reported apart. Hertz press: ``max(|a / a_H - 1|,
  |p0 / p0_H - 1|)`` (contact radius, peak pressure). ``None`` where no closed form exists
  (random roughness) or the period cannot be measured (the row says why).

:func:`run_speed_error` writes the rows as JSON, a Markdown table and a Pareto figure (one
panel per scene: cost against error, log axes, a marker series per level, the front drawn).

A configuration that stops with a :class:`~sim_tactile.errors.SimTactileError` (a too coarse
time step, say) is a row with ``outcome = "error"`` and the message in ``error``, never a
skipped row. An unexpected exception is a row with ``outcome = "crash"``.
"""

from __future__ import annotations

import json
import math
import os
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy import ndimage

from .. import _validate as v
from ..errors import ConfigError, SimTactileError
from ..plates import Plate, features, get_plate
from ..records import Recording
from ..scene.nodes import skin_grid
from ..sensors import Finger, Layout
from ..sim.fidelity import LEVELS, choose_fidelity
from ..sim.press import hertz, press
from ..sim.protocol import FORCE_CONTROLS, SPEED_RAMP_S, START_MARGIN_M, Protocol
from ..sim.simulate import simulate


def _nolog(msg: str) -> None:
    pass


# ---------------------------------------------------------------- scenes
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


#: The scene of each task, with its protocol's nominal speed and force (sim_tactile.tasks).
SCENES: dict[str, SlideScene | PressScene] = {
    "finger7": SlideScene("finger7", "finger7-v1", "finger7/ridges-4", "grid3x3", 0.06, 1.0),
    "multilayer3": SlideScene(
        "multilayer3", "multilayer3-v1", "multilayer3/grating-9", "multilayer3x3x2", 0.065, 5.0
    ),
    "textures20": SlideScene(
        "textures20", "textures20-v1", "textures20/grating-3.0mm", "biotac19", 0.025, 0.5
    ),
    "textures20-icub": SlideScene(
        "textures20-icub", "textures20-v1", "textures20/grating-3.0mm", "icub60", 0.04, 1.0
    ),
    "roughness8": SlideScene("roughness8", "roughness8-v1", "roughness8/ra-50", "pvdf2", 0.24, 1.0),
    "hertz": PressScene("hertz", "press (closed form)"),
}


# ---------------------------------------------------------------- sweeps
@dataclass(frozen=True)
class Sweep:
    """What to run.

    scenes: keys of :data:`SCENES`. levels: which levels are swept (the L2 reference always
    runs, the errors need it). dt_factors / pitch_factors: multiples of each level's auto
    time step and node pitch for L0 and L1 (1 = the auto setting); l2_*: the same for L2,
    never finer than the reference. duration_s: slide duration [s] (None: cross the whole
    textured area); periods: if given (and no duration), slide until the whole pad has been
    over the texture for this many feature spacings (enough for the period check). press_pitches_m: node pitches of the press's L0 and L1 rows;
    press_ref_pitch_m: the reference's.
    """

    scenes: tuple[str, ...] = tuple(SCENES)
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

    def __post_init__(self) -> None:
        if not self.scenes:
            raise ConfigError(f"scenes is empty; valid: one or more of {', '.join(SCENES)}")
        for s in self.scenes:
            v.one_of("scene", s, SCENES)
        if len(set(self.scenes)) != len(self.scenes):
            raise ConfigError(f"scenes = {list(self.scenes)} names a scene twice")
        for lv in self.levels:
            v.one_of("level", lv, LEVELS)
        v.one_of("force_control", self.force_control, FORCE_CONTROLS)

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


#: The full benchmark: every task's scene but the iCub part of textures20 (see
#: :data:`LEFT_OUT`), every level, steps from 1/2 to 4x auto and pitches from 3/4 to 1.5x
#: auto, whole crossings.
FULL = Sweep(scenes=tuple(k for k in SCENES if k != "textures20-icub"))

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
)

#: Why a sweep leaves a scene out (printed in its document, never silent).
LEFT_OUT = {
    "multilayer3": "left out of --quick: its L2 reference (0.4 mm nodes under 5 N) runs at "
    "about 1/40 of real time, minutes",
    "roughness8": "left out of --quick: no closed form to check; its 1 kHz L2 reference "
    "takes about 10 s",
    "textures20-icub": "left out by default: the iCub patch (32 x 22 mm, about 600 nodes at "
    "L1) runs at about half of real time at L1 and its L2 reference has four times the "
    "nodes, many minutes for its sweep; run it with --scenes textures20-icub",
}


def sweep_for(
    quick: bool,
    scenes: Sequence[str] | None = None,
    levels: Sequence[str] | None = None,
    duration_s: float | None = None,
) -> Sweep:
    """The full or quick sweep, restricted to ``scenes`` and ``levels`` if given."""
    base = QUICK if quick else FULL
    changes: dict = {}
    if scenes is not None:
        changes["scenes"] = tuple(scenes)
    if levels is not None:
        changes["levels"] = tuple(levels)
    if duration_s is not None:
        changes["duration_s"] = duration_s
    return replace(base, **changes)


# ---------------------------------------------------------------- closed form: pulse period
def probe_taxel(layout: Layout) -> int:
    """The shallowest taxel nearest the pad's centre (ties: the first)."""
    depth = layout.depth_m
    cand = np.flatnonzero(np.isclose(depth, depth.min()))
    r = np.hypot(layout.positions[cand, 0], layout.positions[cand, 1])
    return int(cand[np.argmin(r)])


def feature_spacing_m(plate: Plate) -> float | None:
    """Centre-to-centre spacing of the plate's features along the slide [m] (median), or
    None if it has fewer than two feature columns (flat, random roughness)."""
    xs = np.unique(np.round([f.x for f in features(plate)], 9))
    if xs.size < 2:
        return None
    return float(np.median(np.diff(xs)))


def pulse_period(
    rec: Recording,
    taxel: int,
    plate: Plate,
    spacing_m: float,
    speed_m_s: float,
    pad_length_m: float,
) -> dict:
    """Measure the period of ``taxel``'s signal while the whole pad is over the texture.

    The closed form holds in the steady state: while the pad (``pad_length_m`` along the
    slide) is entering or leaving the textured area its contact patch changes, and so does
    the signal's apparent period (by up to 4% here). The signal is detrended by
    ``(I - M)^2``, M a moving average over one nominal period ``spacing / speed`` (M removes
    the periodic part, so this keeps it and takes out trends up to quadratic); over the
    steady window a periodic model, a line plus ``K <= 3`` harmonics evaluated at the sample
    times (harmonics that the sensor's rate aliases are modelled as aliased), is fitted by
    least squares for each period in [0.8, 1.25] x nominal, and the best period refined.

    Returns ``{period_s, periods, ripple, pad_speed_m_s}``: ``periods`` is the steady
    window's length in periods, ``ripple`` the peak-to-peak of the fitted periodic part over
    the largest signal in the window (a weak ripple makes a weak check), ``pad_speed_m_s`` the
    pad's mean speed over the window. ``period_s`` is None, with a ``reason``, when the window
    holds fewer than 2 periods or the rate gives fewer than 3 samples per period.
    """
    from scipy import optimize

    rate = float(rec.meta["rate_hz"])
    t = np.asarray(rec.times, float)
    x_pad = np.asarray(rec.meta["x_pad_m"], float)
    y = np.asarray(rec.data[:, taxel], float)
    steady = np.abs(x_pad) <= plate.area_length_m / 2 - pad_length_m / 2
    out: dict = {"period_s": None, "periods": 0.0, "ripple": None, "pad_speed_m_s": None}
    if steady.sum() >= 2:
        out["pad_speed_m_s"] = float(np.polyfit(t[steady], x_pad[steady], 1)[0])
    nominal = spacing_m / speed_m_s
    per = nominal * rate  # samples per period
    if per < 3:
        out["reason"] = f"{rate:g} Hz gives {per:.1f} samples per period; at least 3 are needed"
        return out
    n_win = round(per)
    r = y - ndimage.uniform_filter1d(y, n_win, mode="nearest")
    r = r - ndimage.uniform_filter1d(r, n_win, mode="nearest")
    tt, rr = t[steady], r[steady]
    span = float(tt[-1] - tt[0]) if tt.size else 0.0
    out["periods"] = span / nominal
    if span < 2 * nominal:
        out["reason"] = (
            f"the whole pad is over the texture for {span / nominal:.1f} periods; 2 are needed"
        )
        return out
    tc = tt - tt.mean()
    n_harm = max(1, min(3, int(per // 2)))

    def design(period: float) -> np.ndarray:
        cols = [np.ones_like(tc), tc]
        for k in range(1, n_harm + 1):
            w = 2 * np.pi * k / period
            cols += [np.cos(w * tc), np.sin(w * tc)]
        return np.column_stack(cols)

    def sse(period: float) -> float:
        a = design(period)
        coef = np.linalg.lstsq(a, rr, rcond=1e-10)[0]
        return float(np.sum((rr - a @ coef) ** 2))

    grid = np.linspace(0.8 * nominal, 1.25 * nominal, 451)
    k = int(np.argmin([sse(p) for p in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    best = float(optimize.minimize_scalar(sse, bounds=(lo, hi), method="bounded").x)
    a = design(best)
    fit = a[:, 2:] @ np.linalg.lstsq(a, rr, rcond=1e-10)[0][2:]
    top = float(np.max(np.abs(y[steady])))
    out["period_s"] = best
    out["ripple"] = float(np.ptp(fit) / top) if top > 0 else None
    return out


def _quick_duration(
    plate: Plate, finger: Finger, speed: float, spacing: float | None, n_periods: int
) -> float | None:
    """Slide time [s] until the pad has spent ``n_periods`` feature spacings (and half one
    more) wholly over the texture; None when that is the whole crossing or no spacing."""
    if spacing is None:
        return None
    px = finger.patch_m[0]
    half = plate.area_length_m / 2
    x_start = -(half + px / 2 + START_MARGIN_M)
    steady_lo, steady_hi = -(half - px / 2), half - px / 2
    target = min(steady_lo + (n_periods + 0.5) * spacing, steady_hi + spacing / 2)
    t = (target - x_start) / speed + SPEED_RAMP_S
    full = 2 * abs(x_start) / speed
    return None if t >= full else float(t)


# ---------------------------------------------------------------- slide scenes
@dataclass
class _Config:
    level: str
    setting: str
    pitch_m: float | None = None
    dt_s: float | None = None
    expect_pitch_m: float = 0.0
    expect_dt_s: float = 0.0
    same_as: list[str] = field(default_factory=list)
    aspect: float = 1.0  # node pitch across the slide / along it

    @property
    def expect_pitch_y_m(self) -> float | None:
        return None if self.aspect == 1.0 else self.expect_pitch_m * self.aspect


def _configs(plate, layout, finger, proto, sweep: Sweep) -> list[_Config]:
    sample = 1.0 / proto.rate_hz

    def actual(dt: float) -> float:
        return sample / max(1, math.ceil(sample / dt - 1e-9))

    out: list[_Config] = []
    fid2 = choose_fidelity(plate, layout, finger, proto, "L2")
    out.append(_Config("L2", "reference", None, None, fid2.pitch_m, fid2.dt_s))
    plan = []
    for level in ("L0", "L1"):
        if level in sweep.levels:
            plan.append((level, sweep.dt_factors, sweep.pitch_factors))
    if "L2" in sweep.levels:
        plan.append(("L2", sweep.l2_dt_factors, sweep.l2_pitch_factors))
    out[0].aspect = (fid2.pitch_y_m or fid2.pitch_m) / fid2.pitch_m
    for level, dtf, pf in plan:
        fid = fid2 if level == "L2" else choose_fidelity(plate, layout, finger, proto, level)
        n0 = len(out)
        for f in dtf:
            if f == 1.0:
                out.append(_Config(level, "auto", None, None, fid.pitch_m, fid.dt_s))
            else:
                dt = fid.dt_s * f
                out.append(_Config(level, f"dt x{f:g}", None, dt, fid.pitch_m, actual(dt)))
        for g in pf:
            if g != 1.0:
                p = fid.pitch_m * g
                out.append(_Config(level, f"pitch x{g:g}", p, None, p, fid.dt_s))
        for c in out[n0:]:
            c.aspect = (fid.pitch_y_m or fid.pitch_m) / fid.pitch_m
    # different factors can round to the same step (a whole number of steps per sample, at
    # most one sample period): run each setting once, named "auto" if auto is among them
    groups: dict[tuple, list[_Config]] = {}
    for c in out:
        key = (c.level, round(c.expect_pitch_m, 12), round(c.expect_dt_s, 12))
        groups.setdefault(key, []).append(c)
    unique = []
    for same in groups.values():
        keep = next((c for c in same if c.setting in ("auto", "reference")), same[0])
        keep.same_as = [c.setting for c in same if c is not keep]
        unique.append(keep)
    return unique


def _err(a: np.ndarray, ref: np.ndarray) -> float:
    n = min(len(a), len(ref))
    a, ref = np.asarray(a[:n], float), np.asarray(ref[:n], float)
    den = float(np.linalg.norm(ref))
    return float(np.linalg.norm(a - ref) / den) if den > 0 else float("nan")


def _failure_row(base: dict, exc: BaseException) -> dict:
    crash = not isinstance(exc, SimTactileError)
    msg = f"{type(exc).__name__}: {exc}"
    if crash:
        tb = traceback.extract_tb(exc.__traceback__)
        if tb:
            msg += f" (at {Path(tb[-1].filename).name}:{tb[-1].lineno})"
    return {
        **base,
        "outcome": "crash" if crash else "error",
        "error": msg,
        "rtf": None,
        "cost_s_per_s": None,
        "error_vs_reference": None,
        "error_vs_analytic": None,
    }


def _slide_rows(scene: SlideScene, sweep: Sweep, cache, log) -> list[dict]:
    from ..sensors import get_sensor

    plate = get_plate(scene.plate)
    sensor = get_sensor(scene.sensor)
    layout, finger = sensor.layout, sensor.finger
    taxel = probe_taxel(layout)
    spacing = feature_spacing_m(plate)
    duration = sweep.duration_s
    if duration is None and sweep.periods:
        duration = _quick_duration(plate, finger, scene.speed_m_s, spacing, sweep.periods)
    proto = Protocol(
        speed_m_s=scene.speed_m_s,
        force_n=scene.force_n,
        duration_s=duration,
        rate_hz=layout.rate_hz,
        force_control=sweep.force_control,
    )
    ref_rec: Recording | None = None
    ref_error = None
    rows = []
    for cfg in _configs(plate, layout, finger, proto, sweep):
        base = {
            "scene": scene.name,
            "scene_key": scene.key,
            "task": scene.task,
            "fidelity": cfg.level,
            "force_control": sweep.force_control,
            "setting": cfg.setting,
            "dt_s": cfg.expect_dt_s,
            "pitch_m": cfg.expect_pitch_m,
            "pitch_y_m": cfg.expect_pitch_y_m,
            "n_nodes": skin_grid(finger, cfg.expect_pitch_m, cfg.expect_pitch_y_m).n,
            "duration_s": duration,
        }
        if cfg.same_as:
            base["same_as"] = cfg.same_as
        log(
            f"speed-error: {scene.key} {cfg.level} {cfg.setting} (node pitch "
            f"{cfg.expect_pitch_m * 1e3:.3g} mm, dt {cfg.expect_dt_s * 1e3:.3g} ms)"
        )
        t0 = time.perf_counter()
        try:
            res = simulate(
                plate,
                scene.sensor,
                protocol=proto,
                finger=finger,
                fidelity=cfg.level,
                pitch_m=cfg.pitch_m,
                dt_s=cfg.dt_s,
                ideal=True,
                cache=cache,
            )
        except Exception as exc:  # a failing configuration is a row, never a skipped one
            row = _failure_row(base, exc)
            row["wall_s"] = time.perf_counter() - t0
            if cfg.setting == "reference":
                ref_error = row["error"]
            log(f"  -> {row['outcome']}: {row['error']}")
            rows.append(row)
            continue
        rec = res.recording
        if cfg.setting == "reference":
            ref_rec = rec
        rtf = rec.meta["sim_s"] / rec.meta["slide_wall_s"]
        row = {
            **base,
            "dt_s": res.fidelity.dt_s,
            "pitch_m": res.fidelity.pitch_m,
            "pitch_y_m": res.fidelity.pitch_y_m,
            "n_nodes": skin_grid(finger, res.fidelity.pitch_m, res.fidelity.pitch_y_m).n,
            "outcome": "ok",
            "rtf": rtf,
            "cost_s_per_s": 1.0 / rtf,
            "sim_s": rec.meta["sim_s"],
            "slide_wall_s": rec.meta["slide_wall_s"],
            "wall_s": time.perf_counter() - t0,
            "error_vs_reference": None
            if ref_rec is None
            else (0.0 if rec is ref_rec else _err(rec.data, ref_rec.data)),
            "error_vs_analytic": None,
            "analytic": _analytic(rec, taxel, plate, spacing, scene.speed_m_s, finger),
            "warnings": list(res.warnings),
        }
        if ref_rec is None:
            row["note"] = f"no error against the reference: the L2 reference failed ({ref_error})"
        row["error_vs_analytic"] = row["analytic"].get("error")
        log(
            f"  -> RTF {rtf:.3g}, error vs L2 {_pct(row['error_vs_reference'])}, "
            f"vs closed form {_pct(row['error_vs_analytic'])}"
        )
        rows.append(row)
    return rows


def _analytic(
    rec: Recording, taxel: int, plate: Plate, spacing, speed: float, finger: Finger
) -> dict:
    if spacing is None:
        return {"what": "no closed form for this texture", "error": None}
    m = pulse_period(rec, taxel, plate, spacing, speed, finger.patch_m[0])
    out = {
        "what": "period of the probe taxel, whole pad on the texture, vs spacing / pad speed",
        "probe_taxel": taxel,
        "spacing_m": spacing,
        "period_s": m["period_s"],
        "periods": m["periods"],
        "ripple": m["ripple"],
        "pad_speed_m_s": m["pad_speed_m_s"],
        "speed_error": None if m["pad_speed_m_s"] is None else m["pad_speed_m_s"] / speed - 1.0,
        "error": None,
    }
    if m["period_s"] is not None and m["pad_speed_m_s"]:
        closed = spacing / m["pad_speed_m_s"]
        out["closed_form_s"] = closed
        out["error"] = abs(m["period_s"] / closed - 1.0)
    else:
        out["reason"] = m.get("reason", "the pad did not move over the texture")
    return out


# ---------------------------------------------------------------- the Hertz press
def _press_rows(scene: PressScene, sweep: Sweep, cache, log) -> list[dict]:
    finger = scene.finger()
    closed = hertz(scene.radius_m, finger.e_star_pa, scene.force_n)
    configs = [("L2", "reference", sweep.press_ref_pitch_m, True)]
    for level, coupled in (("L0", False), ("L1", True)):
        if level in sweep.levels:
            configs += [
                (level, f"node pitch {p * 1e3:g} mm", p, coupled) for p in sweep.press_pitches_m
            ]
    ref = None
    rows = []
    for level, setting, pitch, coupled in configs:
        base = {
            "scene": scene.name,
            "scene_key": scene.key,
            "task": scene.task,
            "fidelity": level,
            "setting": setting,
            "dt_s": None,
            "pitch_m": pitch,
            "n_nodes": skin_grid(finger, pitch).n,
            "static": True,
        }
        log(f"speed-error: {scene.key} {level} {setting}")
        t0 = time.perf_counter()
        try:
            r = press(
                finger,
                scene.force_n,
                readout_pitch_m=scene.readout_pitch_m,
                node_pitch_m=pitch,
                fidelity="L1" if coupled else "L0",
                cache=cache,
            )
        except Exception as exc:
            row = _failure_row(base, exc)
            row["wall_s"] = time.perf_counter() - t0
            log(f"  -> {row['outcome']}: {row['error']}")
            rows.append(row)
            continue
        wall = time.perf_counter() - t0
        if setting == "reference":
            ref = r
        a_err = r.contact_radius_m / closed["contact_radius_m"] - 1.0
        p_err = r.peak_pressure_pa / closed["peak_pressure_pa"] - 1.0
        row = {
            **base,
            "outcome": "ok",
            "rtf": None,
            "cost_s_per_s": None,
            "wall_s": wall,
            "cost_s": wall,
            "error_vs_reference": None
            if ref is None
            else (0.0 if r is ref else _err(r.pressure_pa, ref.pressure_pa)),
            "error_vs_analytic": max(abs(a_err), abs(p_err)),
            "analytic": {
                "what": "Hertz contact radius and peak pressure",
                "contact_radius_m": r.contact_radius_m,
                "hertz_contact_radius_m": closed["contact_radius_m"],
                "radius_error": a_err,
                "peak_pressure_pa": r.peak_pressure_pa,
                "hertz_peak_pressure_pa": closed["peak_pressure_pa"],
                "peak_error": p_err,
                "force_error_n": r.total_force_n - scene.force_n,
            },
        }
        log(
            f"  -> {wall:.2f} s, a {a_err:+.1%}, p0 {p_err:+.1%}, "
            f"error vs reference {_pct(row['error_vs_reference'])}"
        )
        rows.append(row)
    return rows


# ---------------------------------------------------------------- the run
def run_speed_error(
    sweep: Sweep = FULL,
    out: str | Path | None = None,
    *,
    cache=None,
    log: Callable[[str], None] = _nolog,
) -> dict:
    """Run ``sweep``; with ``out``, write ``speed_error.json``, ``speed_error.md`` and the
    Pareto figure ``speed_error.png`` there. Returns the document ``{rows, figures, ...}``."""
    t0 = time.perf_counter()
    load0 = _loadavg()
    rows: list[dict] = []
    for key in sweep.scenes:
        scene = SCENES[key]
        if isinstance(scene, PressScene):
            rows += _press_rows(scene, sweep, cache, log)
        else:
            rows += _slide_rows(scene, sweep, cache, log)
    left_out = [
        {"scene": k, "reason": LEFT_OUT.get(k, "not asked for")}
        for k in SCENES
        if k not in sweep.scenes
    ]
    doc = {
        "rows": rows,
        "figures": [],
        "quick": sweep.quick,
        "scenes": list(sweep.scenes),
        "left_out": left_out,
        "sweep": asdict(sweep),
        "machine": {"cpus": os.cpu_count(), "loadavg_start": load0, "loadavg_end": _loadavg()},
        "wall_s": time.perf_counter() - t0,
        "crashes": sum(r["outcome"] == "crash" for r in rows),
    }
    if out is not None:
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        png = plot_pareto(rows, out / "speed_error.png")
        doc["figures"] = [str(png)]
        md = out / "speed_error.md"
        md.write_text(markdown(doc))
        doc["table"] = str(md)
        (out / "speed_error.json").write_text(json.dumps(doc, indent=2) + "\n")
    return doc


def _loadavg() -> list[float] | None:
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:  # pragma: no cover - not on every platform
        return None


# ---------------------------------------------------------------- table and figure
def _pct(x: float | None) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x:.2%}"


def _num(x: float | None, scale: float = 1.0, fmt: str = ".3g") -> str:
    return "-" if x is None else format(x * scale, fmt)


def table_rows(rows: list[dict]) -> list[list[str]]:
    """The table's cells, one list per row (header first)."""
    head = [
        "scene",
        "level",
        "setting",
        "dt [ms]",
        "node pitch [mm]",
        "nodes",
        "RTF",
        "cost [s/s]",
        "error vs L2",
        "error vs closed form",
        "note",
    ]
    out = [head]
    for r in rows:
        note = r.get("error") or r.get("note") or ""
        a = r.get("analytic") or {}
        if not note and r["outcome"] == "ok":
            if r.get("static"):
                note = (
                    f"solve {r['wall_s']:.2f} s; a {a['radius_error']:+.1%}, "
                    f"p0 {a['peak_error']:+.1%}"
                )
            elif a.get("period_s") is not None:
                note = (
                    f"period {a['period_s'] * 1e3:.2f} ms vs {a['closed_form_s'] * 1e3:.2f} ms "
                    f"over {a['periods']:.1f} periods, ripple {a['ripple']:.1%}; pad speed "
                    f"{a['speed_error']:+.1%} off command"
                )
            elif a.get("reason"):
                note = a["reason"]
            elif a.get("what"):
                note = a["what"]
        if r.get("same_as"):
            note = f"also {', '.join(r['same_as'])} (same step, whole steps per sample); " + note
        out.append(
            [
                r["scene"],
                r["fidelity"],
                r["setting"],
                _num(r.get("dt_s"), 1e3),
                _num(r.get("pitch_m"), 1e3),
                str(r.get("n_nodes", "-")),
                _num(r.get("rtf")),
                _num(r.get("cost_s_per_s")),
                _pct(r.get("error_vs_reference")),
                _pct(r.get("error_vs_analytic")),
                note.replace("|", "/"),
            ]
        )
    return out


def markdown(doc: dict) -> str:
    cells = table_rows(doc["rows"])
    lines = [
        "# Speed against error (`sim-tactile bench speed-error`)",
        "",
        f"{'quick' if doc['quick'] else 'full'} run, {doc['wall_s']:.0f} s on "
        f"{doc['machine']['cpus']} cores (load average at start "
        f"{doc['machine']['loadavg_start']}, at end {doc['machine']['loadavg_end']}).",
        "",
        "RTF: simulated slide seconds per wall second of the slide loop, one core; cost = 1/RTF "
        "(the press is static: its cost is the wall time of the solve, in the note). Error vs "
        "L2: relative L2 norm of the ideal (time x taxel) recording against the L2 reference "
        "(press: of the dense grid's pressure against the finest node pitch). Error vs closed "
        "form: period of the probe taxel's signal while the whole pad is over the texture, "
        "against feature spacing / pad speed; Hertz: the larger of the contact-radius and "
        "peak-pressure errors. The reference (error 0) is drawn at the figure's left edge.",
        "",
        "| " + " | ".join(cells[0]) + " |",
        "|" + "---|" * len(cells[0]),
    ]
    lines += ["| " + " | ".join(c) + " |" for c in cells[1:]]
    if doc.get("left_out"):
        lines += ["", "Not run:"]
        lines += [f"- {x['scene']}: {x['reason']}" for x in doc["left_out"]]
    return "\n".join(lines) + "\n"


def pareto_front(errors: Sequence[float], costs: Sequence[float]) -> list[int]:
    """Indices of the configurations no other beats on both error and cost (both lower is
    better), in order of rising cost."""
    order = sorted(range(len(costs)), key=lambda i: (costs[i], errors[i]))
    front, best = [], math.inf
    for i in order:
        if errors[i] < best:
            front.append(i)
            best = errors[i]
    return front


_MARKERS = {"L0": "o", "L1": "s", "L2": "*"}
_COLOURS = {"L0": "tab:orange", "L1": "tab:blue", "L2": "tab:green"}


def plot_pareto(rows: list[dict], path: str | Path) -> Path:
    """One panel per scene: cost against error vs the reference, log axes, one marker series
    per level, the Pareto front drawn through its points; the reference (error 0) is drawn
    at the left edge."""
    from matplotlib.figure import Figure

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    ncols = 2 if len(scenes) > 1 else 1
    nrows = max(1, math.ceil(len(scenes) / ncols))
    fig = Figure(figsize=(6.2 * ncols, 4.6 * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax in axes[len(scenes) :]:
        ax.set_visible(False)
    for ax, scene in zip(axes, scenes, strict=False):
        srows = [r for r in rows if r["scene"] == scene]
        ok = [
            r
            for r in srows
            if r["outcome"] == "ok"
            and r.get("error_vs_reference") is not None
            and math.isfinite(r["error_vs_reference"])
        ]
        static = any(r.get("static") for r in srows)
        cost = [r["cost_s"] if static else r["cost_s_per_s"] for r in ok]
        err = [r["error_vs_reference"] for r in ok]
        pos = [e for e in err if e > 0]
        floor = min(pos) / 3 if pos else 1e-3
        xs = [e if e > 0 else floor for e in err]
        for level in LEVELS:
            idx = [i for i, r in enumerate(ok) if r["fidelity"] == level]
            if idx:
                ax.scatter(
                    [xs[i] for i in idx],
                    [cost[i] for i in idx],
                    marker=_MARKERS[level],
                    s=110 if level == "L2" else 45,
                    color=_COLOURS[level],
                    label=level,
                    zorder=3,
                )
        for i, r in enumerate(ok):
            label = "reference (error 0)" if err[i] == 0 else r["setting"]
            ax.annotate(
                label,
                (xs[i], cost[i]),
                textcoords="offset points",
                xytext=(5, 4) if i % 2 == 0 else (5, -10),  # alternate: fewer overlaps
                fontsize=7,
                color="0.3",
            )
        front = pareto_front(err, cost)
        if front:
            front.sort(key=lambda i: xs[i])  # the attainment staircase, left to right
            fx = [xs[i] for i in front]
            fy = [cost[i] for i in front]
            ax.step(
                fx, fy, where="post", color="k", lw=1.0, ls="--", zorder=2, label="Pareto front"
            )
            ax.scatter(fx, fy, s=190, facecolors="none", edgecolors="k", lw=1.2, zorder=4)
        failed = [r for r in srows if r["outcome"] != "ok"]
        if failed:
            ax.text(  # lower left: nothing lies beyond the front there
                0.02,
                0.02,
                "stopped with an error (see table):\n"
                + "\n".join(f"{r['fidelity']} {r['setting']}" for r in failed),
                transform=ax.transAxes,
                ha="left",
                va="bottom",
                fontsize=7,
                color="tab:red",
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("error vs L2 reference (relative L2 norm)")
        ax.set_ylabel(
            "wall time of the static solve [s]"
            if static
            else "cost: wall s per simulated s (1/RTF)"
        )
        ax.set_title(scene, fontsize=9)
        ax.grid(True, which="both", alpha=0.25)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle("sim-tactile: speed against error of the fidelity levels (lower left is better)")
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path


__all__ = [
    "FULL",
    "QUICK",
    "SCENES",
    "PressScene",
    "SlideScene",
    "Sweep",
    "feature_spacing_m",
    "markdown",
    "pareto_front",
    "plot_pareto",
    "probe_taxel",
    "pulse_period",
    "run_speed_error",
    "sweep_for",
]
