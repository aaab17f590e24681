"""The leaderboard: a folder of result files (``leaderboard/`` at the repository's root), each
one checked (:mod:`.check`), shown as one table per task version and track.

A table ranks its entries by mean accuracy (then by the lower end of the interval), with the
95% interval, the SD and the repeats, the efficiency figures (time to fit and to predict per
repeat; for spiking rows NeuroBench's parameters, synaptic operations and activation
sparsity), the method's version and the package version, commit and machine that made the
entry. Only rows of one split are ranked together (a table per split where a task's rows
differ in it). The papers' numbers (``reported`` entries) head their task's closed table, unranked:
they were measured on the papers' own hardware, not re-run here. An entry is a full run
(``--quick`` files are refused: their protocol is a smoke test's).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from ..errors import ConfigError
from ..tables import markdown_table
from .check import check_file
from .intervals import interval_text
from .registry import get_task, latest, suite, task_ids


@dataclass(frozen=True)
class Entry:
    """One result file of the leaderboard: its path and its document."""

    path: Path
    doc: dict

    @property
    def config(self) -> dict:
        return self.doc["config"]

    @property
    def metrics(self) -> dict:
        return self.doc["results"][self.config["task"]]

    @property
    def reported(self) -> bool:
        return self.config["reported"] is True


def entry_refusals(path: Path) -> list[str]:
    """What keeps the file at ``path`` off the leaderboard: ``check``'s refusals, and a
    quick run's mode."""
    out = check_file(path)
    if not out:
        doc = json.loads(path.read_text())
        if doc["config"]["protocol"].get("mode") != "full":
            out.append("a leaderboard entry is a full run (not --quick)")
    return out


def load_entries(folder: str | Path) -> list[Entry]:
    """Every ``*.json`` in ``folder``, checked; one refused file is an error that lists
    every refusal, one line each."""
    folder = Path(folder)
    files = sorted(folder.glob("*.json"))
    faults = [f"{p.name}: {line}" for p in files for line in entry_refusals(p)]
    if faults:
        raise ConfigError(
            f"{len(faults)} refusal(s) in the leaderboard {folder}: " + " | ".join(faults)
        )
    return [Entry(p, json.loads(p.read_text())) for p in files]


def _ranked(entries: list[Entry]) -> list[Entry]:
    def key(e: Entry):
        ci = e.metrics.get("accuracy_ci95") or [e.metrics["accuracy"]]
        return (-float(e.metrics["accuracy"]), -float(ci[0]), e.config["model_name"])

    return sorted(entries, key=key)


def _seconds(m: dict, name: str) -> str:
    v = m.get(name)
    return "-" if v is None else f"{v:.3g}"


def neurobench_text(m: dict) -> str:
    """A row's NeuroBench figures in a cell: the spiking model's parameters, effective
    accumulates per sample and activation sparsity, and the encoder's spikes per second."""
    nb = m.get("neurobench") or {}
    ops = nb.get("synaptic_operations") or {}
    parts = []
    if nb.get("parameter_count") is not None:
        parts.append(f"{nb['parameter_count']} parameters")
    if ops.get("effective_acs") is not None:
        parts.append(f"{ops['effective_acs']:.3g} ACs/sample")
    if nb.get("activation_sparsity") is not None:
        parts.append(f"activation sparsity {nb['activation_sparsity']:.3f}")
    if (nb.get("encoder") or {}).get("spikes_per_s") is not None:
        parts.append(f"encoder {nb['encoder']['spikes_per_s']:.4g} spikes/s")
    return ", ".join(parts) or "-"


def _row(rank: str, e: Entry) -> list[str]:
    m, cfg = e.metrics, e.config
    method = cfg["method"]
    name = method["name"] + (f" ([link]({method['link']}))" if method.get("link") else "")
    if cfg.get("variant"):  # an open entry on a definition of its own: its first clause
        name += f" ({cfg['variant'].split(':')[0].rstrip('.')})"
    sd = m.get("accuracy_sd")
    if e.reported:
        made = "the paper's hardware (reported, not re-run)"
    else:
        env = cfg.get("environment") or {}
        made = (
            f"sim_tactile {env.get('sim_tactile')} `{env.get('commit') or '-'}`, "
            f"{env.get('cores')} cores, {env.get('cpu')}"
        )
    return [
        rank,
        name,
        f"{m['accuracy']:.4f}",
        interval_text(m.get("accuracy_ci95"), 4),
        "-" if sd is None else f"{sd:.4f}",
        str(cfg["protocol"].get("repeats", "-")),
        f"{_seconds(m, 'fit_s')} / {_seconds(m, 'predict_s')}",
        neurobench_text(m),
        str(method.get("version") or "-"),
        made,
    ]


HEAD = [
    "rank",
    "method",
    "accuracy",
    "95% interval",
    "SD",
    "repeats",
    "fit / predict [s]",
    "NeuroBench",
    "method version",
    "made with",
]


def table(entries: list[Entry]) -> list[str]:
    """One task version's table of one track: the reported entries, then the rest ranked."""
    reported = _ranked([e for e in entries if e.reported])
    ranked = _ranked([e for e in entries if not e.reported])
    rows = [_row("reported", e) for e in reported]
    rows += [_row(str(i + 1), e) for i, e in enumerate(ranked)]
    return markdown_table(HEAD, rows)


def groups(entries: list[Entry]) -> dict[tuple[str, str, str], list[Entry]]:
    """Entries by (task, track, split): only rows of one split compare (roughness8-v1's
    rows split 5:5, 7:3 and 9:1), in the registry's order of the tasks, closed first."""
    out: dict[tuple[str, str, str], list[Entry]] = {}
    for e in entries:
        key = (e.config["task"], e.config["track"], str(e.config["protocol"]["split"]))
        out.setdefault(key, []).append(e)

    order = {t: i for i, t in enumerate(task_ids())}

    def key(k):
        return (order.get(k[0], len(order)), k[1] != "closed", k[2])

    return {k: out[k] for k in sorted(out, key=key)}


def page(folder: str | Path) -> str:
    """The leaderboard's page (Markdown) from the entries in ``folder``."""
    entries = load_entries(folder)
    core = set(suite("core-v1"))
    lines = [
        "# Leaderboard",
        "",
        "Generated by the docs build from the result files in `leaderboard/` at the "
        "repository's root, each checked by `sim-tactile check` (the test suite checks "
        "them too). One table per task version and track; the *closed* track runs the "
        "task's own data, encoder and protocol with only the classifier the method's, the "
        "*open* track anything else. Ranked by mean accuracy over the repeats; the 95% "
        "interval is the percentile bootstrap of that mean. The papers' numbers head their "
        "tables as *reported*: measured on the papers' hardware, not re-run here. The times "
        "are the mean seconds per repeat to fit and to predict, on the machine each row "
        "names; NeuroBench's figures are the spiking rows'. Only rows of one split are "
        "ranked together. To add an entry, see "
        "[submit a result](../how-to/submit-a-result.md).",
        "",
    ]
    for (task, track, split), group in groups(entries).items():
        spec = get_task(task)
        notes = []
        if task in core:
            notes.append("in the suite core-v1")
        if latest(task) != task:
            notes.append(f"superseded by `{latest(task)}`")
        lines += [f"## `{task}`, {track} track, split {split}", ""]
        lines += [f"{spec.title}" + (f" ({'; '.join(notes)})" if notes else "") + ".", ""]
        lines += table(group)
        lines.append("")
    return "\n".join(lines)
