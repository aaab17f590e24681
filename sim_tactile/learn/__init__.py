"""Classifiers and evaluation protocols: the classifier registry (:mod:`.classifiers`), the
spiking network and the LSTM (torch, imported when they are fitted), sparse representation
classification, estimators on precomputed features and distances, and the repeated splits
and accuracy over time of the papers' protocols (:mod:`.protocols`); the spiking network as a
NIR graph (:mod:`.nir`) and NeuroBench's figures of it (:mod:`.neurobench`)."""
