"""Headless preview PNG of a plate: a shaded relief of its surface and the centre-line profile.

Rendered with matplotlib's Agg backend from the analytic height map, so it needs no display
and no OpenGL. The colour scale is in mm, or in um for roughness plates.
"""

from __future__ import annotations

import io

import numpy as np

from .features import height_at
from .spec import Plate, Roughness

#: Raster step of the preview [m].
PREVIEW_STEP_M = 1e-4


def preview_png(plate: Plate, *, dpi: int = 110) -> bytes:
    """PNG bytes of the preview (deterministic for the same plate and matplotlib)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.colors import LightSource

    rough = isinstance(plate.texture, Roughness)
    unit, scale = ("um", 1e6) if rough else ("mm", 1e3)
    half_x = min(plate.length_m, plate.area_length_m + 0.012) / 2
    half_y = plate.width_m / 2
    xs = np.arange(-half_x, half_x + 1e-12, PREVIEW_STEP_M)
    ys = np.arange(-half_y, half_y + 1e-12, PREVIEW_STEP_M)
    z = height_at(plate, xs[None, :], ys[:, None]) * scale

    fig, (ax0, ax1) = plt.subplots(
        2, 1, figsize=(7.5, 5.2), height_ratios=[2.2, 1], layout="constrained"
    )
    ls = LightSource(azdeg=315, altdeg=40)
    span = float(np.nanmax(z) - np.nanmin(z)) or 1.0
    ve = 0.25 * (xs[-1] - xs[0]) * scale / span  # exaggerate so relief shows at any height
    rgb = ls.shade(
        z, cmap=plt.get_cmap("viridis"), vert_exag=ve / (PREVIEW_STEP_M * scale), blend_mode="soft"
    )
    ext = (xs[0] * 1e3, xs[-1] * 1e3, ys[0] * 1e3, ys[-1] * 1e3)
    ax0.imshow(rgb, origin="lower", extent=ext, interpolation="nearest")
    sm = plt.cm.ScalarMappable(cmap="viridis", norm=plt.Normalize(np.nanmin(z), np.nanmax(z)))
    fig.colorbar(sm, ax=ax0, label=f"height [{unit}]", shrink=0.9)
    ax0.set_xlabel("x [mm]  (slide direction: +x)")
    ax0.set_ylabel("y [mm]")
    ax0.set_title(f"{plate.name or 'plate'}  ({plate.family}, hash {plate.hash})", fontsize=10)
    # the line across the most relief, nearest to y = 0 among ties
    relief = np.nanmean(z, axis=1)
    rows = np.flatnonzero(relief >= relief.max() - 1e-9 * max(abs(relief.max()), 1e-30))
    row = int(rows[np.argmin(np.abs(ys[rows]))])
    ax1.plot(xs * 1e3, z[row], lw=0.8, color="k")
    ax1.set_xlim(ext[0], ext[1])
    ax1.set_xlabel(f"x [mm], profile at y = {ys[row] * 1e3:.2f} mm")
    ax1.set_ylabel(f"z [{unit}]")
    ax1.grid(alpha=0.3)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()
