"""Single precision for the spectral contact solve: the product with the compliance in
``float32`` against ``float64``, timed A B A B, and the solves of a real slide replayed with
it.

    python perf/bench_precision.py [--scene textures20-icub60-v1] [--replays 20]

One slide of the scene (the first slide of its middle measured plate, as
``perf/bench_response.py`` picks them) records the spectral solver of its skin and the
penetrations and totals of its held steps. Then:

- the product ``C p`` on random pressures, in ``float64`` (the solver's own
  :meth:`~sim_tactile.sim.skin.contact.spectral.Spectral.apply`) and in ``float32`` (the
  same transforms through pocketfft on ``float32``/``complex64`` buffers), alternated three
  times, the median of 5 x 50 products each;
- ``--replays`` of the slide's solves, spread over it, solved afresh by a new solver with the
  ``float64`` product and by one with the ``float32`` product, both at the reference
  tolerance: how many converge, and the relative L2 of their pressures where both do.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))


def _float32_product(solver):
    """``solver.apply`` with its transforms in single precision (the answer in float64)."""
    from sim_tactile.sim.skin.contact import spectral

    spectral._load_fft()
    pp = spectral._pocketfft
    khat = solver.khat.astype(np.complex64)
    padded = np.zeros(solver._padded.shape, np.float32)
    spectrum = np.zeros(solver._spectrum.shape, np.complex64)
    ny, nx, lx = solver.ny, solver.nx, solver.shape[1]

    def apply(p):
        padded[:, :nx] = p.reshape(ny, nx)
        spectrum[:ny] = pp.r2c(padded, (1,), True, 0, None, 1)
        spectrum[ny:] = 0
        pp.c2c(spectrum, (0,), True, 0, spectrum, 1)
        spectrum.__imul__(khat)
        pp.c2c(spectrum, (0,), False, 2, spectrum, 1)
        out = pp.c2r(spectrum[:ny], (1,), lx, False, 2, None, 1)
        return out[:, :nx].ravel().astype(np.float64)

    return apply


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="textures20-icub60-v1")
    ap.add_argument("--replays", type=int, default=20)
    args = ap.parse_args()

    import bench_response

    from sim_tactile.cache import ArtefactCache
    from sim_tactile.errors import PhysicsError
    from sim_tactile.sim.skin.contact import spectral

    spectral._load_fft()
    if spectral._pocketfft is None:
        print("scipy.fft's pocketfft binding is not available: nothing to measure")
        return 1
    seen, calls = [], []
    real_init, real_solve = spectral.Spectral.__init__, spectral.Spectral.solve_force

    def init(self, *a, **k):
        real_init(self, *a, **k)
        seen.append(self)

    def solve_force(self, pen, total):
        calls.append((self, pen.copy(), total))
        return real_solve(self, pen, total)

    spectral.Spectral.__init__, spectral.Spectral.solve_force = init, solve_force
    try:
        _, jobs = bench_response.jobs_of(args.scene, 3)
        bench_response.run(jobs[1], 1, ArtefactCache(tempfile.mkdtemp()))
    finally:
        spectral.Spectral.__init__, spectral.Spectral.solve_force = real_init, real_solve
    if not seen:
        print(f"{args.scene}: its slide made no spectral solve")
        return 1
    solver = max(seen, key=lambda s: s.n)
    p = np.random.default_rng(0).random(solver.n)
    single = _float32_product(solver)
    a64, a32 = solver.apply(p), single(p)
    print(
        f"{args.scene}: lattice {solver.ny} x {solver.nx}, transforms {solver.shape}; "
        f"float32 product's relative error {np.linalg.norm(a32 - a64) / np.linalg.norm(a64):.2g}"
    )
    times = {"float64": [], "float32": []}
    for _ in range(3):
        for name, f in (("float64", solver.apply), ("float32", single)):
            for _ in range(5):
                t0 = time.perf_counter()
                for _ in range(50):
                    f(p)
                times[name].append((time.perf_counter() - t0) / 50)
    t64, t32 = (statistics.median(times[k]) for k in ("float64", "float32"))
    print(f"product: float64 {1e6 * t64:.1f} us, float32 {1e6 * t32:.1f} us ({t64 / t32:.2f}x)")

    mine = [c for c in calls if c[0] is solver]
    picks = mine[:: max(1, len(mine) // args.replays)][: args.replays]
    converged, errors = 0, []
    for _, pen, total in picks:
        ref = spectral.Spectral(solver.table)
        p64, _ = ref.solve_force(pen, total)
        trial = spectral.Spectral(solver.table)
        trial.apply = _float32_product(trial)
        try:
            p32, _ = trial.solve_force(pen, total)
        except PhysicsError:
            continue
        converged += 1
        errors.append(np.linalg.norm(p32 - p64) / max(np.linalg.norm(p64), 1e-300))
    worst = f"{max(errors):.2g}" if errors else "-"
    print(
        f"replayed solves at the reference tolerance: {converged} of {len(picks)} converged in "
        f"float32; pressures' relative L2 against float64, largest: {worst}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
