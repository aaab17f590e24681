"""Speed against error of the soft-finger levels, the Hertz check, and the loop's overhead.

    python benchmarks/bench_finger.py [--json] [--quick]

Scene: finger7/ridges-4, grid3x3, 60 mm/s, 1 N (the soft-finger paper's setup). Every level
runs at its auto time step and at 2x and 0.5x of it; the reference is L2 (half the node
pitch, a quarter of the time step). Errors:

- error_vs_reference: ||d - d_L2|| / ||d_L2|| over the whole (time x taxel) recording;
- error_vs_analytic: the pulse period of the middle taxel against ridge pitch / speed.

RTF is simulated seconds of the slide per wall second of the slide loop (one core). The loop
overhead compares the full step against bare MuJoCo calls on the same models (mj_step on the
finger, mj_kinematics + mj_collision on the skin), with and without the skin's contact solve.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

import mujoco
import numpy as np
from scipy import ndimage
from threadpoolctl import threadpool_limits

from sim_tactile.scene.finger import Finger
from sim_tactile.sim.press import hertz, press
from sim_tactile.sim.simulate import Protocol, simulate

V = 0.06
PLATE = "finger7/ridges-4"


def _period(rec) -> float:
    i = 4  # middle taxel of grid3x3
    t, y = rec.times, rec.data[:, i].astype(float)
    x = rec.meta["x_start_m"] + V * t
    over = np.abs(x) < 15.75e-3
    lab, n = ndimage.label(y[over] > 1e-3 * y.max())
    c = [
        np.sum(t[over][lab == k] * y[over][lab == k]) / np.sum(y[over][lab == k])
        for k in range(1, n + 1)
    ]
    return float(np.median(np.diff(c))) if len(c) > 1 else float("nan")


def run_levels(quick: bool) -> list[dict]:
    ref = simulate(
        PLATE, "grid3x3", protocol=Protocol(speed_m_s=V), fidelity="L2", ideal=True
    ).recording
    rows = []
    factors = (1.0,) if quick else (2.0, 1.0, 0.5)
    for level in ("L0", "L1"):
        for f in factors:
            base = simulate(
                PLATE,
                "grid3x3",
                protocol=Protocol(speed_m_s=V, duration_s=0.05),
                fidelity=level,
                ideal=True,
            )
            dt = base.fidelity.dt_s * f
            try:
                r = simulate(
                    PLATE,
                    "grid3x3",
                    protocol=Protocol(speed_m_s=V),
                    fidelity=level,
                    dt_s=dt,
                    ideal=True,
                )
            except Exception as exc:  # a too coarse step is a result too
                rows.append(
                    {"scene": PLATE, "fidelity": level, "dt_s": dt, "outcome": f"error: {exc}"}
                )
                continue
            rec = r.recording
            n = min(len(rec.data), len(ref.data))
            err = float(np.linalg.norm(rec.data[:n] - ref.data[:n]) / np.linalg.norm(ref.data[:n]))
            rows.append(
                {
                    "scene": PLATE,
                    "fidelity": level,
                    "dt_s": r.fidelity.dt_s,
                    "node_pitch_m": r.fidelity.pitch_m,
                    "rtf": rec.meta["sim_s"] / rec.meta["slide_wall_s"],
                    "error_vs_reference": err,
                    "error_vs_analytic": abs(_period(rec) / (9e-3 / V) - 1),
                    "outcome": "ok",
                }
            )
    rows.append(
        {
            "scene": PLATE,
            "fidelity": "L2",
            "dt_s": ref.meta["dt_s"],
            "node_pitch_m": ref.meta["fidelity"]["pitch_m"],
            "rtf": ref.meta["sim_s"] / ref.meta["slide_wall_s"],
            "error_vs_reference": 0.0,
            "error_vs_analytic": abs(_period(ref) / (9e-3 / V) - 1),
            "outcome": "ok",
        }
    )
    return rows


def hertz_rows() -> list[dict]:
    f = Finger(
        shape="sphere",
        radius_m=8e-3,
        size_m=(12e-3, 12e-3),
        young_pa=0.3e6,
        poisson=0.5,
        thickness_m=5e-3,
    )
    ref = hertz(8e-3, f.e_star_pa, 1.0)
    out = []
    for level, coupled in (("L0", False), ("L1", True)):
        r = press(f, 1.0, pitch_m=0.25e-3, coupled=coupled)
        out.append(
            {
                "fidelity": level,
                "contact_radius_mm": r.contact_radius_m * 1e3,
                "radius_error": r.contact_radius_m / ref["contact_radius_m"] - 1,
                "peak_kpa": r.peak_pressure_pa / 1e3,
                "peak_error": r.peak_pressure_pa / ref["peak_pressure_pa"] - 1,
                "force_error": r.total_force_n - 1.0,
            }
        )
    return out


def loop_overhead(repeats: int = 5) -> dict:
    """Median seconds per step: full project step vs bare MuJoCo calls (+ the skin solve)."""
    from sim_tactile.sim import simulate as S

    captured = {}
    orig = S._Runner.__init__

    def spy(self, *a, **k):
        orig(self, *a, **k)
        captured["runner"] = self

    S._Runner.__init__ = spy
    try:
        simulate(PLATE, "grid3x3", protocol=Protocol(speed_m_s=V, duration_s=0.3), ideal=True)
    finally:
        S._Runner.__init__ = orig
    run = captured["runner"]
    s = run.s
    n = 200
    full, bare, bare_solve = [], [], []
    q0, v0 = run.d_dyn.qpos.copy(), run.d_dyn.qvel.copy()

    def reset() -> None:  # every timed loop starts from the same settled, sliding state
        run.d_dyn.qpos[:], run.d_dyn.qvel[:] = q0, v0
        run.d_dyn.qfrc_applied[:] = 0.0

    with threadpool_limits(limits=1, user_api="blas"):
        for _ in range(repeats):
            reset()
            t = time.perf_counter()
            acc = np.zeros(s.layout.n)
            for _ in range(n):
                run.step(force_cmd=1.0, slide_v=V, taxel_acc=acc)
            full.append((time.perf_counter() - t) / n)
            reset()
            t = time.perf_counter()
            for _ in range(n):
                mujoco.mj_kinematics(s.m_col, run.d_col)
                mujoco.mj_collision(s.m_col, run.d_col)
                mujoco.mj_step(s.m_dyn, run.d_dyn)
            bare.append((time.perf_counter() - t) / n)
            pen = run.pen.copy()
            reset()
            t = time.perf_counter()
            for _ in range(n):
                mujoco.mj_kinematics(s.m_col, run.d_col)
                mujoco.mj_collision(s.m_col, run.d_col)
                S._skin_pressure(s, run.fid, pen, run.active)
                mujoco.mj_step(s.m_dyn, run.d_dyn)
            bare_solve.append((time.perf_counter() - t) / n)
    f, b, bs = statistics.median(full), statistics.median(bare), statistics.median(bare_solve)
    return {
        "step_full_us": f * 1e6,
        "step_bare_mujoco_us": b * 1e6,
        "step_bare_plus_skin_us": bs * 1e6,
        "overhead_vs_bare_mujoco": f / b - 1,
        "overhead_vs_bare_plus_skin": f / bs - 1,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    with threadpool_limits(limits=1, user_api="blas"):
        doc = {"rows": run_levels(args.quick), "hertz": hertz_rows(), "loop": loop_overhead()}
    if args.json:
        print(json.dumps(doc, indent=2))
        return 0
    print(
        f"{'level':6s} {'dt [ms]':>8s} {'pitch [mm]':>10s} {'RTF':>7s} {'err vs L2':>10s} {'period err':>10s}"
    )
    for r in doc["rows"]:
        if r["outcome"] != "ok":
            print(f"{r['fidelity']:6s} {r['dt_s'] * 1e3:8.3f}  {r['outcome']}")
            continue
        print(
            f"{r['fidelity']:6s} {r['dt_s'] * 1e3:8.3f} {r['node_pitch_m'] * 1e3:10.3f} {r['rtf']:7.2f} "
            f"{r['error_vs_reference']:10.3%} {r['error_vs_analytic']:10.3%}"
        )
    for h in doc["hertz"]:
        print(
            f"Hertz {h['fidelity']}: a = {h['contact_radius_mm']:.3f} mm ({h['radius_error']:+.1%}), "
            f"p0 = {h['peak_kpa']:.1f} kPa ({h['peak_error']:+.1%}), force error {h['force_error']:+.1e} N"
        )
    lp = doc["loop"]
    print(
        f"step: full {lp['step_full_us']:.0f} us, bare MuJoCo {lp['step_bare_mujoco_us']:.0f} us, bare + skin solve "
        f"{lp['step_bare_plus_skin_us']:.0f} us; overhead {lp['overhead_vs_bare_mujoco']:.0%} vs bare MuJoCo, "
        f"{lp['overhead_vs_bare_plus_skin']:.0%} vs MuJoCo + skin solve"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
