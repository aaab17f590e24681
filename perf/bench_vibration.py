"""How well the time step resolves a rough plate's vibration: what a piezoelectric sensor
reports, against the same slide at finer steps.

    python perf/bench_vibration.py [--scene roughness8-v1] [--plates P,...] [--slides 0]
        [--dts 1,0.5,0.25,0.125,0.0625] [--paths] [--json]

For each plate (all of the scene's, sorted, or ``--plates``) and slide (``--slides``: its
index among the plate's slides of the full task, seed 0), the slide's ideal taxel loads are
computed per step (``path = per-step``) at each time step of ``--dts`` [ms] and passed
through the sensor's own transducer without noise (the piezoelectric's high-pass: a steady
load reads zero). Each row gives the pad's advance per step over the roughness's correlation
length and, for each step, the relative L2 of that output against the finest step's, and of
the raw loads, in percent. The loads agree to a fraction of a percent at every step; the
vibration, which is all a piezoelectric film reports, converges only once the pad advances
less than about a correlation length a step.

``--paths`` compares instead, at the slide's own step, the fast paths against the per-step
solve: ``solve_every = 2`` and the table along the slide (``path = phase-table``, which
``auto`` takes for a set of many slides a plate), their output and their raw loads.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import replace

import numpy as np
from _task_slides import add_arguments, task_slides


def rel(a: np.ndarray, b: np.ndarray) -> float:
    """The relative L2 of ``a`` against ``b``, in percent."""
    return float(100 * np.linalg.norm(a - b) / np.linalg.norm(b))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_arguments(ap, slides="0", scene="roughness8-v1")
    ap.add_argument("--dts", default="1,0.5,0.25,0.125,0.0625", help="time steps [ms]")
    ap.add_argument("--paths", action="store_true", help="the fast paths at the slide's step")
    args = ap.parse_args()
    if args.paths:
        return paths(args)

    from sim_tactile.cache import ArtefactCache
    from sim_tactile.sim import StepOptions, run

    dts = sorted((float(s) * 1e-3 for s in args.dts.split(",")), reverse=True)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cache = ArtefactCache(tmp)
        for plate, k, slide in task_slides(args):
            tex = slide.plate.params().get("texture") or {}
            corr = tex.get("corr_length_m")
            speed = slide.drawn().speed_m_s
            loads, outs = {}, {}
            for dt in dts:
                step = StepOptions(path="per-step")
                loads[dt], outs[dt] = _output(run, replace(slide, dt_s=dt), step, cache)
            ref = dts[-1]
            row = {
                "plate": plate,
                "slide": k,
                "speed_m_s": speed,
                "corr_length_m": corr,
                "steps": {
                    f"{dt * 1e3:g}": {
                        "advance_over_corr": None if not corr else speed * dt / corr,
                        "output_pct": rel(outs[dt], outs[ref]),
                        "loads_pct": rel(loads[dt], loads[ref]),
                    }
                    for dt in dts[:-1]
                },
            }
            rows.append(row)
            if not args.json:
                cells = "; ".join(
                    f"dt {dt} ms (advance {v['advance_over_corr']:.2g} corr): output "
                    f"{v['output_pct']:.1f}%, loads {v['loads_pct']:.2f}%"
                    if v["advance_over_corr"] is not None
                    else f"dt {dt} ms: output {v['output_pct']:.1f}%, loads {v['loads_pct']:.2f}%"
                    for dt, v in row["steps"].items()
                )
                print(f"{plate} slide {k} ({speed:.3f} m/s): {cells}", flush=True)
    if args.json:
        json.dump(rows, sys.stdout, indent=1)
    return 0


def _output(run, slide, opts, cache):
    """The slide's ideal loads with ``opts`` and its sensor's output of them, noise-free."""
    sensor = slide.sensor_def
    x = run(replace(slide, options=opts), cache).recording.data.astype(float)
    return x, sensor.transducer.apply(x, sensor.rate_hz)


def paths(args) -> int:
    """``--paths``: each fast path's output and raw loads against the per-step solve's."""
    from sim_tactile.cache import ArtefactCache
    from sim_tactile.sim import StepOptions, run

    ways = {"every 2nd step": StepOptions(solve_every=2), "table": StepOptions(path="phase-table")}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cache = ArtefactCache(tmp)
        for plate, k, slide in task_slides(args):
            ref_x, ref_y = _output(run, slide, StepOptions(path="per-step"), cache)
            row = {"plate": plate, "slide": k}
            for name, opts in ways.items():
                x, y = _output(run, slide, opts, cache)
                row[name] = {"output_pct": rel(y, ref_y), "loads_pct": rel(x, ref_x)}
            rows.append(row)
            if not args.json:
                cells = "; ".join(
                    f"{name}: output {row[name]['output_pct']:.1f}%, loads "
                    f"{row[name]['loads_pct']:.2f}%"
                    for name in ways
                )
                print(f"{plate} slide {k}: {cells}", flush=True)
    if args.json:
        json.dump(rows, sys.stdout, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
