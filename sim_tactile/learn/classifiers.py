"""The registry of classifier names (``sim-tactile run --classifiers``) -> estimators.

Every registered classifier is built for a task's data by :func:`make_classifier` and takes
the task's recordings, arrays ``(samples, time, channels)``, so that the protocols treat all
of them alike (splits, truncation for accuracy over time). Where a classifier needs spike
trains, the task's encoder (a :class:`LearnContext` field) comes first in its pipeline.

==========  ==================================================================================
svm-raw     linear SVM on the raw data collapsed in time (mean per channel; paper 000)
svm-spike   linear SVM on spike counts of the encoding (paper 000: threshold encoding, K = 2)
lstm        :class:`~sim_tactile.learn.lstm.LSTMClassifier` on the raw data
snn         :class:`~sim_tactile.learn.snn.SNNClassifier` on the encoded spike rasters
svm         linear SVM on spike features (papers 002, 003; standardised)
lda         linear discriminant analysis on spike features (paper 003)
knn         k nearest neighbours on spike features (paper 001, SF-kNN)
std-knn     k nearest neighbours on spike-train distances (paper 001, STD-kNN)
src         sparse representation classification on spike features (paper 003)
==========  ==================================================================================

The linear SVMs are scikit-learn's ``SVC(kernel="linear")`` (libsvm, one-vs-one), C = 1.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from sklearn.base import BaseEstimator
from sklearn.discriminant_analysis import LinearDiscriminantAnalysis
from sklearn.neighbors import KNeighborsClassifier
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC

from .._names import did_you_mean
from ..encoders.encodings import Steps, threshold_encoding
from ..errors import ConfigError, UnknownNameError
from ..spikes import SpikeFeatures, SpikeTrainDistances
from .preprocess import SpikeCounts, SpikeRaster, TimeCollapse
from .src import SRCClassifier


@dataclass(frozen=True)
class LearnContext:
    """What the builders need to know about a task's data.

    rate_hz: sampling rate [Hz]; n_channels: input channels; grid_shape: ``(rows, cols)`` of
    spatially arranged taxels (enables the LSTM's convolutional front) or None; encoder:
    ``context -> pipeline steps`` from arrays to ``list[SpikeTrains]``; spike_features: the
    :data:`~sim_tactile.spikes.FEATURES` of svm / lda / knn / src; params: per-classifier
    keyword overrides of the final estimator (e.g. ``{"snn": {"hidden": 1200}}``).
    """

    rate_hz: float
    n_channels: int
    grid_shape: tuple[int, int] | None = None
    encoder: Callable[[LearnContext], Steps] = threshold_encoding
    spike_features: tuple[str, ...] = ("rate_hz", "mean_isi_s")
    params: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

    def kwargs(self, name: str, **defaults: Any) -> dict:
        return {**defaults, **dict(self.params.get(name, {}))}


@dataclass(frozen=True)
class ClassifierSpec:
    """A registered classifier: its name, a description of its input features, its builder
    ``(context, random_state) -> estimator``, whether it reads recordings causally (then
    accuracy over time needs one fit) and whether it needs torch."""

    name: str
    features: str
    build: Callable[[LearnContext, int | None], BaseEstimator]
    anytime: bool = False
    needs_torch: bool = False


def _svm(**kw: Any) -> SVC:
    return SVC(kernel="linear", **{"C": 1.0, **kw})


def _build_svm_raw(ctx: LearnContext, seed: int | None) -> BaseEstimator:
    return Pipeline([("collapse", TimeCollapse()), ("svm", _svm(**ctx.kwargs("svm-raw")))])


def _build_svm_spike(ctx: LearnContext, seed: int | None) -> BaseEstimator:
    steps = ctx.encoder(ctx) + [("counts", SpikeCounts()), ("svm", _svm(**ctx.kwargs("svm-spike")))]
    return Pipeline(steps)


def _build_snn(ctx: LearnContext, seed: int | None) -> BaseEstimator:
    from .snn import SNNClassifier  # torch is imported when it is fitted

    dt = 1.0 / ctx.rate_hz
    snn = SNNClassifier(**ctx.kwargs("snn", dt_s=dt, random_state=seed))
    return Pipeline(ctx.encoder(ctx) + [("raster", SpikeRaster(dt_s=dt)), ("snn", snn)])


def _build_lstm(ctx: LearnContext, seed: int | None) -> BaseEstimator:
    from .lstm import LSTMClassifier

    return LSTMClassifier(**ctx.kwargs("lstm", grid_shape=ctx.grid_shape, random_state=seed))


def _feature_final(name: str, ctx: LearnContext) -> BaseEstimator:
    """The estimator of a feature classifier after the spike features: scaling + model."""
    if name == "svm":
        clf = _svm(**ctx.kwargs("svm"))
    elif name == "lda":
        clf = LinearDiscriminantAnalysis(**ctx.kwargs("lda"))
    elif name == "knn":
        clf = KNeighborsClassifier(**ctx.kwargs("knn", n_neighbors=5))
    elif name == "src":
        # standardised features, then each sample to unit norm (SRCClassifier, paper 003):
        # without centring, samples that differ only in overall rate would look alike
        clf = SRCClassifier(**ctx.kwargs("src", sparsity=5))
    else:
        raise ConfigError(f"{name!r} is not a spike-feature classifier; valid: {FEATURE_MODELS}")
    return Pipeline([("scale", StandardScaler()), ("clf", clf)])


#: classifiers on spike features (their final estimator: :func:`feature_estimator`)
FEATURE_MODELS = ("svm", "lda", "knn", "src")


def feature_estimator(name: str, ctx: LearnContext) -> BaseEstimator:
    """Scaling + model of the spike-feature classifier ``name`` (svm, lda, knn, src), for a
    feature matrix computed beforehand."""
    return _feature_final(name, ctx)


def std_knn_params(ctx: LearnContext) -> tuple[str, dict, str, int]:
    """``(metric, metric params, combine, k)`` of the STD-kNN classifier in ``ctx``."""
    kw = ctx.kwargs("std-knn", metric="victor_purpura", combine="sum", n_neighbors=11)
    metric = kw.pop("metric")
    combine = kw.pop("combine")
    k = kw.pop("n_neighbors")
    if metric in ("victor_purpura", "vp") and "q" not in kw:
        kw["q"] = 24.0  # paper 001's best, 0.024 / ms
    return metric, kw, combine, k


def _feature_pipeline(ctx: LearnContext, name: str) -> BaseEstimator:
    steps = ctx.encoder(ctx) + [("features", SpikeFeatures(features=ctx.spike_features))]
    return Pipeline([*steps, *_feature_final(name, ctx).steps])


def _build_svm(ctx: LearnContext, seed: int | None) -> BaseEstimator:
    return _feature_pipeline(ctx, "svm")


def _build_lda(ctx: LearnContext, seed: int | None) -> BaseEstimator:
    return _feature_pipeline(ctx, "lda")


def _build_knn(ctx: LearnContext, seed: int | None) -> BaseEstimator:
    return _feature_pipeline(ctx, "knn")


def _build_src(ctx: LearnContext, seed: int | None) -> BaseEstimator:
    return _feature_pipeline(ctx, "src")


def _build_std_knn(ctx: LearnContext, seed: int | None) -> BaseEstimator:
    metric, kw, combine, k = std_knn_params(ctx)
    dist = SpikeTrainDistances(metric=metric, metric_params=kw, combine=combine)
    knn = KNeighborsClassifier(n_neighbors=k, metric="precomputed")
    return Pipeline(ctx.encoder(ctx) + [("distances", dist), ("knn", knn)])


_SPECS = (
    ClassifierSpec("svm-raw", "raw data, mean over time per channel", _build_svm_raw),
    ClassifierSpec("svm-spike", "spike counts per encoded channel", _build_svm_spike),
    ClassifierSpec("lstm", "raw data (standardised)", _build_lstm, needs_torch=True),
    ClassifierSpec("snn", "encoded spike rasters", _build_snn, anytime=True, needs_torch=True),
    ClassifierSpec("svm", "spike features (standardised)", _build_svm),
    ClassifierSpec("lda", "spike features (standardised)", _build_lda),
    ClassifierSpec("knn", "spike features (standardised)", _build_knn),
    ClassifierSpec("std-knn", "spike-train distances", _build_std_knn),
    ClassifierSpec("src", "spike features (standardised, unit norm)", _build_src),
)
CLASSIFIERS: Mapping[str, ClassifierSpec] = {s.name: s for s in _SPECS}


def classifier_names() -> tuple[str, ...]:
    """The names of the registered classifiers (:func:`get_classifier` takes them)."""
    return tuple(CLASSIFIERS)


def get_classifier(name: str) -> ClassifierSpec:
    """The registered classifier ``name``; UnknownNameError naming the valid ones."""
    try:
        return CLASSIFIERS[name]
    except KeyError:
        raise UnknownNameError(
            f"classifier {name!r} is not known{did_you_mean(name, CLASSIFIERS)}; valid: "
            f"{', '.join(CLASSIFIERS)}"
        ) from None


def make_classifier(
    name: str, context: LearnContext, random_state: int | None = None
) -> BaseEstimator:
    """A fresh, unfitted estimator ``name`` for data described by ``context``."""
    return get_classifier(name).build(context, random_state)
