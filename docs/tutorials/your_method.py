"""Tutorial: your method on a task, scored under the task's own protocol.

python docs/tutorials/your_method.py OUT_DIR [--full]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import FunctionTransformer, StandardScaler
from sklearn.svm import LinearSVC

import sim_tactile.tasks as tasks


def mean_and_spread(X: np.ndarray) -> np.ndarray:
    """(slides, time, taxels) -> (slides, 2 x taxels): each taxel's mean and SD in time."""
    return np.concatenate([X.mean(axis=1), X.std(axis=1)], axis=1)


def main(out: Path, quick: bool = True) -> dict:
    # 1. the task's data and protocol, for your own framework
    data = tasks.load("finger7-v1", quick=quick)
    print(data.X.shape, data.class_names, data.rate_hz)
    train, test = next(iter(data.splits()))  # the task's first split
    print(f"first split: {len(train)} slides to train on, {len(test)} to test on")

    # 2. your method: any scikit-learn estimator on the raw (slides, time, taxels) array
    mine = make_pipeline(FunctionTransformer(mean_and_spread), StandardScaler(), LinearSVC())

    # 3. scored beside the built-in rows and the paper, into the task's report
    report = tasks.evaluate("finger7-v1", {"mine": mine}, quick=quick, out=out)
    for row in report["results"]:
        print(f"{row['classifier']:>12s} {row['accuracy_mean']:.3f}")
    return report


if __name__ == "__main__":
    main(Path(sys.argv[1]), quick="--full" not in sys.argv)
