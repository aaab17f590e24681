"""Figures of a recording: taxel traces over time and a taxel heat map (headless, Agg)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..records import Recording


def _figure(*args, **kw):
    from matplotlib.figure import Figure

    return Figure(*args, **kw)


def plot_traces(rec: Recording, path: str | Path) -> Path:
    """One line per taxel, load against time, in rows of taxels that share a y."""
    fig = _figure(figsize=(8, 4.5), layout="constrained")
    ax = fig.add_subplot()
    pos = rec.taxels
    order = np.lexsort((pos[:, 0], pos[:, 1]))
    cmap = __import__("matplotlib").colormaps["viridis"]
    for k, i in enumerate(order):
        ax.plot(
            rec.times,
            rec.data[:, i],
            lw=0.9,
            color=cmap(k / max(len(order) - 1, 1)),
            label=f"x={pos[i, 0] * 1e3:+.1f} y={pos[i, 1] * 1e3:+.1f} mm"
            if len(order) <= 12
            else None,
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
    if len(order) <= 12:
        ax.legend(fontsize=7, ncol=3)
    ax.grid(alpha=0.3)
    path = Path(path)
    fig.savefig(path, dpi=100)
    return path


def plot_heatmap(rec: Recording, path: str | Path) -> Path:
    """Each taxel's mean and peak load at its position on the pad."""
    fig = _figure(figsize=(8, 3.6), layout="constrained")
    pos = rec.taxels * 1e3
    for j, (title, vals) in enumerate(
        (("mean", rec.data.mean(axis=0)), ("peak", rec.data.max(axis=0)))
    ):
        ax = fig.add_subplot(1, 2, j + 1)
        sc = ax.scatter(
            pos[:, 0], pos[:, 1], c=vals, s=max(20, 4000 / len(pos)), marker="s", cmap="magma"
        )
        fig.colorbar(sc, ax=ax, label=f"{title} [{rec.units}]")
        ax.set_aspect("equal")
        ax.set_xlabel("x (slide) [mm]")
        ax.set_ylabel("y [mm]")
        ax.set_title(f"{title} taxel output")
    path = Path(path)
    fig.savefig(path, dpi=100)
    return path
