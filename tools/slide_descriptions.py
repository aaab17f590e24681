"""Write the content hash of every slide description of every simulated task's quick and
full run, task by task, to ``tests/data/slide_descriptions.json``.

    python tools/slide_descriptions.py [--check]

A slide's description (:meth:`~sim_tactile.sim.plan.slide.Slide.describe`) is what its cache
key is made from: a refactor of how a slide is described must leave every one unchanged,
and ``tests/test_slides.py`` compares them with this file. Run the script when a task is
*added*; a difference in a released task's slides is a new version instead. ``--check`` only
compares and exits 1 on a difference.
"""

from __future__ import annotations

import sys
from pathlib import Path

from sim_tactile.hashing import content_hash
from sim_tactile.slides import SlideSet
from sim_tactile.tasks import get_task, task_ids

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "slide_descriptions.json"


def descriptions() -> dict:
    """Per simulated task: the hash of the list of its quick run's slide descriptions, and
    of its full run's."""
    out = {}
    for t in task_ids():
        ss = get_task(t).get_data
        if not isinstance(ss, SlideSet):
            continue
        out[t] = {
            run: content_hash([j.describe() for j in ss.jobs(seed=0, quick=quick)])
            for run, quick in (("quick", True), ("full", False))
        }
    return out


def main() -> int:
    sys.path.insert(0, str(Path(__file__).parent))
    from task_descriptions import write_or_check

    return write_or_check(OUT, descriptions(), __doc__)


if __name__ == "__main__":
    sys.exit(main())
