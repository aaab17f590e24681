"""Tutorial: your own plate file and sensor file, simulated like the presets.

python docs/tutorials/own_plates_and_sensor.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

from sim_tactile.plates import get_plate
from sim_tactile.sensors import resolve_sensor
from sim_tactile.sim.protocol import Protocol
from sim_tactile.sim.simulate import simulate

PLATE = """\
# a plate file: a grating of 2.5 mm period on the preset base (every key is checked)
name = "my-grating"

[texture]
kind = "grating"
period_m = 2.5e-3
height_m = 0.4e-3
duty = 0.4
"""

SENSOR = """\
# a sensor file: the grid3x3 preset's pad and transducer, a 4 x 4 grid of taxels
base = "grid3x3"
name = "my4x4"

[layout.grid]
rows = 4
cols = 4
pitch_m = 2.5e-3
size_m = 2.0e-3
depth_m = 0.0
"""


def main(out: Path, quick: bool = True) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    (out / "my-grating.toml").write_text(PLATE)
    (out / "my4x4.toml").write_text(SENSOR)
    plate = get_plate(str(out / "my-grating.toml"))
    sensor = resolve_sensor(str(out / "my4x4.toml"))
    print(plate.name, "with", sensor.layout.n, "taxels")
    protocol = Protocol(duration_s=0.3 if quick else None)
    rec = simulate(plate, sensor, protocol=protocol, seed=0).recording
    print("samples x channels:", rec.data.shape)
    return {"channels": int(rec.data.shape[1])}


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
