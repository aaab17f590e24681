"""Spike raster plots (matplotlib; works headless with the Agg backend)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from ..records import SpikeTrains


def raster(
    trains: SpikeTrains | Sequence[np.ndarray],
    *,
    ax=None,
    signal: np.ndarray | None = None,
    rate_hz: float | None = None,
    title: str | None = None,
    out: str | Path | None = None,
    marker_height: float = 0.8,
    color: str = "k",
):
    """Draw a spike raster: one row per channel, spike times [s] on the x axis.

    Args:
        trains: a :class:`SpikeTrains` (channel names become the row labels) or a sequence of
            spike-time arrays [s].
        ax: an existing matplotlib Axes; a new figure is made if ``None``.
        signal: optional ``(time, channels)`` input drawn above the raster (needs ``rate_hz``).
        title: figure title; ``out``: if given, the figure is saved there (PNG, SVG, ...).

    Returns:
        The matplotlib Figure.
    """
    from matplotlib.figure import Figure  # no pyplot: no global state, no display needed

    if isinstance(trains, SpikeTrains):
        times, names = list(trains.times), list(trains.channel_names)
        window = (trains.t_start, trains.t_end)
    else:
        times = [np.asarray(t, dtype=float) for t in trains]
        names = [f"ch{k}" for k in range(len(times))]
        window = None
    if ax is None:
        rows = 2 if signal is not None else 1
        ratios = [1, 2] if signal is not None else [1]
        fig = Figure(figsize=(8, 1.5 + 0.18 * len(times) + (1.5 if signal is not None else 0)))
        axes = fig.subplots(
            rows, 1, sharex=True, gridspec_kw={"height_ratios": ratios}, squeeze=False
        )
        ax = axes[-1, 0]
        if signal is not None:
            sig = np.asarray(signal, dtype=float)
            if rate_hz is None:
                raise ConfigError("rate_hz is needed to draw signal")
            axes[0, 0].plot(np.arange(sig.shape[0]) / rate_hz, sig, lw=0.8)
            axes[0, 0].set_ylabel("input")
    else:
        fig = ax.figure
    ax.eventplot(times, lineoffsets=np.arange(len(times)), linelengths=marker_height, colors=color)
    ax.set_yticks(np.arange(len(times)))
    ax.set_yticklabels(names, fontsize=7 if len(times) > 20 else 9)
    ax.set_ylim(-0.5, len(times) - 0.5)
    ax.invert_yaxis()
    ax.set_xlabel("time [s]")
    if window is not None:
        ax.set_xlim(*window)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    if out is not None:
        fig.savefig(out, dpi=120)
    return fig
