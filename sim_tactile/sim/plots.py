"""Figures of a recording: taxel traces over time and a taxel heat map (headless, Agg)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..records import Recording


def _figure(*args, **kw):
    from matplotlib.figure import Figure

    return Figure(*args, **kw)


#: Up to this many taxels, each has its own colour and a line in the legend; beyond, the
#: colour runs over the taxel index and a colour bar says so.
LEGEND_UP_TO = 20


def channel_names(rec: Recording) -> list[str]:
    """The recording's channel names, as its sensor names them (the BioTac's ``ele1`` ..
    ``ele19``, a grid's ``r0c0`` ..); ``t0``, ``t1``, .. for a recording that names none."""
    names = rec.meta.get("channel_names")
    if names and len(names) == rec.n_taxels:
        return [str(c) for c in names]
    return [f"t{i}" for i in range(rec.n_taxels)]


def plot_traces(rec: Recording, path: str | Path) -> Path:
    """One line per taxel, its output against time, ordered by the taxel's row (y) then its
    column (x); each labelled with its name and its position on the pad."""
    import matplotlib

    n = len(rec.taxels)
    fig = _figure(figsize=(8.8 if n <= LEGEND_UP_TO else 8, 4.5), layout="constrained")
    ax = fig.add_subplot()
    pos = rec.taxels
    order = np.lexsort((pos[:, 0], pos[:, 1]))
    names = channel_names(rec)
    if n <= 10:
        colours = [matplotlib.colormaps["tab10"](k) for k in range(n)]
    elif n <= LEGEND_UP_TO:
        colours = [matplotlib.colormaps["tab20"](k) for k in range(n)]
    else:
        colours = [matplotlib.colormaps["viridis"](k / (n - 1)) for k in range(n)]
    for k, i in enumerate(order):
        ax.plot(
            rec.times,
            rec.data[:, i],
            lw=0.9,
            color=colours[k],
            label=f"{names[i]} ({pos[i, 0] * 1e3:+.1f}, {pos[i, 1] * 1e3:+.1f}) mm",
        )
    ax.set_xlabel("time since the slide started [s]")
    ax.set_ylabel(f"taxel output [{rec.units}]")
    meta = rec.meta
    ax.set_title(
        f"{meta.get('plate', '')}, {meta.get('layout', '')}, "
        f"{meta.get('protocol', {}).get('speed_m_s', 0) * 1e3:.0f} mm/s, "
        f"{meta.get('protocol', {}).get('force_n', 0):.2g} N, {meta.get('fidelity', {}).get('level', '')}",
        fontsize=10,
    )
    if n <= LEGEND_UP_TO:
        fig.legend(loc="outside right upper", fontsize=7, title="taxel (x, y)", title_fontsize=7)
    else:
        sm = matplotlib.cm.ScalarMappable(
            norm=matplotlib.colors.Normalize(0, n - 1), cmap=matplotlib.colormaps["viridis"]
        )
        fig.colorbar(sm, ax=ax, label="taxel, by row then column")
    ax.grid(alpha=0.3)
    path = Path(path)
    fig.savefig(path, dpi=100)
    return path


def plot_heatmap(rec: Recording, path: str | Path) -> Path:
    """Each taxel's mean and peak load at its position on the pad (a panel whose taxels all
    read the same shows that value, without a colour bar)."""
    fig = _figure(figsize=(8, 3.6), layout="constrained")
    pos = rec.taxels * 1e3
    for j, (title, vals) in enumerate(
        (("mean", rec.data.mean(axis=0)), ("peak", rec.data.max(axis=0)))
    ):
        ax = fig.add_subplot(1, 2, j + 1)
        varies = np.ptp(vals) > 1e-9 * max(1.0, float(np.abs(vals).max()))
        lim = {} if varies else {"vmin": float(vals[0]) - 1.0, "vmax": float(vals[0]) + 1.0}
        sc = ax.scatter(
            pos[:, 0],
            pos[:, 1],
            c=vals,
            s=max(20, 4000 / len(pos)),
            marker="s",
            cmap="magma",
            **lim,
        )
        if varies:
            fig.colorbar(sc, ax=ax, label=f"{title} [{rec.units}]")
        else:
            title = f"{title} (every taxel {float(vals[0]):.3g} {rec.units})"
        ax.set_aspect("equal")
        ax.set_xlabel("x (slide) [mm]")
        ax.set_ylabel("y [mm]")
        ax.set_title(f"{title} taxel output", fontsize=10)
    path = Path(path)
    fig.savefig(path, dpi=100)
    return path
