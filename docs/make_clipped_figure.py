"""The figure of what clipping the node patches changes: grid3x3's row that meets the bumps
of ``finger7/bumps-4x4`` (1 N, 60 mm/s, ideal loads, 1 mm nodes), with whole patches and
with the patches clipped at the bumps' walls and the taxels' edges (``sim.skin.clipped``).

    python docs/make_clipped_figure.py OUT.png
"""

from __future__ import annotations

import sys
from dataclasses import replace

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from sim_tactile.plates import get_plate  # noqa: E402
from sim_tactile.sensors import get_sensor  # noqa: E402
from sim_tactile.sim.plan.fidelity import choose_fidelity  # noqa: E402
from sim_tactile.sim.plan.protocol import Protocol  # noqa: E402
from sim_tactile.sim.slide import simulate  # noqa: E402


def main(out: str) -> None:
    s = get_sensor("grid3x3")
    plate = get_plate("finger7/bumps-4x4")
    proto = Protocol(duration_s=1.0, speed_m_s=0.06).at_rate(s.layout.rate_hz)
    fid = choose_fidelity(plate, s.layout, s.finger, proto, "L1")
    recs = {
        name: simulate(
            plate, s, protocol=proto, fidelity=replace(fid, clipped=clip), ideal=True
        ).recording
        for name, clip in (("whole patches", False), ("clipped at walls and taxel edges", True))
    }
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.4), sharey=True)
    for ax, taxel in zip(axes, (6, 7, 8), strict=True):
        for name, rec in recs.items():
            x = np.asarray(rec.meta["x_pad_m"]) * 1e3
            ax.plot(x, rec.data[:, taxel], label=name)
        tx, ty = rec.taxels[taxel, :2] * 1e3
        ax.set_title(f"taxel {taxel} at ({tx:+.1f}, {ty:+.1f}) mm")
        ax.set_xlabel("pad position on the plate [mm]")
    axes[0].set_ylabel("taxel load [N]")
    axes[0].legend(fontsize=8)
    fig.suptitle("finger7/bumps-4x4, 1 mm nodes: four identical bumps pass each taxel", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main(sys.argv[1])
