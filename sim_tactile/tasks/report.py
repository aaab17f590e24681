"""The task report: comparison with the paper and the typed report (:class:`Report`, one
Markdown and one text renderer); its figures are in :mod:`.figures`."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from ..tables import markdown_table, text_table
from .intervals import MIN_REPEATS, interval_text
from .registry import PaperCell
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
    accuracy over the repeats (its mean, SD and 95% interval, :mod:`.intervals`; None below
    :data:`~.intervals.MIN_REPEATS` repeats), the paper's number and how they compare.
    ``extra`` holds the per-repeat details (accuracies, confusion, accuracy over time,
    timings); ``part`` the part of a suite the row comes from."""

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
    accuracy_ci95: list[float] | None = None

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
    "accuracy_ci95",
)


@dataclass
class Report:
    """A task's report (``report.json``): its rows and how they were made. A suite's report
    holds its parts' rows, each labelled ``<part>: <row>``, and ``parts`` (part -> its own
    report's path). ``result_files``: the result file of each row (:mod:`.result_file`)."""

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
    result_files: list[str] | None = None

    def to_json(self) -> dict:
        d = {k: getattr(self, k) for k in _REPORT_KEYS}
        d["results"] = [r.to_json() for r in self.results]
        for k in _OPTIONAL_KEYS:
            if getattr(self, k) is not None:
                d[k] = getattr(self, k)
        return d

    @classmethod
    def from_json(cls, d: dict) -> Report:
        known = {k: d[k] for k in (*_REPORT_KEYS, *_OPTIONAL_KEYS) if k in d}
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
                "paper's protocol; the neural models are not trained to convergence. "
                + self.quick_counts(),
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
        head = ["run", "features", "accuracy (SD)", "95% interval", "paper (SD)", "repeats"]
        head += ["vs paper", "wall [s]"]
        lines += markdown_table(head, [_cells(r) for r in self.results])
        lines += _flag_lines(self.results, "- ")
        lines += ["", INTERVAL_NOTE, "", _timing(self.timing)]
        lines += _over_time_table(self.results)
        lines += neuromorphic_table(self.results)
        users = [r for r in self.results if r.extra.get("user_method")]
        if users:
            lines += ["", "Your methods (run from your code; their splits are the task's):", ""]
            lines += [f"- `{r.label}`: `{r.extra.get('method', '')}`" for r in users]
        if self.parts is not None:
            lines += ["", "Parts: " + ", ".join(f"[{p}]({p}/report.md)" for p in self.parts)]
        if self.result_files:
            lines += ["", "Result files (one per row; `sim-tactile check FILE` validates one):", ""]
            lines += [f"- `{_relative(f, self.parts)}`" for f in self.result_files]
        if self.figures:
            lines += ["", "## Figures", ""]
            lines += [f"![{Path(f).stem}]({_relative(f, self.parts)})" for f in self.figures]
        if self.remarks:
            notes = "## Notes" + (" (on the full protocol)" if self.quick else "")
            lines += ["", notes, ""] + [f"- {r}" for r in self.remarks]
        if self.reference:
            lines += ["", f"Reference: {self.reference}"]
        return "\n".join(lines) + "\n"

    def text(self) -> str:
        """The report for a terminal: one line a row, the timing and the figures."""
        lines = [f"{self.task}" + (" (quick)" if self.quick else "")]
        lines += [self.quick_counts(), ""] if self.quick else [""]
        rows = [
            [
                _marked(r),
                f"{r.accuracy_mean:.3f} ({r.accuracy_std:.3f})",
                interval_text(r.accuracy_ci95),
                paper_text(r.paper),
                r.comparison["message"],
            ]
            for r in self.results
        ]
        head = ["run", "accuracy (SD)", "95% interval", "paper", "vs paper"]
        lines += text_table(head, rows, right=(1, 2, 3))
        lines += _flag_lines(self.results, "")
        lines += [INTERVAL_NOTE]
        lines += ["", _timing(self.timing)]
        lines += [f"figure: {f}" for f in self.figures]
        return "\n".join(lines)

    def quick_counts(self) -> str:
        """What a quick run ran (the title and the notes describe the full protocol): its
        slides per class, its split and each row's repeats."""
        if self.parts is not None:
            return "Each part's report gives its quick counts."
        d, p = self.dataset, self.protocol
        per = sorted(set(d.get("per_class") or []))
        each = f"{per[0]} per class" if len(per) == 1 else "per class " + "-".join(map(str, per))
        reps = ", ".join(f"{k} {n}" for k, n in (p.get("repeats") or {}).items())
        return (
            f"This run: {d['samples']} slides ({d['classes']} classes, {each}), split "
            f"{p['split']}, repeats: {reps}. The title and the notes describe the full protocol."
        )


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
_OPTIONAL_KEYS = ("parts", "result_files")
#: What the interval column is, under each table of a report.
INTERVAL_NOTE = (
    "95% interval: of the mean over the repeats (percentile bootstrap); '-' below "
    f"{MIN_REPEATS} repeats."
)


def _marked(r: ResultRow) -> str:
    """A row's label, led by ``!`` where :mod:`.flags` found it doubtful."""
    return f"! {r.label}" if r.extra.get("flags") else r.label


def _flag_lines(rows: list[ResultRow], lead: str) -> list[str]:
    """Under the table: why each row marked ``!`` is doubtful ([] when none is)."""
    said = [f"{lead}! {r.label}: {f}" for r in rows for f in r.extra.get("flags") or []]
    return ["", "Check the rows marked !:", *said] if said else []


def _cells(r: ResultRow) -> list[str]:
    return [
        _marked(r),
        r.features,
        f"{r.accuracy_mean:.3f} ({r.accuracy_std:.3f})",
        interval_text(r.accuracy_ci95),
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
