"""Tutorial: one slide from Python: a plate, a protocol, ``simulate``, ``press`` and the
streams.

    python docs/tutorials/one_slide.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

from sim_tactile.plates import Grating, Plate, surface_of
from sim_tactile.sensors import Finger
from sim_tactile.sim import Protocol, press, simulate
from sim_tactile.sim.plots import plot_traces


def main(out: Path, quick: bool = True) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    # a plate: a grating of 3 mm period, 0.5 mm high ridges across the slide
    plate = Plate(texture=Grating(period_m=3e-3, height_m=0.5e-3))
    print("height at the centre [m]:", float(surface_of(plate).height(0.0, 0.0)))

    # a slide: 60 mm/s at 1 N, the pad crossing the texture (quick: the first 0.3 s)
    protocol = Protocol(speed_m_s=0.06, force_n=1.0, duration_s=0.3 if quick else None)
    res = simulate(plate, "grid3x3", protocol=protocol, seed=0, ideal=True)
    rec = res.recording  # data (time x taxels) [N], times [s], taxels (N x 3) [m], meta
    print(res.fidelity.reason)
    print("samples x taxels:", rec.data.shape, "peak load [N]:", float(rec.data.max()))
    rec.save(out / "slide.npz")
    plot_traces(rec, out / "slide.png")

    # a static press of a spherical pad, read by a dense grid
    sphere = Finger(shape="sphere", radius_m=8e-3, size_m=(8e-3, 8e-3))
    pressed = press(sphere, 1.0, readout_pitch_m=0.5e-3)
    print(f"contact radius {pressed.contact_radius_m * 1e3:.2f} mm")
    return {"samples": int(rec.data.shape[0]), "radius_m": pressed.contact_radius_m}


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
