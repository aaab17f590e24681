"""Render docs/img/plates.png: a montage of eight preset plates (the README's picture).

python docs/make_plate_montage.py
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LightSource

from sim_tactile.plates import get_plate, surface_of

NAMES = [
    "finger7/ridges-4",
    "finger7/bumps-6x6",
    "multilayer3/grating-9",
    "multilayer3/hemispheres-6x6",
    "textures20/cylinders-3.0mm",
    "textures20/grating-3.0mm-draft30",
    "roughness8/ra-50",
    "roughness8/ra-3.2",
]


def main() -> None:
    fig, axes = plt.subplots(2, 4, figsize=(12, 6.2), layout="constrained")
    ls = LightSource(azdeg=315, altdeg=35)
    for ax, name in zip(axes.ravel(), NAMES, strict=True):
        p = get_plate(name)
        xs = np.arange(-0.021, 0.021, 5e-5)
        ys = np.arange(-0.018, 0.018, 5e-5)
        z = surface_of(p).height(xs[None, :], ys[:, None])
        span = float(np.ptp(z)) or 1.0
        rgb = ls.shade(
            z / span, cmap=plt.get_cmap("cividis"), vert_exag=0.004 / 5e-5 * 0.3, blend_mode="soft"
        )
        ax.imshow(rgb, origin="lower", extent=(-21, 21, -18, 18))
        unit = f"{np.max(z) * 1e6:.0f} um" if "rough" in name else f"{np.max(z) * 1e3:.2g} mm"
        ax.set_title(f"{name}\npeak {unit}", fontsize=9)
        ax.set_xticks([-18, 0, 18])
        ax.set_yticks([-18, 0, 18])
        ax.tick_params(labelsize=7)
    fig.suptitle("sim_tactile preset plates (x = slide direction, mm)", fontsize=11)
    out = Path(__file__).parent / "img" / "plates.png"
    fig.savefig(out, dpi=90)
    print(out)


if __name__ == "__main__":
    main()
