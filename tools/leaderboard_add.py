"""Add entries to the leaderboard (``leaderboard/`` at the repository's root).

    python tools/leaderboard_add.py OUT/results/TASK--METHOD.json ...
    python tools/leaderboard_add.py --reported TASK ...

The first form copies result files written by ``sim-tactile run`` or ``tasks.evaluate``
(full runs; each is checked first) as ``leaderboard/<task>--<method>.json`` (an open-track
file of a built-in row, on a definition of its own such as a calibrated sensor, as
``<task>--<method>--open.json``); a file there already is not replaced. The second
writes the papers' numbers that ``TASK`` registers, as entries marked ``reported`` (not
re-run), ``leaderboard/<task>--paper-<row>.json``. A contributor's pull request adds one
file instead (docs/how-to/submit-a-result.md); the maintainers use this for the built-in
baselines.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path

from sim_tactile.tasks.leaderboard import entry_refusals
from sim_tactile.tasks.result_file import dumps, reported_documents, slug

BOARD = Path(__file__).resolve().parents[1] / "leaderboard"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", type=Path, help="result files to copy in")
    ap.add_argument("--reported", nargs="*", default=[], metavar="TASK")
    args = ap.parse_args()
    BOARD.mkdir(exist_ok=True)
    bad = 0
    for path in args.files:
        refusals = entry_refusals(path)
        for line in refusals:
            print(f"{path}: {line}", file=sys.stderr)
        if refusals:
            bad += 1
            continue
        cfg = json.loads(path.read_text())["config"]
        own = "--open" if cfg["method"]["builtin"] and cfg["track"] == "open" else ""
        dest = BOARD / f"{cfg['task']}--{slug(cfg['model_name'])}{own}.json"
        if dest.exists() and dest.read_bytes() != path.read_bytes():
            print(f"{path}: {dest} exists already (remove it first to replace it)", file=sys.stderr)
            bad += 1
            continue
        shutil.copyfile(path, dest)
        print(dest)
    for task in args.reported:
        for doc in reported_documents(task):
            row = doc["config"]["method"]["row"]
            dest = BOARD / f"{task}--paper-{slug(row)}.json"
            dest.write_text(dumps(doc))
            print(dest)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
