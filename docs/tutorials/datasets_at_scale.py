"""Tutorial: a data set of your own configuration into a Zarr store, read back lazily.

python docs/tutorials/datasets_at_scale.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

import sim_tactile.datasets as datasets
from sim_tactile.generate import generate

CONFIG = """\
name = "my-set"
seed = 0
plates = ["finger7/flat", "finger7/ridges-2"]   # the classes
sensor = "grid3x3"
slides_per_plate = 20
quick_slides_per_plate = 2        # used by --quick

[protocol]
speed_m_s = 0.06
force_n = 1.0
"""


def main(out: Path, quick: bool = True) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    config = out / "my-set.toml"
    config.write_text(CONFIG)
    res = generate(str(config), out / "my.zarr", workers=1, quick=quick, progress=False)
    print(f"{res['trials']} slides in {res['wall_s']:.1f} s")
    store = datasets.open(out / "my.zarr")  # lazy: a slide's samples are read when asked
    print(len(store), "slides;", store[0].shape, "(time x taxels)")
    for x, y in store:  # every slide, checked against its checksum as it is read
        assert x.ndim == 2 and y in (0, 1)
    return res


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
