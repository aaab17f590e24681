"""Classifiers and evaluation protocols: the classifier registry (:mod:`.classifiers`), the
spiking network and the LSTM (torch, imported when they are fitted), sparse representation
classification, estimators on precomputed features and distances, and the repeated splits
and accuracy over time of the papers' protocols (:mod:`.protocols`); the spiking network as a
NIR graph (:mod:`.nir`) and NeuroBench's figures of it (:mod:`.neurobench`)."""

from __future__ import annotations

from .._lazy import lazy_exports

#: The public names and the module that defines each (loaded on first use: torch, Tonic and
#: the data hubs' libraries only when a name that needs them is read).
_EXPORTS = {
    "get_classifier": ".classifiers",
    "classifier_names": ".classifiers",
    "make_classifier": ".classifiers",
    "ClassifierSpec": ".classifiers",
    "SplitSpec": ".protocols",
    "repeated_splits": ".protocols",
    "evaluate": ".protocols",
    "EvalResult": ".protocols",
    "SpikeRaster": ".preprocess",
    "SNNClassifier": ".snn",
    "LSTMClassifier": ".lstm",
    "SRCClassifier": ".src",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
