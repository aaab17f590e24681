"""Real-time factor of each sensor on the same plate (the cost grows with the taxel count),
and the statistics of simulated BioTac and iCub streams against the real data.

    python perf/bench_sensors.py [--json] [--data PATH] [--repeats N]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

import numpy as np

from sim_tactile.sensors import get_sensor
from sim_tactile.sim.slide import simulate

PLATE = "textures20/grating-3.0mm"
DEFAULT_DATA = Path(__file__).resolve().parents[2] / "shared" / "datasets" / "biotac_slide_20_50"


def cost_rows(repeats: int) -> list[dict]:
    rows = []
    for name in ("grid3x3", "multilayer3x3x2", "biotac19", "icub60"):
        rtf, res = [], None
        for _ in range(repeats):
            res = simulate(PLATE, name)
            m = res.recording.meta
            rtf.append(m["sim_s"] / m["slide_wall_s"])
        rows.append(
            {
                "sensor": name,
                "taxels": res.recording.n_taxels,
                "nodes_pitch_mm": res.fidelity.pitch_m * 1e3,
                "dt_ms": res.fidelity.dt_s * 1e3,
                "rtf_median": statistics.median(rtf),
                "pad_mm": list(np.round(np.array(get_sensor(name).finger.patch_m) * 1e3, 1)),
            }
        )
    return rows


def stats_rows(data: Path) -> list[dict]:
    if not data.is_dir():
        return []
    files = sorted((data / "raw_data").glob("mat*/mat*_bio.csv"))[::50]
    real_b = np.array(
        [np.genfromtxt(f, delimiter=",", skip_header=1)[100:500, 26:45] for f in files]
    )
    real_i = (
        np.load(data / "compiled_data" / "icub_test.npy").reshape(200, 60, 75).transpose(0, 2, 1)
    )
    out = []
    for name, real in (("biotac19", real_b), ("icub60", real_i)):
        sims = np.array(
            [simulate(PLATE, name, seed=s).recording.data.astype(float) for s in range(3)]
        )
        for label, a, ax in (("real", real, 1), ("simulated", sims, 1)):
            out.append(
                {
                    "sensor": name,
                    "source": label,
                    "mean": float(a.mean()),
                    "max": float(a.max()),
                    "temporal_std": float(np.median(a.std(axis=ax))),
                    "noise_diff_std": float(np.median(np.diff(a, axis=ax).std(axis=ax))),
                }
            )
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    doc = {"plate": PLATE, "cost": cost_rows(args.repeats), "stats": stats_rows(args.data)}
    if args.json:
        print(json.dumps(doc, indent=2))
        return 0
    print(f"{'sensor':16s} {'taxels':>6s} {'node pitch':>10s} {'dt [ms]':>8s} {'RTF':>6s}")
    for r in doc["cost"]:
        print(
            f"{r['sensor']:16s} {r['taxels']:6d} {r['nodes_pitch_mm']:10.2f} {r['dt_ms']:8.2f} {r['rtf_median']:6.2f}"
        )
    for r in doc["stats"]:
        print(
            f"{r['sensor']:10s} {r['source']:10s} mean {r['mean']:7.2f} max {r['max']:7.1f} "
            f"temporal std {r['temporal_std']:6.2f} noise (diff std) {r['noise_diff_std']:5.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
