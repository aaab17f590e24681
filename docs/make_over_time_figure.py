"""Accuracy over time of a task from one or more of its reports (runs of different
classifiers of the same task and seed), drawn as ``sim-tactile run`` draws it.

    python docs/make_over_time_figure.py OUT.png REPORT.json [REPORT.json ...]

The README's figures: the SVM and the network runs of ``biotac20-real-v1`` and
``icub20-real-v1`` (the commands in its task table).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from sim_tactile.tasks.figures import plot_over_time
from sim_tactile.tasks.registry import PaperCell
from sim_tactile.tasks.report import Report


def main(out: str, *reports: str) -> None:
    docs = [Report.from_json(json.loads(Path(r).read_text())) for r in reports]
    if len({d.task for d in docs}) != 1:
        raise SystemExit("the reports are of different tasks")
    rows = [row for d in docs for row in d.results if row.over_time]
    curves = {row.label: row.over_time_curve() for row in rows}
    papers = {row.label: PaperCell(**row.paper) if row.paper else None for row in rows}
    plot_over_time(curves, papers, docs[0].task, Path(out))
    print(out)


if __name__ == "__main__":
    main(*sys.argv[1:])
