"""Spike features and spike-train distances of a whole data set, computed once from the
encoding fitted on all samples (tasks with ``encode_once``: the papers encode offline); each
split then fits its final estimator only."""

from __future__ import annotations

import json
import time

import numpy as np

from ..errors import ConfigError
from ..learn.classifiers import FEATURE_MODELS, LearnContext, feature_estimator, std_knn_params
from ..learn.precomputed import OnDistances, OnFeatures
from ..records import SpikeTrains
from ..spikes import SpikeFeatures
from ..spikes.multichannel import pairwise_multichannel
from .registry import TaskSpec


class Precomputed:
    """Spike features and spike-train distances of the whole data set, computed once from
    the encoding fitted on all samples (tasks with ``encode_once``)."""

    def __init__(self, spec: TaskSpec, ds, encoded) -> None:
        if encoded[0].n_channels != ds.n_channels:
            raise ConfigError(
                f"task {spec.id}: encode_once needs one spike train per input channel, the "
                f"encoder gives {encoded[0].n_channels} for {ds.n_channels}"
            )
        self.encoded = encoded
        self.features = spec.features
        self._feats = SpikeFeatures(features=spec.features).fit_transform(encoded)
        self._dist: dict[str, np.ndarray] = {}
        self.distance_s = 0.0

    @staticmethod
    def handles(name: str) -> bool:
        return name in FEATURE_MODELS or name == "std-knn"

    def describe(self) -> dict:
        return {
            "features": list(self.features),
            "feature_matrix": list(self._feats.shape),
            "distance_matrices": sorted(self._dist),
            "distance_s": round(self.distance_s, 3),
        }

    def estimator(self, name: str, ctx: LearnContext, cols):
        if name in FEATURE_MODELS:
            nf = len(self.features)
            missing = [f for f in ctx.spike_features if f not in self.features]
            if missing:
                raise ConfigError(
                    f"spike features {missing} are not among the task's precomputed features "
                    f"{list(self.features)}"
                )
            which = [self.features.index(f) for f in ctx.spike_features]
            chans = range(self.encoded[0].n_channels) if cols is None else cols
            sel = [c * nf + j for c in chans for j in which]
            return OnFeatures(feature_estimator(name, ctx), self._feats[:, sel])
        metric, params, combine, k = std_knn_params(ctx)
        key = json.dumps([metric, params, combine, cols], sort_keys=True)
        if key not in self._dist:
            t0 = time.perf_counter()
            trains = self.encoded
            if cols is not None:
                trains = [
                    SpikeTrains(
                        tuple(s.times[c] for c in cols),
                        s.t_start,
                        s.t_end,
                        tuple(s.channel_names[c] for c in cols),
                    )
                    for s in self.encoded
                ]
            self._dist[key] = pairwise_multichannel(trains, metric, combine=combine, **params)
            self.distance_s += time.perf_counter() - t0
        return OnDistances(self._dist[key], n_neighbors=k)
