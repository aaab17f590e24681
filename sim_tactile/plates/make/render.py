"""Headless preview PNG of a plate: a shaded relief of its surface and the centre-line profile.

Rendered with matplotlib's Agg backend from the analytic height map, so it needs no display
and no OpenGL. The colour scale is in mm, or in um for roughness plates. A height-map
plate's panel is drawn on its samples (every sample, or every ``k``-th where the plate has
more than :data:`MAX_PREVIEW_CELLS`); samples without material (holes) are drawn in
:data:`HOLE_RGB` and named in a legend; a flat plate gets a colour bar around its one level.
"""

from __future__ import annotations

import io
import math

import numpy as np

from ..define.spec import Plate
from ..define.surface import Surface, surface_of

#: Raster step of the preview [m].
PREVIEW_STEP_M = 1e-4
#: Most raster cells a height-map plate's preview draws (the figure is about 800 pixels
#: wide, so more would not show).
MAX_PREVIEW_CELLS = 1_000_000
#: Colour of the places without material (not in viridis).
HOLE_RGB = (0.85, 0.10, 0.55)


def _axes(plate: Plate, surface: Surface) -> tuple[np.ndarray, np.ndarray]:
    """The raster's x and y [m]: every PREVIEW_STEP_M, or a height map's samples."""
    half_x = min(plate.length_m, plate.area_length_m + 0.012) / 2
    half_y = plate.width_m / 2
    t = surface.height_map
    if t is None:
        return (
            np.arange(-half_x, half_x + 1e-12, PREVIEW_STEP_M),
            np.arange(-half_y, half_y + 1e-12, PREVIEW_STEP_M),
        )
    cells = (2 * half_x / t.pixel_m) * (2 * half_y / t.pixel_m)
    step = t.pixel_m * max(1, math.ceil(math.sqrt(cells / MAX_PREVIEW_CELLS)))
    mx, my = t.grid()
    return _through(mx[0], half_x, step), _through(my[0], half_y, step)


def _through(origin: float, half: float, step: float) -> np.ndarray:
    """Points every ``step`` within ``[-half, half]``, one of them at ``origin``."""
    k0 = math.ceil((-half - origin) / step - 1e-9)
    k1 = math.floor((half - origin) / step + 1e-9)
    return origin + np.arange(k0, k1 + 1) * step


def preview_png(plate: Plate, *, dpi: int = 110) -> bytes:
    """PNG bytes of the preview (deterministic for the same plate and matplotlib)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.colors import LightSource, Normalize
    from matplotlib.patches import Patch

    surface = surface_of(plate)
    rough = surface.profile is not None
    unit, scale = ("um", 1e6) if rough else ("mm", 1e3)
    xs, ys = _axes(plate, surface)
    z = surface.height(xs[None, :], ys[:, None]) * scale
    holes = np.isnan(z)
    lo, hi = (float(np.min(z[~holes])), float(np.max(z[~holes]))) if not holes.all() else (0, 0)
    norm = Normalize(lo, hi) if hi > lo else Normalize(lo - 0.5, lo + 0.5)  # a flat plate
    zf = np.where(holes, lo, z)

    fig, (ax0, ax1) = plt.subplots(
        2, 1, figsize=(7.5, 5.2), height_ratios=[2.2, 1], layout="constrained"
    )
    ls = LightSource(azdeg=315, altdeg=40)
    span = (hi - lo) or 1.0
    ve = 0.25 * (xs[-1] - xs[0]) * scale / span  # exaggerate so relief shows at any height
    step = (xs[1] - xs[0]) if len(xs) > 1 else PREVIEW_STEP_M
    cmap = plt.get_cmap("viridis")
    rgb = ls.shade(zf, cmap=cmap, norm=norm, vert_exag=ve / (step * scale), blend_mode="soft")
    rgb[holes, :3] = HOLE_RGB
    ext = (xs[0] * 1e3, xs[-1] * 1e3, ys[0] * 1e3, ys[-1] * 1e3)
    ax0.imshow(rgb, origin="lower", extent=ext, interpolation="nearest")
    if holes.any():
        t = surface.height_map
        n = f" ({int(np.isnan(t.z).sum())} samples)" if t is not None else ""
        ax0.legend(
            handles=[Patch(color=HOLE_RGB, label=f"no material{n}")],
            loc="upper right",
            fontsize=8,
        )
    fig.colorbar(
        plt.cm.ScalarMappable(cmap=cmap, norm=norm), ax=ax0, label=f"height [{unit}]", shrink=0.9
    )
    ax0.set_xlabel("x [mm]  (slide direction: +x)")
    ax0.set_ylabel("y [mm]")
    ax0.set_title(f"{plate.name or 'plate'}  ({plate.family}, hash {plate.hash})", fontsize=10)
    # the line across the most relief, nearest to y = 0 among ties (holes count as the lowest)
    relief = zf.mean(axis=1)
    rows = np.flatnonzero(relief >= relief.max() - 1e-9 * max(abs(relief.max()), 1e-30))
    row = int(rows[np.argmin(np.abs(ys[rows]))])
    ax1.plot(xs * 1e3, z[row], lw=0.8, color="k")  # a hole is a gap
    ax1.set_xlim(ext[0], ext[1])
    ax1.set_xlabel(f"x [mm], profile at y = {ys[row] * 1e3:.2f} mm")
    ax1.set_ylabel(f"z [{unit}]")
    ax1.grid(alpha=0.3)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()
