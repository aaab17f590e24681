"""NeuroBench's figures of a spiking model, and the spike rate of an encoder.

NeuroBench (``neurobench``) computes its metrics with forward hooks on a model's
``torch.nn.Linear`` / ``Conv`` layers and snnTorch neurons, run step by step. The package's
SRM network (:class:`~sim_tactile.learn.snn.SNNClassifier`) filters its input before the
first weights and convolves whole rasters, so NeuroBench cannot hook it; :func:`layer_metrics`
computes the same figures, by NeuroBench's definitions, from the layers' weights, inputs and
outputs (the tests compare it with ``neurobench.benchmarks.Benchmark`` on an snnTorch model
with the same weights):

- ``footprint_bytes``: the bytes of the parameters and buffers (NeuroBench's ``Footprint``);
- ``parameter_count``: the number of parameters (``ParameterCount``);
- ``connection_sparsity``: the fraction of zero weights (``ConnectionSparsity``);
- ``activation_sparsity``: the fraction of zero neuron outputs, over every spiking layer,
  step and sample (``ActivationSparsity``);
- ``synaptic_operations``: per sample, ``effective_acs`` (each non-zero input of a layer at a
  step costs one accumulate per non-zero weight it fans out to: spiking inputs),
  ``effective_macs`` (the same for non-binary inputs: multiply-accumulates) and ``dense``
  (every input times every weight, every step) (``SynapticOperations``).

:func:`encoder_rate` gives an encoder's spikes per second of input, summed over its channels:
what a neuromorphic chip would pay to receive the encoding.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import ConfigError
from ..records import SpikeTrains


def _spiking(x: np.ndarray) -> bool:
    """NeuroBench's test of a spiking input: every value is 0, 1 or -1."""
    return bool(np.isin(x, (-1.0, 0.0, 1.0)).all())


def layer_metrics(
    weights: Sequence[np.ndarray],
    inputs: Sequence[np.ndarray],
    activations: Sequence[np.ndarray],
    *,
    buffer_bytes: int = 0,
) -> dict:
    """NeuroBench's figures from a feed-forward model's layers.

    weights: each layer's ``(out, in)`` weight matrix; inputs: each layer's input
    ``(samples, steps, in)``; activations: each spiking layer's output ``(samples, steps,
    n)``; buffer_bytes: the model's other stored state (NeuroBench counts buffers in the
    footprint)."""
    if len(weights) != len(inputs):
        raise ConfigError(f"{len(weights)} weight matrices for {len(inputs)} layer inputs")
    n_samples = int(inputs[0].shape[0]) if inputs else 0
    if n_samples == 0:
        raise ConfigError("layer_metrics needs at least one sample")
    acs = macs = dense = 0.0
    for w, x in zip(weights, inputs, strict=True):
        w, x = np.asarray(w), np.asarray(x)
        if x.shape[-1] != w.shape[1]:
            raise ConfigError(f"a layer input of {x.shape[-1]} features meets weights {w.shape}")
        fan_out = (w != 0).sum(axis=0).astype(np.float64)  # non-zero weights per input
        ops = float(((x != 0).reshape(-1, x.shape[-1]) @ fan_out).sum())
        if _spiking(x):
            acs += ops
        else:
            macs += ops
        dense += float(x.shape[0] * x.shape[1] * w.size)
    zeros = sum(int((np.asarray(w) == 0).sum()) for w in weights)
    size = sum(int(np.asarray(w).size) for w in weights)
    fired = sum(int(np.count_nonzero(a)) for a in activations)
    cells = sum(int(np.asarray(a).size) for a in activations)
    return {
        "footprint_bytes": int(sum(np.asarray(w).nbytes for w in weights) + buffer_bytes),
        "parameter_count": size,
        "connection_sparsity": zeros / size,
        "activation_sparsity": (cells - fired) / cells if cells else 0.0,
        "synaptic_operations": {
            "effective_acs": acs / n_samples,
            "effective_macs": macs / n_samples,
            "dense": dense / n_samples,
        },
    }


def snn_metrics(clf: Any, X: object) -> dict:
    """NeuroBench's figures of a fitted :class:`~sim_tactile.learn.snn.SNNClassifier` on the
    rasters ``X`` ``(samples, steps, channels)``: its two weight layers take the input raster
    and the hidden spikes; its hidden and output neurons are the spiking layers; its buffer
    is the alpha kernel. Also ``spikes_per_sample`` (hidden and output neurons)."""
    from ._torch import import_torch

    torch = import_torch()
    module = getattr(clf, "module_", None)
    if module is None:
        raise ConfigError("the SNNClassifier is not fitted; call fit first")
    x = clf._check_X(X, fitted=True)
    dev = next(module.parameters()).device
    with torch.no_grad():
        s1, s2, _ = module.layers(clf._prepare(torch, x, dev))
    hidden = s1.cpu().numpy().transpose(0, 2, 1)
    out = s2.cpu().numpy().transpose(0, 2, 1)
    weights = [p.detach().cpu().numpy() for p in (module.fc1.weight, module.fc2.weight)]
    buffers = sum(b.numel() * b.element_size() for b in module.buffers())
    figs = layer_metrics(weights, [x, hidden], [hidden, out], buffer_bytes=int(buffers))
    figs["spikes_per_sample"] = float((hidden.sum() + out.sum()) / x.shape[0])
    return figs


def encoder_rate(trains: Sequence[SpikeTrains]) -> dict:
    """Spikes per second of input of an encoding (summed over its channels), and per channel
    (``trains``: one SpikeTrains per sample)."""
    trains = list(trains)
    if not trains:
        raise ConfigError("encoder_rate needs at least one sample")
    spikes = float(sum(int(s.counts().sum()) for s in trains))
    seconds = float(sum(s.duration_s for s in trains))
    return {
        "spikes_per_s": spikes / seconds,
        "spikes_per_s_per_channel": spikes / seconds / trains[0].n_channels,
        "channels": int(trains[0].n_channels),
    }


def neuromorphic_figures(est: Any, x_test: np.ndarray) -> dict | None:
    """What a report row carries of a fitted estimator on its test samples: the encoder's
    spike rate (where a Pipeline's steps give spike trains) and the model's NeuroBench
    figures (where its last step has ``neuromorphic_metrics``); None where neither."""
    steps = [s for _, s in est.steps] if hasattr(est, "steps") else [est]
    final = steps[-1]
    has_metrics = callable(getattr(final, "neuromorphic_metrics", None))
    out: dict = {}
    z = x_test
    for step in steps[:-1]:
        z = step.transform(z)
        if isinstance(z, list) and z and isinstance(z[0], SpikeTrains):
            out["encoder"] = encoder_rate(z)
            if not has_metrics:
                break
    if has_metrics:
        out.update(final.neuromorphic_metrics(z))
    return out or None
