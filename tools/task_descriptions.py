"""Write every registered task's whole definition to ``tests/data/task_descriptions.json``.

    python tools/task_descriptions.py [--check]

A released task id never changes meaning: ``tests/test_task_registry.py`` compares each
task's :meth:`~sim_tactile.tasks.registry.TaskSpec.describe` with this file. Run the script
when a task is *added* (a new id); a difference in a released id is a new version instead.
``--check`` only compares and exits 1 on a difference.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from sim_tactile.tasks import get_task, task_ids

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "task_descriptions.json"


def descriptions() -> dict:
    return {t: get_task(t).describe() for t in task_ids()}


def write_or_check(out: Path, data: dict, doc: str) -> int:
    """Write ``data`` as sorted JSON to ``out``, or with ``--check`` on the command line
    compare and return 1 on a difference (the shared main of the description tools)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args()
    text = json.dumps(data, indent=1, sort_keys=True) + "\n"
    if args.check:
        same = out.is_file() and out.read_text() == text
        print("same" if same else f"{out} differs")
        return 0 if same else 1
    out.write_text(text)
    print(f"wrote {out} ({len(text)} bytes)", file=sys.stderr)
    return 0


def main() -> int:
    return write_or_check(OUT, descriptions(), __doc__)


if __name__ == "__main__":
    sys.exit(main())
