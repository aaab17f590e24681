"""Speed against error of the soft-finger levels, the Hertz check, and the loop's overhead.

    python perf/bench_finger.py [--json] [--quick]

Scene: finger7/ridges-4, grid3x3, 60 mm/s, 1 N (the soft-finger paper's setup). L0 and L1 run
at their auto time step and at 2x and 0.5x of it; the reference is L2 (half the node pitch, a
quarter of the time step). The sweep, the errors and the Hertz rows come from
:mod:`sim_tactile.bench.speed_error` (``sim-tactile bench speed-error`` runs the same code on
every task's scene):

- error_vs_reference: ||d - d_L2|| / ||d_L2|| over the whole (time x taxel) recording;
- error_vs_analytic: the period of the middle taxel's pulses against ridge pitch / pad speed.

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
from threadpoolctl import threadpool_limits

from sim_tactile.bench.speed_error import run_speed_error
from sim_tactile.bench.sweep import Sweep
from sim_tactile.plates import get_plate
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.plan.slide import Slide
from sim_tactile.sim.slide import prepare

V = 0.06
PLATE = "finger7/ridges-4"


def run_levels(quick: bool) -> list[dict]:
    """Rows of L0 and L1 (auto step, and 2x and 0.5x of it unless quick) and the L2 reference
    under the default quasi-static force control; then L1 (auto, 2x, 0.5x) and its own L2
    reference under the dynamic force loop."""
    qs = Sweep(
        scenes=("finger7",),
        levels=("L0", "L1"),
        dt_factors=(1.0,) if quick else (2.0, 1.0, 0.5),
        pitch_factors=(1.0,),
        force_control="quasi-static",
    )
    dyn = Sweep(
        scenes=("finger7",),
        levels=("L1",),
        dt_factors=(1.0,) if quick else (2.0, 1.0, 0.5),
        pitch_factors=(1.0,),
        force_control="dynamic",
    )
    return run_speed_error(qs)["rows"] + run_speed_error(dyn)["rows"]


def hertz_rows(quick: bool = False) -> list[dict]:
    """The Hertz press (sphere R 8 mm, E 0.3 MPa, 1 N) at 0.2 mm node pitch, L0 and L1."""
    sweep = Sweep(
        scenes=("hertz",),
        levels=("L0", "L1"),
        press_pitches_m=(0.2e-3,),
        press_ref_pitch_m=0.15e-3 if quick else 0.1e-3,
    )
    out = []
    for r in run_speed_error(sweep)["rows"]:
        if r["fidelity"] == "L2" or r["outcome"] != "ok":
            continue
        a = r["analytic"]
        out.append(
            {
                "fidelity": r["fidelity"],
                "contact_radius_mm": a["contact_radius_m"] * 1e3,
                "radius_error": a["radius_error"],
                "peak_kpa": a["peak_pressure_pa"] / 1e3,
                "peak_error": a["peak_error"],
                "force_error": a["force_error_n"],
                "error_vs_reference": r["error_vs_reference"],
            }
        )
    return out


def loop_overhead(repeats: int = 5) -> dict:
    """Median seconds per step of three loops over the same 200 sliding steps, from the state
    0.3 s into a slide (the pad on the ridges):

    - full: the project's step (readout, skin solve, checks, drag, taxel loads);
    - bare MuJoCo: MuJoCo stepping the same model: kinematics and collision of the skin nodes
      against the plate, and mj_step (no skin solve);
    - minimal: the least a user's own script must do for the same physics: the depth map (the
      compiled collider where the plate allows it, else MuJoCo's collider), the skin's
      force-holding contact solve, and mj_step. Where the step solves a reduced problem
      (:class:`sim_tactile.sim.step.held.CompiledHeldStep`: collider probes per column, the mirror
      half), the minimal loop calls the same reduced collider and solver, so both do the same
      work.

    The loop overhead is full / minimal - 1: what the project's loop adds to the physics.
    """
    import copy

    from sim_tactile.sim.step.held import CompiledHeldStep

    slide = Slide(get_plate(PLATE), "grid3x3", Protocol(speed_m_s=V, duration_s=0.3))
    pressed = prepare(slide)
    run = pressed.runner
    s = run.s
    n = 200
    into = np.zeros(s.layout.n)
    for _ in range(round(0.3 / run.dt)):  # 0.3 s into the slide: the pad on the ridges
        run.step(force_cmd=1.0, slide_v=V, taxel_out=into)
    full, bare, minimal = [], [], []
    dd = run.d_dyn
    dc = mujoco.MjData(s.m_col)
    q0, v0 = dd.qpos.copy(), dd.qvel.copy()
    held = run.hold if isinstance(run.hold, CompiledHeldStep) else None
    skin0 = copy.deepcopy(run.skin)
    held0 = copy.deepcopy(held.solver) if held is not None else None
    A = s.grid.area_m2

    def reset() -> None:  # every timed loop starts from the same settled, sliding state
        dd.qpos[:], dd.qvel[:] = q0, v0
        dd.qfrc_applied[:] = 0.0
        run.skin = copy.deepcopy(skin0)
        if run.hold is not None and held is None:
            run.hold.skin = run.skin
        if held is not None:
            held.solver = copy.deepcopy(held0)

    with threadpool_limits(limits=1, user_api="blas"):
        for _ in range(repeats):
            reset()
            t = time.perf_counter()
            acc = np.zeros(s.layout.n)
            for _ in range(n):
                run.step(force_cmd=1.0, slide_v=V, taxel_out=acc)
            full.append((time.perf_counter() - t) / n)
            reset()
            t = time.perf_counter()
            for _ in range(n):
                dc.qpos[:] = dd.qpos
                mujoco.mj_kinematics(s.m_col, dc)
                mujoco.mj_collision(s.m_col, dc)
                dd.ctrl[0] = V
                mujoco.mj_step(s.m_dyn, dd)
            bare.append((time.perf_counter() - t) / n)
            reset()
            pen = np.empty(s.n_nodes)
            t = time.perf_counter()
            if held is not None:  # the reduced problem the step solves
                bone = held.bone0.copy()
                for _ in range(n):
                    bone[0] = held.bone0[0] + dd.qpos[s.jx]
                    bone[2] = held.bone0[2] + dd.qpos[s.jz]
                    held.depths(bone)
                    p, dz = held.solver.solve_force(held.pen, 1.0 / A)
                    dd.qpos[s.jz] -= dz
                    dd.qvel[s.jz] = 0.0
                    dd.ctrl[0] = V
                    mujoco.mj_step(s.m_dyn, dd)
            else:
                for _ in range(n):
                    run.collider.depths_at(dd.qpos, pen)
                    if run.quasi_static:  # hold the force: the pad to where the skin carries it
                        p, dz = run.skin.solve_force(pen, 1.0 / A)
                        dd.qpos[s.jz] -= dz
                        dd.qvel[s.jz] = 0.0
                    else:
                        p = run.skin.solve(pen)
                        dd.qfrc_applied[s.jz] = p.sum() * A - 1.0
                    dd.ctrl[0] = V
                    mujoco.mj_step(s.m_dyn, dd)
            minimal.append((time.perf_counter() - t) / n)
    f, b, m = statistics.median(full), statistics.median(bare), statistics.median(minimal)
    return {
        "step_full_us": f * 1e6,
        "step_bare_mujoco_us": b * 1e6,
        "step_minimal_us": m * 1e6,
        "overhead_vs_bare_mujoco": f / b - 1,
        "overhead_vs_minimal": f / m - 1,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    with threadpool_limits(limits=1, user_api="blas"):
        doc = {
            "rows": run_levels(args.quick),
            "hertz": hertz_rows(args.quick),
            "loop": loop_overhead(),
        }
    if args.json:
        print(json.dumps(doc, indent=2))
        return 0
    print(
        f"{'force':12s} {'level':6s} {'dt [ms]':>8s} {'pitch [mm]':>10s} {'RTF':>7s} {'err vs L2':>10s} {'period err':>10s}"
    )
    for r in doc["rows"]:
        if r["outcome"] != "ok":
            print(
                f"{r['force_control']:12s} {r['fidelity']:6s} {r['dt_s'] * 1e3:8.3f}  {r['outcome']}: {r['error']}"
            )
            continue
        ana = r["error_vs_analytic"]
        print(
            f"{r['force_control']:12s} {r['fidelity']:6s} {r['dt_s'] * 1e3:8.3f} {r['pitch_m'] * 1e3:10.3f} {r['rtf']:7.2f} "
            f"{r['error_vs_reference']:10.3%} {'-' if ana is None else format(ana, '10.3%'):>10s}"
        )
    for h in doc["hertz"]:
        print(
            f"Hertz {h['fidelity']}: a = {h['contact_radius_mm']:.3f} mm ({h['radius_error']:+.1%}), "
            f"p0 = {h['peak_kpa']:.1f} kPa ({h['peak_error']:+.1%}), force error {h['force_error']:+.1e} N"
        )
    lp = doc["loop"]
    print(
        f"step: full {lp['step_full_us']:.0f} us, bare MuJoCo {lp['step_bare_mujoco_us']:.0f} us, minimal "
        f"(MuJoCo + readout + skin solve) {lp['step_minimal_us']:.0f} us; loop overhead "
        f"{lp['overhead_vs_minimal']:.0%} over the minimal loop ({lp['overhead_vs_bare_mujoco']:.0%} over bare MuJoCo)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
