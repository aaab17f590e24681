"""Speed against error of the soft finger's fidelity levels, on each task's scene.

For every scene (the setup of a task: plate, sensor with its pad, speed and force) the sweep
runs each fidelity level (:mod:`sim_tactile.sim.plan.fidelity`) at its auto setting and at
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
- ``error_vs_physics``: the configuration's skin (its level and node grid) in static presses
  at a few pad offsets, against an independent half-space solver (Tamaas, a test extra) of
  the same presses, both read by the sensor's taxels: the relative norm over offsets x
  taxels, and ``physics_max``, the largest taxel difference in units of the largest
  reference load (:mod:`~sim_tactile.bench.physics`). None without Tamaas (the row says why).

:func:`run_speed_error` writes the rows as JSON, a Markdown table and a Pareto figure (one
panel per scene: cost against error, log axes, a marker series per level, the front drawn).

A configuration that stops with a :class:`~sim_tactile.errors.SimTactileError` (a too coarse
time step, say) is a row with ``outcome = "error"`` and the message in ``error``, never a
skipped row. An unexpected exception is a row with ``outcome = "crash"``.
"""

from __future__ import annotations

import json
import os
import time
import traceback
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SimTactileError
from ..plates import Plate, get_plate, surface_of
from ..records import Recording
from ..scene.nodes import skin_grid
from ..sensors import Finger, get_sensor
from ..sim.plan.fidelity import choose_fidelity, steps_per_sample
from ..sim.plan.lattices import anchored_cells
from ..sim.plan.protocol import Protocol
from ..sim.slide import simulate
from ..sim.static_press import hertz, press
from . import physics
from .closed_forms import probe_taxel, pulse_period, quick_duration
from .pareto import markdown, pct, plot_pareto
from .scenes import PressScene, SlideScene, scenes
from .sweep import FULL, LEFT_OUT, Sweep


def _nolog(msg: str) -> None:
    pass


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
    def actual(dt: float) -> float:  # the step simulate() takes for a target step dt
        return 1.0 / (proto.rate_hz * steps_per_sample(proto.rate_hz, dt))

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
    if "L1" in sweep.levels:  # what a slide takes by default, where it is not L1's own grid
        fa = choose_fidelity(plate, layout, finger, proto, "auto")
        f1 = choose_fidelity(plate, layout, finger, proto, "L1")
        if (fa.pitch_m, fa.pitch_y_m, fa.clipped, fa.wall_m) != (
            f1.pitch_m,
            f1.pitch_y_m,
            f1.clipped,
            f1.wall_m,
        ):
            out.append(_Config("auto", "default", None, None, fa.pitch_m, fa.dt_s))
            out[-1].aspect = (fa.pitch_y_m or fa.pitch_m) / fa.pitch_m
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
        "error_vs_physics": None,
    }


def _slide_rows(scene: SlideScene, sweep: Sweep, cache, log) -> list[dict]:
    plate = get_plate(scene.plate)
    sensor = get_sensor(scene.sensor)
    layout, finger = sensor.layout, sensor.finger
    taxel = probe_taxel(layout)
    spacing = surface_of(plate).period_m  # the texture's one period
    duration = sweep.duration_s
    if duration is None and sweep.periods:
        duration = quick_duration(plate, finger, scene.speed_m_s, spacing, sweep.periods)
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
            **_grid_of(res.fidelity, rec, finger, layout, plate, proto),
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
            f"  -> RTF {rtf:.3g}, error vs L2 {pct(row['error_vs_reference'])}, "
            f"vs closed form {pct(row['error_vs_analytic'])}"
        )
        rows.append(row)
    if sweep.physics:
        _physics_errors(rows, plate, sensor, scene.force_n, sweep.physics_offsets, log)
    return rows


def _grid_of(fid, rec, finger, layout, plate, proto) -> dict:
    """The grid a slide ran on: step, pitches, clipped or anchored, and its node (or anchored
    cell) count."""
    if fid.wall_m is None:
        n = skin_grid(finger, fid.pitch_m, fid.pitch_y_m).n
    else:
        n = anchored_cells(
            finger, layout, plate, proto.offset_y_m, fid.pitch_m, fid.pitch_y_m, fid.wall_m
        )
    return {
        "dt_s": fid.dt_s,
        "pitch_m": fid.pitch_m,
        "pitch_y_m": fid.pitch_y_m,
        "clipped": fid.clipped,
        "wall_m": fid.wall_m,
        "grid": rec.meta["skin_problem"],
        "n_nodes": n,
    }


def _physics_errors(rows, plate, sensor, force_n: float, n_offsets: int, log) -> None:
    """Fill each ok row's error against physics (one static measure per level and grid)."""
    missing = physics.tamaas_missing()
    ok = [r for r in rows if r["outcome"] == "ok"]
    for r in ok:
        r["error_vs_physics"] = r["physics_max"] = None
    if missing:
        for r in ok:
            r["physics_note"] = missing
        return
    t0 = time.perf_counter()
    ref = physics.reference(plate, sensor, force_n, n_offsets)
    info = {
        "offsets_m": list(ref.offsets_m),
        "spacing_m": ref.spacing_m,
        "ref_change": ref.ref_change,
        "wall_s": time.perf_counter() - t0,
    }
    log(
        f"  physics: Tamaas at {ref.spacing_m * 1e3:g} mm, {len(ref.offsets_m)} offsets, "
        f"{info['wall_s']:.1f} s (a grid twice as coarse moves it {pct(ref.ref_change)})"
    )
    done: dict[tuple, tuple[float, float]] = {}
    for r in ok:
        clipped, wall = r.get("clipped", False), r.get("wall_m")
        level = "L1" if r["fidelity"] == "auto" else r["fidelity"]
        key = (level, r["pitch_m"], r["pitch_y_m"], clipped, wall)
        if key not in done:
            loads = physics.configuration_loads(
                ref, plate, sensor, force_n, level, r["pitch_m"], r["pitch_y_m"], clipped, wall
            )
            done[key] = ref.error(loads)
            log(
                f"  physics: {r['fidelity']} {r['pitch_m'] * 1e3:.3g} mm nodes: "
                f"{pct(done[key][0])} (largest taxel {pct(done[key][1])})"
            )
        r["error_vs_physics"], r["physics_max"] = done[key]
        r["physics"] = info


def _analytic(
    rec: Recording, taxel: int, plate: Plate, spacing, speed: float, finger: Finger
) -> dict:
    if spacing is None:
        return {"what": "no closed form for this texture", "error": None}
    m = pulse_period(rec, taxel, plate.area_length_m, spacing, speed, finger.patch_m[0])
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
            "error_vs_physics": None,
            "physics_note": "the press's physics is Hertz's closed form (error vs closed form)",
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
            f"error vs reference {pct(row['error_vs_reference'])}"
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
    every = scenes()
    for key in sweep.scenes:
        scene = every[key]
        if isinstance(scene, PressScene):
            rows += _press_rows(scene, sweep, cache, log)
        else:
            rows += _slide_rows(scene, sweep, cache, log)
    left_out = [
        {"scene": k, "reason": LEFT_OUT.get(k, "not asked for")}
        for k in every
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
