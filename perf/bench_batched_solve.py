"""The batched contact solve (torch, CPU or GPU) against the numpy solve, pose for pose, on
real poses of every task scene whose skin is solved spectrally.

    python perf/bench_batched_solve.py [--scenes icub-grating,icub-boxes,finger7-v2]
        [--poses 512] [--batches 1,8,64,512] [--tols 1e-10,1e-4] [--dtypes float64,float32]
        [--devices cpu,cuda] [--threads 1] [--min-poses 64] [--cold]
        [--save-poses DIR [--record-only] | --load-poses DIR] [--compile] [--json]

On a GPU machine without MuJoCo or CadQuery, record the poses where the package is whole
and carry them over::

    python perf/bench_batched_solve.py --save-poses poses --record-only    # here
    python perf/bench_batched_solve.py --load-poses poses --json           # there

**The poses.** For each scene, one slide of the task (its first slide on the plate named
in :data:`SCENES`) is prepared (scene, approach, press) by the package's own driver, then
slid at the protocol's speed until its spectral skin has been asked ``--poses`` contact
solves. Each is recorded: the node depths (n,), the pressures' total (NaN where the pad
is held at its height, under position control, as finger7-v2 slides: the plain solve), and
the solver's last pressures, the warm start it had (the slide's own; a problem equal to the
last one, which the numpy solve answers from memory, is skipped). A pose is then the
problem a driver stepping slides in lockstep hands to the batched solve: its depths, its
total and its warm start. ``--cold`` adds rows without warm starts (the phases
of a phase table solved afresh). ``--save-poses DIR`` writes them as ``DIR/<scene>.npz``
(with the skin's kernel table); ``--load-poses DIR`` reads them back, so that the benchmark
runs where only numpy, scipy, numba and torch are installed (a GPU machine without MuJoCo
or CadQuery).

**The solves.** Each pose is solved by the numpy solve
(:class:`~sim_tactile.sim.skin.contact.spectral.Spectral`, numba-compiled vector work,
scipy's pocketfft), one at a time from its warm start, and by
:class:`~sim_tactile.sim.skin.contact.batched.BatchedSpectral` in batches of B poses, for
each tolerance, dtype (``float32`` only at tolerances of at least ``FLOAT32_MIN_TOL``) and
device (``--devices``; by default ``cuda`` where torch sees a GPU, else ``cpu``: the numpy
solve is the CPU's column; one warm-up batch of each size first, so cuFFT's plans are
made). A batch size B solves ``max(B, --min-poses)`` poses (at most
``--poses``) in batches of B. torch runs on ``--threads`` CPU threads (1: per core, as the
numpy solve).

**What it prints**: the machine line (CPUs, GPU, torch, threads, commit), then one table
row per scene, start (``warm``: each pose from its slide's last pressures; ``cold``),
tolerance, device, dtype and B:

- ``numpy [us/pose]``, ``batched [us/pose]``: wall time per pose, and the ``speed-up`` of
  the batched solve (numpy over batched);
- ``numpy iterations``, ``iterations``: the mean iterations of a pose in each (the batched
  solve counts those of the start that converged, as the numpy solve does); ``steps``: the
  lockstep iterations of a batch (it runs to its slowest pose); ``products``: the batched
  solve's FFT products per pose (one an iteration, plus the deflections taken again every
  16 iterations and after a projection moved a node, plus one for the pad's shift);
- ``max rel L1``: the largest ``sum |p - p_numpy| / sum p_numpy`` over the poses, against
  the numpy solve at the same tolerance (a few times the tolerance: tested); ``numpy
  error`` and ``error``: the same against the numpy solve at the reference tolerance
  (1e-10), of the numpy solve and of the batched one at the row's tolerance (float32 holds
  a tolerance where its error is near the numpy solve's).

Expected, measured on 2 shared x86 cores (so only roughly): the numpy solve of the iCub's
265 x 23 grating takes some 50 iterations and tens of ms a pose at 1e-10 (20 iterations at
1e-4); the batched solve on one CPU thread is 2 to 5 times slower per pose (torch's
unfused passes against numba's fused loops; its FFTs cost about the same), float32 about
as fast as the numpy solve. On a GPU it is bound by kernel launches at small B and should
gain with B up to some hundreds of poses; an eager torch solve of this problem took 150 to
190 us a pose at B = 512 on an H200 (issue 47), against some 5 ms for one CPU core.
``--compile`` runs the vector work through ``torch.compile`` (a first call compiles for a
minute or two; on a GPU it should cut the element-wise kernels several-fold). ``--json``
prints one JSON document with every row instead.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

#: Scene name -> (task, plate, what it stands for): the task scenes whose skin the planner
#: solves spectrally (the iCub's plates on the 265 x 23 and 93 x 67 lattices, and
#: finger7-v2's curved pad, whose nodes in reach fill a block of its 89 x 65 lattice).
SCENES = {
    "icub-grating": ("textures20-icub60-v2", "textures20-long/grating-1.5mm"),
    "icub-boxes": ("textures20-icub60-v2", "textures20-long/boxes-4.5mm"),
    "icub-hemispheres": ("textures20-icub60-v2", "textures20-long/hemispheres-3.0mm"),
    "finger7-v2": ("finger7-v2", "finger7/bumps-3x3"),
}


def record_poses(scene: str, n: int) -> dict:
    """``n`` real contact problems of ``scene`` (see the module docstring): ``pen`` (n, N),
    ``total`` (n,) (NaN where the pad is held at its height: position control, the plain
    solve), ``warm`` (n, N), the skin's ``table`` and ``tol``."""
    from sim_tactile.sim import prepare
    from sim_tactile.sim.skin.models import SpectralSkin
    from sim_tactile.tasks import get_task

    task, plate = SCENES[scene]
    job = next(j for j in get_task(task).get_data.jobs(seed=0) if j.plate.name == plate)
    pressed = prepare(
        job.plate,
        job.sensor,
        protocol=job.protocol,
        finger=job.finger,
        fidelity=job.fidelity,
        seed=job.seed,
        pitch_m=job.pitch_m,
    )
    runner = pressed.runner
    skin = runner.skin
    if not isinstance(skin, SpectralSkin):
        raise SystemExit(f"{scene}: its skin is not solved spectrally ({skin.describe()})")
    solver = skin.solver
    calls: list[tuple[np.ndarray, float, np.ndarray]] = []

    def recorder(real, held):
        def solve(pen, *total):
            last_pen, last_total, _ = solver._last
            t = total[0] if held else None
            repeat = last_pen is not None and t == last_total and np.array_equal(pen, last_pen)
            if not repeat:  # (a repeated problem returns the last answer: no solve)
                calls.append((pen.copy(), np.nan if t is None else float(t), solver.p.copy()))
            return real(pen, *total)

        return solve

    skin.solve_force = recorder(skin.solve_force, True)
    skin.solve = recorder(skin.solve, False)
    proto = pressed.protocol
    z_vel = 0.0 if proto.force_control == "position" else None
    while len(calls) < n:
        runner.step(force_cmd=proto.force_n, slide_v=proto.speed_m_s, z_vel=z_vel)
    pen, total, warm = (np.array(x) for x in zip(*calls[:n], strict=True))
    return {"pen": pen, "total": total, "warm": warm, "table": solver.table, "tol": solver.tol}


def numpy_solves(poses: dict, tol: float, cold: bool) -> tuple[np.ndarray, np.ndarray, float]:
    """Each pose by the numpy solve from its warm start (a fresh start where ``cold``):
    ``(p, iterations, seconds per pose)``."""
    from sim_tactile.sim.skin.contact.spectral import Spectral

    sp = Spectral(poses["table"], tol=tol)
    out, its, wall = [], [], 0.0
    for k, (pen, total, warm) in enumerate(
        zip(poses["pen"], poses["total"], poses["warm"], strict=True)
    ):
        sp.p = np.zeros(sp.n) if cold else warm.copy()
        sp._last = (None, None, None)
        t0 = time.perf_counter()
        p, _ = sp.solve(pen) if np.isnan(total) else sp.solve_force(pen, total)
        if k > 0:  # (the first compiles and warms the caches)
            wall += time.perf_counter() - t0
        out.append(p)
        its.append(sp.iterations)
    return np.array(out), np.array(its), wall / max(1, len(out) - 1)


def batched_solves(poses, tol, cold, device, dtype, B, count, compile=False):
    """The first ``count`` poses in batches of ``B``: ``(p, iterations, seconds per pose,
    lockstep iterations per batch, products per pose)``."""
    import torch

    from sim_tactile.sim.skin.contact.batched import BatchedSpectral
    from sim_tactile.sim.skin.contact.spectral import Spectral

    bs = BatchedSpectral(
        Spectral(poses["table"]), device=device, dtype=dtype, tol=tol, compile=compile
    )
    pen, total, warm = poses["pen"], poses["total"], poses["warm"]
    held = not np.isnan(total).any()

    def run(lo, hi):
        w = None if cold else warm[lo:hi]
        if held:
            p, _, it = bs.solve_force(pen[lo:hi], total[lo:hi], w)
        else:
            p, it = bs.solve(pen[lo:hi], w)
        return p, it

    run(0, min(B, count))  # warm-up: cuFFT's plans, torch's caches
    out, its, steps, products = [], [], [], 0
    sync = torch.cuda.synchronize if device.startswith("cuda") else (lambda: None)
    sync()
    t0 = time.perf_counter()
    for lo in range(0, count, B):
        p, it = run(lo, min(lo + B, count))
        out.append(p)
        its.append(it)
        steps.append(bs.steps)
        products += bs.products
    sync()
    wall = time.perf_counter() - t0
    return (
        np.concatenate(out),
        np.concatenate(its),
        wall / count,
        float(np.mean(steps)),
        products / count,
    )


def rel_l1(a: np.ndarray, b: np.ndarray) -> float:
    """The largest ``sum |a - b| / sum b`` over the rows."""
    return float((np.abs(a - b).sum(axis=1) / np.abs(b).sum(axis=1)).max())


def measure(scene: str, poses: dict, a) -> list[dict]:
    from sim_tactile.sim.skin.contact.batched import FLOAT32_MIN_TOL
    from sim_tactile.sim.skin.contact.spectral import TOL

    rows = []
    ny, nx = poses["table"].shape
    for cold in (False, True) if a.cold else (False,):
        truth = numpy_solves(poses, TOL, cold)[0]  # the reference
        for tol in (float(t) for t in a.tols.split(",")):
            ref, ref_its, ref_s = numpy_solves(poses, tol, cold)
            for device in a.device_list:
                for dtype in a.dtypes.split(","):
                    if dtype == "float32" and tol < FLOAT32_MIN_TOL:
                        continue
                    for B in (int(b) for b in a.batches.split(",")):
                        count = min(len(ref), max(B, a.min_poses))
                        if B > len(ref):
                            continue
                        p, its, s, steps, prods = batched_solves(
                            poses, tol, cold, device, dtype, B, count, a.compile
                        )
                        row = {
                            "scene": scene,
                            "lattice": f"{nx} x {ny}",
                            "start": "cold" if cold else "warm",
                            "tol": tol,
                            "device": device,
                            "dtype": dtype,
                            "B": B,
                            "poses": count,
                            "numpy_us": 1e6 * ref_s,
                            "batched_us": 1e6 * s,
                            "speedup": ref_s / s,
                            "numpy_iterations": float(ref_its[:count].mean()),
                            "iterations": float(its.mean()),
                            "steps": steps,
                            "products": prods,
                            "max_rel_l1": rel_l1(p, ref[:count]),
                            "numpy_error": rel_l1(ref[:count], truth[:count]),
                            "error": rel_l1(p, truth[:count]),
                        }
                        rows.append(row)
                        if not a.json:
                            print(_line(row), flush=True)
    return rows


def _line(r: dict) -> str:
    return (
        f"| {r['scene']} | {r['lattice']} | {r['start']} | {r['tol']:g} | {r['device']} | "
        f"{r['dtype']} | {r['B']} | {r['numpy_us']:.0f} | {r['batched_us']:.0f} | "
        f"{r['speedup']:.2f}x | {r['numpy_iterations']:.1f} | {r['iterations']:.1f} | "
        f"{r['steps']:.1f} | {r['products']:.1f} | {r['max_rel_l1']:.1e} | "
        f"{r['numpy_error']:.1e} | {r['error']:.1e} |"
    )


HEADER = (
    "| scene | lattice | start | tol | device | dtype | B | numpy [us/pose] | batched "
    "[us/pose] | speed-up | numpy iterations | iterations | steps | products | max rel L1 | "
    "numpy error | error |\n" + "|---" * 17 + "|"
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default="icub-grating,icub-boxes,finger7-v2")
    ap.add_argument("--poses", type=int, default=512, help="poses recorded per scene")
    ap.add_argument("--batches", default="1,8,64,512")
    ap.add_argument("--min-poses", type=int, default=64, help="poses solved at least per B")
    ap.add_argument("--tols", default="1e-10,1e-4")
    ap.add_argument("--dtypes", default="float64,float32")
    ap.add_argument("--devices", default=None, help="default: cuda where there is one, else cpu")
    ap.add_argument("--threads", type=int, default=1, help="torch's CPU threads")
    ap.add_argument("--cold", action="store_true", help="also solve without warm starts")
    ap.add_argument("--compile", action="store_true", help="torch.compile the vector work")
    ap.add_argument("--save-poses", default=None, help="write the poses to this folder")
    ap.add_argument("--record-only", action="store_true", help="save the poses, solve none")
    ap.add_argument("--load-poses", default=None, help="read the poses from this folder")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    import torch

    torch.set_num_threads(a.threads)
    a.device_list = (
        a.devices.split(",") if a.devices else ["cuda" if torch.cuda.is_available() else "cpu"]
    )
    machine = _machine(torch, a)
    if not a.json:
        print(machine, flush=True)
        print(HEADER, flush=True)
    rows = []
    for scene in a.scenes.split(","):
        if a.load_poses:
            with np.load(Path(a.load_poses) / f"{scene}.npz") as z:
                poses = {k: z[k] for k in z.files}
            poses["pen"], poses["total"], poses["warm"] = (
                poses[k][: a.poses] for k in ("pen", "total", "warm")
            )
        else:
            poses = record_poses(scene, a.poses)
        if a.save_poses:
            Path(a.save_poses).mkdir(parents=True, exist_ok=True)
            np.savez_compressed(Path(a.save_poses) / f"{scene}.npz", **poses)
        if not a.record_only:
            rows += measure(scene, poses, a)
    if a.json:
        print(json.dumps({"machine": machine, "rows": rows}))
    return 0


def _machine(torch, a) -> str:
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
        cwd=Path(__file__).parent,
    ).stdout.strip()
    gpu = torch.cuda.get_device_name(0) if torch.cuda.is_available() else "no GPU"
    return (
        f"{os.cpu_count()} CPUs, {gpu}; torch {torch.__version__} on {a.threads} CPU "
        f"thread(s); commit {commit or '?'}"
    )


if __name__ == "__main__":
    sys.exit(main())
