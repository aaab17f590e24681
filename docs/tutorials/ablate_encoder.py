"""Tutorial: ablate a neuron parameter of a task's encoder over its cached slides.

python docs/tutorials/ablate_encoder.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

from sim_tactile.tasks import get_task
from sim_tactile.tasks.ablate import PARAM_HELP, ablate, used_params


def main(out: Path, quick: bool = True) -> dict:
    spec = get_task("finger7-v1")
    for name in sorted(used_params(spec)):  # what this task lets you sweep
        print(f"{name:>12s}: {PARAM_HELP[name]}")
    # the SA Izhikevich neurons' input gain, and the preset (SA = RS, RA = FS)
    sets = {"gain": [5.0, 15.0] if quick else [5.0, 15.0, 50.0], "preset": ["RS", "FS"]}
    report = ablate("finger7-v1", sets, out, quick=quick, classifiers="svm", repeats=2)
    for row in report["rows"]:
        print(row["params"], row["label"], f"{row['accuracy_mean']:.3f}")
    return report


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
