"""The figures of a task's report (PNG, headless): confusion matrices with their counts,
accuracy over time, one sample's streams and spike rasters per class, and the plates."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..learn.protocols import EvalResult
from ..plates import Plate
from ..records import SpikeTrains, TactileDataset
from .registry import PaperCell, TaskSpec


def _figure(**kw):
    from matplotlib.figure import Figure  # no pyplot: no global state, headless

    return Figure(**kw)


#: Up to this many classes, each cell of a confusion matrix carries its count.
COUNTS_UP_TO = 25


def plot_confusions(results: dict[str, EvalResult], class_names: Sequence[str], out: Path):
    """One confusion matrix per run: each cell coloured by the share of its true class
    (one colour bar for all), and, up to :data:`COUNTS_UP_TO` classes, labelled with its
    count of test samples summed over the repeats."""
    names = list(results)
    cols = min(3, len(names))
    rows = int(np.ceil(len(names) / cols))
    n = len(class_names)
    side = 3.2 + 0.22 * n
    fig = _figure(figsize=(side * cols + 1.0, side * rows + 0.5), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    im = None
    for ax, name in zip(axes, names, strict=False):
        counts = np.asarray(results[name].confusion, dtype=float)
        share = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)
        im = ax.imshow(share, vmin=0, vmax=1, cmap="Blues")
        if n <= COUNTS_UP_TO:
            for i, j in np.ndindex(counts.shape):
                if counts[i, j]:
                    ax.text(
                        j,
                        i,
                        f"{counts[i, j]:.0f}",
                        ha="center",
                        va="center",
                        fontsize=max(4.0, 9.0 - 0.2 * n),
                        color="white" if share[i, j] > 0.5 else "black",
                    )
        ax.set_title(f"{name}\naccuracy {results[name].mean:.3f}", fontsize=9)
        ax.set_xlabel("predicted class")
        ax.set_ylabel("true class")
        ticks = np.arange(n)
        ax.set_xticks(ticks, [str(c) for c in class_names], rotation=90, fontsize=7)
        ax.set_yticks(ticks, [str(c) for c in class_names], fontsize=7)
    for ax in axes[len(names) :]:
        ax.set_axis_off()
    if im is not None:
        fig.colorbar(
            im, ax=axes[: len(names)].tolist(), shrink=0.8, label="share of the true class"
        )
    fig.savefig(out, dpi=110)


def plot_over_time(
    curves: dict[str, dict[float, Sequence[float]]],
    papers: dict[str, PaperCell | None],
    title: str,
    out: Path,
):
    """Accuracy over time: ``curves`` maps a run to its accuracies at each time [s] (one per
    repeat), drawn as mean and SD; the paper's cell of a run as a cross at the end."""
    fig = _figure(figsize=(6.5, 4.2), layout="constrained")
    ax = fig.subplots()
    for name, curve in curves.items():
        if not curve:
            continue
        ts = sorted(curve)
        m = np.array([np.mean(curve[t]) for t in ts])
        s = np.array([np.std(curve[t]) for t in ts])
        line = ax.plot(ts, m, marker="o", label=name)[0]
        ax.fill_between(ts, m - s, m + s, color=line.get_color(), alpha=0.15)
        cell = papers.get(name)
        if cell is not None:
            ax.errorbar(
                [ts[-1]],
                [cell.mean],
                yerr=[cell.std or 0],
                fmt="x",
                color=line.get_color(),
                capsize=3,
            )
    ax.set_xlabel("time from the start of the recording [s]")
    ax.set_ylabel("test accuracy")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    ax.set_title(title + " (x: paper, full length)", fontsize=10)
    ax.text(
        0.01,
        0.01,
        "SVM, LSTM: retrained on the first t s; SNN: output counts up to t",
        transform=ax.transAxes,
        fontsize=7,
        color="0.3",
    )
    ax.legend(loc="lower right")
    fig.savefig(out, dpi=110)


def plot_rasters(ds: TactileDataset, encoded: Sequence[SpikeTrains], out: Path):
    """One encoded sample of every class (the first of each), spikes over time."""
    from matplotlib.collections import LineCollection

    n_cls = len(ds.class_names)
    cols = min(5, n_cls)
    rows = int(np.ceil(n_cls / cols))
    fig = _figure(figsize=(3.2 * cols, 2.6 * rows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False, sharex=True)).ravel()
    for k, ax in enumerate(axes):
        if k >= n_cls:
            ax.set_axis_off()
            continue
        idx = int(np.flatnonzero(ds.labels == k)[0])
        tr = encoded[idx]
        times = np.concatenate(tr.times)
        chan = np.repeat(np.arange(tr.n_channels), [t.size for t in tr.times])
        segs = np.stack([np.c_[times, chan - 0.4], np.c_[times, chan + 0.4]], axis=1)
        ax.add_collection(LineCollection(segs, colors="k", linewidths=0.6))  # one artist
        ax.set_xlim(tr.t_start, tr.t_end)
        ax.set_ylim(-0.5, tr.n_channels - 0.5)
        ax.invert_yaxis()
        ax.set_title(f"{ds.class_names[k]} (sample {idx})", fontsize=8)
        ax.tick_params(labelsize=6)
        if k % cols == 0:
            ax.set_ylabel("encoded channel", fontsize=7)
        if k >= (rows - 1) * cols:
            ax.set_xlabel("time [s]", fontsize=7)
    fig.savefig(out, dpi=100)


def plot_streams(ds: TactileDataset, out: Path):
    """The sensor output of one sample of every class (the first of each), every channel."""
    n_cls = len(ds.class_names)
    cols = min(5, n_cls)
    rows = int(np.ceil(n_cls / cols))
    fig = _figure(figsize=(3.2 * cols + 1.6, 2.4 * rows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False, sharex=True, sharey=True)).ravel()
    t = np.arange(ds.n_time) / ds.rate_hz
    colours = taxel_colours(ds.n_channels)
    for k, ax in enumerate(axes):
        if k >= n_cls:
            ax.set_axis_off()
            continue
        idx = int(np.flatnonzero(ds.labels == k)[0])
        for c in range(ds.n_channels):
            ax.plot(t, ds.data[idx, :, c], lw=0.7, color=colours[c], label=taxel_label(ds, c))
        ax.set_title(f"{ds.class_names[k]} (sample {idx})", fontsize=8)
        ax.tick_params(labelsize=6)
        if k % cols == 0:
            ax.set_ylabel(f"output [{ds.units}]" if ds.units else "output", fontsize=7)
        if k >= (rows - 1) * cols:
            ax.set_xlabel("time [s]", fontsize=7)
    taxel_key(fig, axes[0], ds.n_channels, ds.channel_names)
    fig.savefig(out, dpi=100)


#: Up to this many taxels, each has a line in the legend; beyond, a colour bar of the index.
LEGEND_UP_TO = 20


def taxel_colours(n: int) -> list:
    """One colour per taxel, all different: tab10 / tab20 up to 20, then a continuous map."""
    import matplotlib

    if n <= 10:
        return [matplotlib.colormaps["tab10"](i) for i in range(n)]
    if n <= 20:
        return [matplotlib.colormaps["tab20"](i) for i in range(n)]
    return [matplotlib.colormaps["viridis"](i / (n - 1)) for i in range(n)]


def taxel_label(ds: TactileDataset, c: int) -> str:
    """A taxel's name with its position on the pad [mm] where the data set knows it."""
    name = str(ds.channel_names[c])
    if ds.taxel_positions is None:
        return name
    x, y = np.asarray(ds.taxel_positions)[c, :2] * 1e3
    return f"{name} ({x:+.1f}, {y:+.1f}) mm"


def taxel_key(fig, ax, n: int, names: Sequence[str]) -> None:
    """The taxels' legend beside the panels (a colour bar of the index past
    :data:`LEGEND_UP_TO` taxels)."""
    import matplotlib

    if n <= LEGEND_UP_TO:
        fig.legend(
            *ax.get_legend_handles_labels(),
            loc="outside right upper",
            fontsize=6,
            title="taxel (x, y on the pad)",
            title_fontsize=6,
        )
        return
    sm = matplotlib.cm.ScalarMappable(
        norm=matplotlib.colors.Normalize(0, n - 1), cmap=matplotlib.colormaps["viridis"]
    )
    bar = fig.colorbar(sm, ax=fig.axes, shrink=0.8)
    bar.set_label(f"taxel index ({names[0]} .. {names[-1]})", fontsize=7)


def plot_plates(plates: Sequence[Plate], class_names: Sequence[str], out: Path):
    """Top view of each plate's surface height (the analytic definition the simulation used)."""
    from ..plates import surface_of

    n = len(plates)
    cols = min(5, n)
    rows = int(np.ceil(n / cols))
    fig = _figure(figsize=(2.6 * cols, 2.0 * rows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    for k, ax in enumerate(axes):
        if k >= n:
            ax.set_axis_off()
            continue
        p = plates[k]
        hx, hy = 0.5 * p.area_length_m + 3e-3, 0.5 * p.area_width_m + 3e-3
        x = np.linspace(-hx, hx, 360)
        y = np.linspace(-hy, hy, 240)
        z = surface_of(p).height(x[None, :], y[:, None]) * 1e3
        low = float(np.nanmin(z)) if np.isfinite(z).any() else 0.0
        span = float(np.nanmax(z)) - low if np.isfinite(z).any() else 0.0  # NaN: off the plate
        im = ax.imshow(
            z,
            extent=(-hx * 1e3, hx * 1e3, -hy * 1e3, hy * 1e3),
            origin="lower",
            cmap="viridis",
            vmin=low,
            vmax=low + max(span, 1e-9),
        )
        if span > 0:  # a flat plate has nothing for a colour bar to say
            fig.colorbar(im, ax=ax, shrink=0.8).ax.tick_params(labelsize=5)
        title = str(class_names[k]) + ("" if span > 0 else " (flat: height 0)")
        ax.set_title(title, fontsize=8)
        ax.tick_params(labelsize=5)
    fig.suptitle("plate height [mm] over x (slide) and y [mm]", fontsize=8)
    fig.savefig(out, dpi=100)


def write_figures(
    out: Path,
    spec: TaskSpec,
    ds: TactileDataset,
    encoded: Sequence[SpikeTrains],
    results: dict[str, EvalResult],
    runs: Sequence,
) -> list[str]:
    """Confusion matrices (runs on all channels), accuracy over time (when computed), the
    sensor streams and spike rasters of one sample per class and, for simulated data, the
    plates; returns the paths."""
    files = []
    main = {r.name: results[r.name] for r in runs if r.channels == "all"} or dict(results)
    f = out / "confusion.png"
    plot_confusions(main, ds.class_names, f)
    files.append(str(f))
    if any(results[r.name].over_time for r in runs):
        f = out / "accuracy_over_time.png"
        curves = {name: r.over_time for name, r in results.items()}
        plot_over_time(curves, {r.name: r.paper for r in runs}, spec.id, f)
        files.append(str(f))
    f = out / "streams_per_class.png"
    plot_streams(ds, f)
    files.append(str(f))
    f = out / "raster_per_class.png"
    plot_rasters(ds, encoded, f)
    files.append(str(f))
    plates = recorded_plates(ds.meta.get("setup") or {})
    if plates and all(p is not None for p in plates):
        f = out / "plates.png"
        plot_plates(plates, ds.class_names, f)
        files.append(str(f))
    return files


def recorded_plates(setup: dict) -> list[Plate | None]:
    """The plates a data set recorded, from their parameters (no lookup by name). A height
    map's samples are not in its parameters: its file is read again (a script runs again,
    or this process's loaded plate is taken) and kept only if it gives the recorded plate;
    else None (a store holds the samples: ``SlideStore.plates``)."""
    from ..plates import get_plate
    from ..plates.define.surface import samples_apart

    out: list[Plate | None] = []
    for ref, params in zip(setup.get("plates", []), setup.get("plate_params", []), strict=False):
        if not samples_apart(params):
            out.append(Plate.from_params(params))
            continue
        try:
            plate = get_plate(ref)
        except Exception:  # noqa: BLE001  (the file is gone or no longer loads: no picture)
            plate = None
        out.append(plate if plate is not None and plate.params() == params else None)
    return out
