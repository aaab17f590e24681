"""The task report: comparison with the paper, the typed report (:class:`Report`, one
Markdown and one text renderer) and the PNG figures."""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..learn.protocols import EvalResult
from ..plates import Plate
from ..records import SpikeTrains, TactileDataset
from ..tables import markdown_table, text_table
from .registry import PaperCell, TaskSpec
from .report_neuro import neuromorphic_table

#: A cell reproduces the paper when it lies within this many of the paper's standard
#: deviations, or above.
TOLERANCE_SD = 2.0


def compare(mean: float, cell: PaperCell | None, note: str | None, *, quick: bool) -> dict:
    """Where ``mean`` lies against the paper's cell: ``status`` is ``within`` (|delta| <= 2
    paper SDs), ``above``, ``below`` or ``no paper value``; ``message`` says it in words."""
    if cell is None:
        return {"status": "no paper value", "message": "the paper gives no number for this"}
    delta = mean - cell.mean
    out: dict = {"delta": round(delta, 4)}
    if cell.std is None or cell.std <= 0:
        out.update(status="no paper SD", message=f"{delta:+.3f} from the paper (no SD given)")
        return out
    k = delta / cell.std
    out["delta_sd"] = round(k, 2)
    if abs(k) <= TOLERANCE_SD:
        out.update(status="within", message=f"within {TOLERANCE_SD:g} paper SDs ({k:+.1f} SD)")
    else:
        word = "above" if k > 0 else "below"
        verb = "exceeds" if k > 0 else "misses"
        msg = f"{verb} the paper by {abs(delta):.3f} ({abs(k):.1f} paper SDs)"
        if quick:
            msg += "; quick run (fewer epochs and repeats), not a reproduction"
        if note:
            msg += f". Why: {note}"
        out.update(status=word, message=msg)
    out["goal_met"] = out["status"] in ("within", "above")
    return out


def paper_text(cell: dict | None) -> str:
    """A paper cell (``PaperCell.to_json()``) as ``mean (SD)``, ``mean`` without an SD, or ``-``."""
    if cell is None:
        return "-"
    sd = cell["std"]
    return f"{cell['mean']:.3f}" + ("" if sd is None else f" ({sd:.3f})")


@dataclass
class ResultRow:
    """One row of a task's report: a classifier on a set of channels under a split, its
    accuracy over the repeats, the paper's number and how they compare. ``extra`` holds the
    per-repeat details (accuracies, confusion, accuracy over time, timings); ``part`` the
    part of a suite the row comes from."""

    classifier: str
    label: str
    features: str
    accuracy_mean: float
    accuracy_std: float
    paper: dict | None
    repeats: int
    comparison: dict
    wall_s: float = 0.0
    channels: str = "all"
    split: str = ""
    part: str | None = None
    extra: dict = field(default_factory=dict)

    @property
    def over_time(self) -> dict:
        return self.extra.get("over_time") or {}

    def over_time_curve(self) -> dict[float, list[float]]:
        """Accuracy over time as ``{time [s]: the repeats' accuracies}``."""
        return {float(t): v["accuracies"] for t, v in self.over_time.items()}

    def to_json(self) -> dict:
        d = {k: getattr(self, k) for k in _ROW_KEYS}
        if self.part is not None:
            d["part"] = self.part
        return {**d, **self.extra}

    @classmethod
    def from_json(cls, d: dict) -> ResultRow:
        known = {k: d[k] for k in (*_ROW_KEYS, "part") if k in d}
        return cls(**known, extra={k: x for k, x in d.items() if k not in known})


_ROW_KEYS = (
    "classifier",
    "label",
    "features",
    "accuracy_mean",
    "accuracy_std",
    "paper",
    "repeats",
    "comparison",
    "wall_s",
    "channels",
    "split",
)


@dataclass
class Report:
    """A task's report (``report.json``): its rows and how they were made. A suite's report
    holds its parts' rows, each labelled ``<part>: <row>``, and ``parts`` (part -> its own
    report's path)."""

    task: str
    title: str
    quick: bool
    results: list[ResultRow]
    timing: dict
    figures: list[str]
    protocol: dict
    dataset: dict
    remarks: list[str]
    reference: str
    environment: dict
    parts: dict | None = None

    def to_json(self) -> dict:
        d = {k: getattr(self, k) for k in _REPORT_KEYS}
        d["results"] = [r.to_json() for r in self.results]
        if self.parts is not None:
            d["parts"] = self.parts
        return d

    @classmethod
    def from_json(cls, d: dict) -> Report:
        known = {k: d[k] for k in (*_REPORT_KEYS, "parts") if k in d}
        known["results"] = [ResultRow.from_json(r) for r in d["results"]]
        return cls(**known)

    def write(self, out: Path) -> None:
        """``report.json`` and ``report.md`` into ``out``."""
        (out / "report.json").write_text(json.dumps(self.to_json(), indent=2) + "\n")
        (out / "report.md").write_text(self.markdown())

    def markdown(self) -> str:
        """``report.md``: the table beside the paper's, the protocol, timing and figures."""
        lines = [f"# {self.task}: {self.title}", ""]
        if self.quick:
            lines += [
                "**Quick run**: fewer plates, slides, epochs, repeats and time points than the "
                "paper's protocol; the neural models are not trained to convergence.",
                "",
            ]
        if self.parts is None:
            p, d = self.protocol, self.dataset
            lines += [
                f"Protocol: split {p['split']}, repeats {p['repeats']}, seed {p['seed']}; "
                f"encoding: {p['encoding']}.",
                f"Data: {d['samples']} samples, {d['time_steps']} steps at {d['rate_hz']:g} Hz, "
                f"{d['channels']} channels, {d['classes']} classes.",
                "",
            ]
        head = ["run", "features", "accuracy (SD)", "paper (SD)", "repeats", "vs paper", "wall [s]"]
        lines += markdown_table(head, [_cells(r) for r in self.results])
        lines += ["", _timing(self.timing)]
        lines += _over_time_table(self.results)
        lines += neuromorphic_table(self.results)
        users = [r for r in self.results if r.extra.get("user_method")]
        if users:
            lines += ["", "Your methods (run from your code; their splits are the task's):", ""]
            lines += [f"- `{r.label}`: `{r.extra.get('method', '')}`" for r in users]
        if self.parts is not None:
            lines += ["", "Parts: " + ", ".join(f"[{p}]({p}/report.md)" for p in self.parts)]
        if self.figures:
            lines += ["", "## Figures", ""]
            lines += [f"![{Path(f).stem}]({_relative(f, self.parts)})" for f in self.figures]
        if self.remarks:
            lines += ["", "## Notes", ""] + [f"- {r}" for r in self.remarks]
        if self.reference:
            lines += ["", f"Reference: {self.reference}"]
        return "\n".join(lines) + "\n"

    def text(self) -> str:
        """The report for a terminal: one line a row, the timing and the figures."""
        lines = [f"{self.task}" + (" (quick)" if self.quick else ""), ""]
        rows = [
            [
                r.label,
                f"{r.accuracy_mean:.3f} ({r.accuracy_std:.3f})",
                paper_text(r.paper),
                r.comparison["message"],
            ]
            for r in self.results
        ]
        lines += text_table(["run", "accuracy", "paper", "vs paper"], rows, right=(1, 2))
        lines += ["", _timing(self.timing)]
        lines += [f"figure: {f}" for f in self.figures]
        return "\n".join(lines)


_REPORT_KEYS = (
    "task",
    "title",
    "quick",
    "results",
    "timing",
    "figures",
    "protocol",
    "dataset",
    "remarks",
    "reference",
    "environment",
)


def _cells(r: ResultRow) -> list[str]:
    return [
        r.label,
        r.features,
        f"{r.accuracy_mean:.3f} ({r.accuracy_std:.3f})",
        paper_text(r.paper),
        str(r.repeats),
        r.comparison["message"],
        f"{r.wall_s:.1f}",
    ]


def _timing(t: dict) -> str:
    return (
        f"Timing: simulate {t['simulate_s']:.1f} s, load {t.get('load_s', 0.0):.1f} s, encode "
        f"{t['encode_s']:.1f} s, classify {t['classify_s']:.1f} s, wall {t.get('wall_s', 0.0):.1f} s."
    )


def _over_time_table(rows: list[ResultRow]) -> list[str]:
    curves = [r for r in rows if r.over_time]
    if not curves:
        return []
    pts = sorted({float(t) for r in curves for t in r.over_time})
    body = [
        [r.label]
        + [f"{r.over_time[f'{t:g}']['mean']:.3f}" if f"{t:g}" in r.over_time else "-" for t in pts]
        for r in curves
    ]
    head = ["classifier"] + [f"{t:g} s" for t in pts]
    return ["", "## Accuracy over time", "", *markdown_table(head, body)]


def _relative(figure: str, parts: dict | None) -> str:
    """A figure's path from its report's folder (a suite's figures lie in its parts')."""
    f = Path(figure)
    return f"{f.parent.name}/{f.name}" if parts is not None else f.name


# ------------------------------------------------------------------------------- figures
def _figure(**kw):
    from matplotlib.figure import Figure  # no pyplot: no global state, headless

    return Figure(**kw)


def plot_confusions(results: dict[str, EvalResult], class_names: Sequence[str], out: Path):
    names = list(results)
    cols = min(4, len(names))
    rows = int(np.ceil(len(names) / cols))
    fig = _figure(figsize=(4.2 * cols, 4.0 * rows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    for ax, name in zip(axes, names, strict=False):
        cm = results[name].confusion.astype(float)
        cm = cm / np.maximum(cm.sum(axis=1, keepdims=True), 1)
        ax.imshow(cm, vmin=0, vmax=1, cmap="Blues")
        ax.set_title(f"{name}: {results[name].mean:.3f}")
        ax.set_xlabel("predicted")
        ax.set_ylabel("true")
        ticks = np.arange(len(class_names))
        ax.set_xticks(ticks, [str(c) for c in class_names], rotation=90, fontsize=6)
        ax.set_yticks(ticks, [str(c) for c in class_names], fontsize=6)
    for ax in axes[len(names) :]:
        ax.set_axis_off()
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
    fig = _figure(figsize=(3.2 * cols, 2.4 * rows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False, sharex=True, sharey=True)).ravel()
    t = np.arange(ds.n_time) / ds.rate_hz
    for k, ax in enumerate(axes):
        if k >= n_cls:
            ax.set_axis_off()
            continue
        idx = int(np.flatnonzero(ds.labels == k)[0])
        ax.plot(t, ds.data[idx], lw=0.6)
        ax.set_title(f"{ds.class_names[k]} (sample {idx})", fontsize=8)
        ax.tick_params(labelsize=6)
        if k % cols == 0:
            ax.set_ylabel(ds.units or "output", fontsize=7)
        if k >= (rows - 1) * cols:
            ax.set_xlabel("time [s]", fontsize=7)
    fig.savefig(out, dpi=100)


def plot_plates(plates: Sequence[Plate], class_names: Sequence[str], out: Path):
    """Top view of each plate's surface height (the analytic definition the simulation used)."""
    from ..plates import height_at

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
        z = height_at(p, x[None, :], y[:, None]) * 1e3
        im = ax.imshow(
            z, extent=(-hx * 1e3, hx * 1e3, -hy * 1e3, hy * 1e3), origin="lower", cmap="viridis"
        )
        fig.colorbar(im, ax=ax, shrink=0.8).ax.tick_params(labelsize=5)
        ax.set_title(str(class_names[k]), fontsize=8)
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

    out: list[Plate | None] = []
    for ref, params in zip(setup.get("plates", []), setup.get("plate_params", []), strict=False):
        if params.get("texture", {}).get("kind") != "heightmap":
            out.append(Plate.from_params(params))
            continue
        try:
            plate = get_plate(ref)
        except Exception:  # noqa: BLE001  (the file is gone or no longer loads: no picture)
            plate = None
        out.append(plate if plate is not None and plate.params() == params else None)
    return out
