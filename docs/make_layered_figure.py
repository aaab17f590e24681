"""The README's figure of what a finite skin changes: grid3x3's middle row on
``finger7/ridges-4`` (1 N, 60 mm/s, ideal loads) with the default half-space skin and with
the same 4 mm of silicone bonded to a rigid bone.

    python docs/make_layered_figure.py OUT.png
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import replace

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from sim_tactile.cache import ArtefactCache  # noqa: E402
from sim_tactile.sensors import get_sensor  # noqa: E402
from sim_tactile.sensors.stack import Layer, Stack  # noqa: E402
from sim_tactile.sim.slide import simulate  # noqa: E402


def main(out: str) -> None:
    half = get_sensor("grid3x3")
    f = half.finger
    layered = replace(half, finger=f.layered(Stack((Layer(f.thickness_m, f.young_pa, f.poisson),))))
    cache = ArtefactCache(tempfile.mkdtemp())
    recs = {
        name: simulate("finger7/ridges-4", s, ideal=True, seed=1, cache=cache).recording
        for name, s in (("half-space (default)", half), ("4 mm layer on a rigid bone", layered))
    }
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.4), sharey=True)
    for ax, taxel in zip(axes, (3, 4, 5), strict=True):
        for name, rec in recs.items():
            ax.plot(rec.times, rec.data[:, taxel], label=name)
        x, y = rec.taxels[taxel, :2] * 1e3
        ax.set_title(f"taxel {taxel} at ({x:+.1f}, {y:+.1f}) mm")
        ax.set_xlabel("time [s]")
    axes[0].set_ylabel("normal load [N]")
    axes[0].legend(loc="upper left", fontsize=8)
    fig.suptitle(
        "grid3x3 on finger7/ridges-4, 1 N, 60 mm/s: the same silicone as a half-space and as a layer on its bone",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    print(out)


if __name__ == "__main__":
    main(*sys.argv[1:])
