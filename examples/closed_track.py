"""A classifier of one's own on the task's own encoding: the closed track.

``spike_features_logreg`` returns ``("task", estimator)``: the task's encoder (its spike
trains) feeds the estimator, here the task's spike features, standardised, and a logistic
regression in place of the built-in linear SVM. Only the classifier is the method's, so its
result file stands in the closed track. From the repository's root::

    sim-tactile run finger7-v1 --classifiers none \\
        --method logreg=examples/closed_track.py:spike_features_logreg --out out/logreg
    sim-tactile check out/logreg/results/finger7-v1--logreg.json
"""

from __future__ import annotations

from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler

from sim_tactile.spikes import SpikeFeatures
from sim_tactile.tasks import TASK_ENCODER


def spike_features_logreg():
    """The task's encoding -> mean rate and mean ISI per channel -> scaling -> logistic
    regression."""
    clf = Pipeline(
        [
            ("features", SpikeFeatures(features=("rate_hz", "mean_isi_s"))),
            ("scale", StandardScaler()),
            ("logreg", LogisticRegression(max_iter=2000)),
        ]
    )
    return TASK_ENCODER, clf
