"""The spiking network and the LIF encoder as NIR graphs (the Neuromorphic Intermediate
Representation, ``nir``), which snnTorch, Norse, Lava, Rockpool, Sinabs, Spyx and SpiNNaker2
read.

**The SNN** (:class:`~sim_tactile.learn.snn.SNNClassifier`, two layers of SRM neurons) becomes
``input -> fc1 (Linear) -> hidden (CubaLIF) -> fc2 (Linear) -> output (CubaLIF)``:

- *synapse, exact*: the SRM's alpha kernel ``eps(t) = (t / tau) exp(1 - t / tau)`` is the
  impulse response of a CubaLIF whose synaptic and membrane time constants are both
  ``tau = tau_sr_s``, with ``r * w_in = e * tau`` (continuous time); ``v_leak = 0`` and the
  threshold is ``theta``. Spikes enter a discrete simulator as one-step pulses of height 1
  (the raster's convention), so ``w_in`` carries ``1 / dt_s``: ``w_in = e * tau_sr_s / dt_s``,
  ``r = 1``.
- *refractoriness, approximate*: the SRM does not reset its potential; a spike adds the
  refractory kernel ``-scale_ref * theta * (t / tau_ref) exp(1 - t / tau_ref)``. NIR's
  neurons reset the membrane to ``v_reset = 0`` instead (the synaptic current goes on). A
  strongly driven SRM neuron therefore fires again sooner than the CubaLIF.
- *time step, the consumer's*: a simulator that integrates the graph with forward Euler at
  ``dt_s`` (Norse) has the decay ``1 - dt / tau`` per step for ``exp(-dt / tau)``, and its
  cascade of two filters answers one step earlier than the SRM's kernel, which is zero at
  ``t = 0``.

:func:`alpha_kernel_mismatch` measures the synapse's part; :func:`agreement` runs the graph in
Norse (a NIR consumer written elsewhere) and compares its decisions and output counts with the
package's network. snnTorch's importer is not a fit: it assumes a step of 0.1 ms and
``r = tau_mem / 0.1 ms`` for every CubaLIF.

**The LIF encoder** (:class:`~sim_tactile.encoders.LIFEncoder`) becomes ``input -> Affine
(its normalisation and gain: diag(scale * gain), -offset * scale * gain) -> LIF (tau_m_s,
r = 1, v_leak = v_rest, v_threshold = v_th, v_reset)``. NIR has no refractory period and no
threshold adaptation: an encoder with ``refractory_s > 0`` or ``beta > 0`` is refused.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError, MissingDependencyError, require

#: The graph's node names, in order.
SNN_NODES = ("input", "fc1", "hidden", "fc2", "output_neurons", "output")
#: How to install Norse, the NIR consumer :func:`norse_run` uses (it declares torchvision,
#: which the pinned torch has no wheel for: install it without its declared dependencies).
NORSE_INSTALL = "pip install 'sim-tactile[nir]' nirtorch && pip install --no-deps norse"


def _nir():
    return require("nir", "nir")


def _cuba(nir, n: int, tau_s: float, theta: float, w_in: float):
    one = np.ones(n)
    return nir.CubaLIF(
        tau_syn=tau_s * one,
        tau_mem=tau_s * one,
        r=one.copy(),
        v_leak=0.0 * one,
        v_threshold=theta * one,
        v_reset=0.0 * one,
        w_in=w_in * one,
    )


def snn_to_nir(clf: Any, class_names: Sequence[str] | None = None):
    """The fitted SNNClassifier ``clf`` as a ``nir.NIRGraph`` (see the module docstring);
    its input is the raster ``(channels,)`` per step, its output the class neurons' spikes.
    The metadata's ``classes`` name the output neurons in order: ``class_names[label]``
    where the labels index ``class_names`` (a task's plates), else the labels as text (the
    nir library reads a list of strings back as bytes)."""
    nir = _nir()
    module = getattr(clf, "module_", None)
    if module is None:
        raise ConfigError("the SNNClassifier is not fitted; call fit before exporting it")
    w1 = module.fc1.weight.detach().cpu().numpy().astype(np.float32)
    w2 = module.fc2.weight.detach().cpu().numpy().astype(np.float32)
    tau, dt, theta = float(clf.tau_sr_s), float(clf.dt_s), float(clf.theta)
    w_in = math.e * tau / dt
    nodes = dict(
        zip(
            SNN_NODES,
            (
                nir.Input(input_type={"input": np.array([w1.shape[1]])}),
                nir.Linear(weight=w1),
                _cuba(nir, w1.shape[0], tau, theta, w_in),
                nir.Linear(weight=w2),
                _cuba(nir, w2.shape[0], tau, theta, w_in),
                nir.Output(output_type={"output": np.array([w2.shape[0]])}),
            ),
            strict=True,
        )
    )
    edges = list(zip(SNN_NODES[:-1], SNN_NODES[1:], strict=True))
    return nir.NIRGraph(nodes=nodes, edges=edges, metadata=_snn_metadata(clf, class_names))


def _class_names(labels: np.ndarray, names: Sequence[str] | None) -> list[str]:
    if names is None:
        return [str(c) for c in labels]
    names = [str(n) for n in names]
    idx = [int(c) for c in labels]
    if any(c != i or not 0 <= i < len(names) for c, i in zip(labels, idx, strict=True)):
        raise ConfigError(
            f"the network's labels {list(labels)} do not index class_names ({len(names)}); "
            "valid: labels 0 .. len(class_names) - 1"
        )
    return [names[i] for i in idx]


def _snn_metadata(clf: Any, class_names: Sequence[str] | None = None) -> dict:
    return {
        "source": "sim_tactile SNNClassifier (SRM neurons, seed paper 000)",
        "dt_s": float(clf.dt_s),
        "input": "one-step pulses of height 1 per input spike, at dt_s",
        "classes": _class_names(clf.classes_, class_names),
        "approximation": "SRM refractory kernel -> reset to v_reset = 0; see sim_tactile.learn.nir",
    }


def lif_encoder_to_nir(encoder: Any):
    """A fitted :class:`~sim_tactile.encoders.LIFEncoder` as a ``nir.NIRGraph``: an Affine
    node (normalisation and gain) and a LIF node per channel. Its input is the sensor signal
    (the encoder's ``X``) per time step, held between samples."""
    nir = _nir()
    p = getattr(encoder, "params_", None)
    if p is None:
        raise ConfigError("the LIFEncoder is not fitted; call fit before exporting it")
    for name, value in (("refractory_s", p.refractory_s), ("beta", p.beta)):
        if value > 0:
            raise ConfigError(
                f"LIFParams.{name} = {value:g}: NIR's LIF has no refractory period and no "
                "threshold adaptation; valid for export: refractory_s = 0 and beta = 0"
            )
    n = int(encoder.n_features_in_)
    gain = np.asarray(encoder.scale_, np.float64) * float(encoder.gain_)
    one = np.ones(n)
    nodes = {
        "input": nir.Input(input_type={"input": np.array([n])}),
        "normalise": nir.Affine(
            weight=np.diag(gain).astype(np.float32),
            bias=(-np.asarray(encoder.offset_) * gain).astype(np.float32),
        ),
        "lif": nir.LIF(
            tau=p.tau_m_s * one,
            r=one.copy(),
            v_leak=p.v_rest * one,
            v_threshold=p.v_th * one,
            v_reset=p.v_reset * one,
        ),
        "output": nir.Output(output_type={"output": np.array([n])}),
    }
    edges = [("input", "normalise"), ("normalise", "lif"), ("lif", "output")]
    meta = {"source": "sim_tactile LIFEncoder", "channels": list(encoder.channel_names_)}
    return nir.NIRGraph(nodes=nodes, edges=edges, metadata=meta)


#: A node's parameters that are time constants [s]: finite and > 0 (NIR's neurons divide
#: by them; a negative one makes a neuron whose potential grows without bound).
TIME_CONSTANTS = ("tau", "tau_syn", "tau_mem")
#: What a NIR file may be refused for while it is read: h5py's and nir's own errors on a
#: file that is not HDF5, is cut short, or holds no graph of known nodes.
_READ_ERRORS = (OSError, KeyError, ValueError, TypeError, AttributeError, IndexError)


def check_graph(graph: Any, where: str) -> None:
    """Refuse ``graph`` (read from or written to ``where``, named in the error) unless every
    number in it is finite, every time constant (:data:`TIME_CONSTANTS`) is > 0, every
    neuron's threshold is above its reset, and every edge joins two of its nodes; a graph
    inside it is checked the same way."""
    nir = _nir()
    nodes = getattr(graph, "nodes", None)
    if not isinstance(nodes, dict):
        raise ConfigError(f"NIR file {where!r} holds a {type(graph).__name__}; valid: a graph")
    for name, node in nodes.items():
        if isinstance(node, nir.NIRGraph):
            check_graph(node, f"{where}: {name}")
            continue
        for key, value in vars(node).items():
            if key in ("input_type", "output_type", "metadata") or isinstance(value, str):
                continue
            try:
                a = np.asarray(value, dtype=np.float64)
            except (TypeError, ValueError):
                continue
            bad = int(np.count_nonzero(~np.isfinite(a)))
            if bad:
                raise ConfigError(
                    f"NIR file {where!r}: node {name!r}: {key} has {bad} values that are NaN "
                    "or infinite; valid: finite numbers"
                )
            if key in TIME_CONSTANTS and not (a > 0).all():
                raise ConfigError(
                    f"NIR file {where!r}: node {name!r}: {key} = {float(a.min()):g} s; "
                    "valid: > 0 s (a time constant)"
                )
        if hasattr(node, "v_threshold") and hasattr(node, "v_reset"):
            if not (np.asarray(node.v_threshold) > np.asarray(node.v_reset)).all():
                raise ConfigError(
                    f"NIR file {where!r}: node {name!r}: v_threshold is not above v_reset "
                    "everywhere; valid: v_threshold > v_reset (else the neuron fires on "
                    "every step)"
                )
    for edge in getattr(graph, "edges", []):
        if len(edge) != 2 or any(e not in nodes for e in edge):
            raise ConfigError(
                f"NIR file {where!r}: edge {tuple(edge)} joins no two of its nodes {sorted(nodes)}"
            )


def write_nir(graph: Any, path: str | Path) -> Path:
    """Write ``graph`` to ``path`` (HDF5, ``nir.write``; the folder must exist), whole or
    not at all: into a temporary file beside it, then renamed over it (a file already at
    ``path`` stays as it was if the write fails). The graph is checked first
    (:func:`check_graph`)."""
    import os
    import tempfile

    nir = _nir()
    path = Path(path)
    if not path.parent.is_dir():
        raise ConfigError(f"folder {str(path.parent)!r} does not exist; create it first")
    if path.is_dir():
        raise ConfigError(f"NIR file {str(path)!r} is a folder; valid: a file's path")
    check_graph(graph, str(path))
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".partial")
    os.close(fd)
    try:
        nir.write(tmp, graph)
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_nir(path: str | Path):
    """A graph written by :func:`write_nir` (``nir.read``), read as data: a file that is not
    a NIR graph, or whose graph fails :func:`check_graph`, is refused naming the file."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"NIR file {str(path)!r} is a folder; valid: a file's path")
    if not path.is_file():
        raise ConfigError(f"NIR file {str(path)!r} does not exist")
    nir = _nir()
    try:
        graph = nir.read(str(path))
    except _READ_ERRORS as exc:
        raise ConfigError(
            f"NIR file {str(path)!r} cannot be read as a NIR graph ({type(exc).__name__}: "
            f"{' '.join(str(exc).split())}); valid: an HDF5 file written by nir.write"
        ) from None
    check_graph(graph, str(path))
    return graph


def norse_run(graph: Any, x: np.ndarray, dt_s: float) -> np.ndarray:
    """Run ``graph`` in Norse (``norse.torch.from_nir`` at step ``dt_s``) on ``x``
    ``(samples, steps, inputs)``; returns the output spikes ``(samples, steps, outputs)``."""
    try:
        from norse.torch.utils.import_nir import from_nir
    except ImportError as exc:
        raise MissingDependencyError(
            f"norse is needed to run a NIR graph: {NORSE_INSTALL}"
        ) from exc
    import warnings

    torch = require("torch", "learn")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # nirtorch's deprecation notice
        module = from_nir(graph, dt=float(dt_s))
    xt = torch.as_tensor(np.asarray(x, np.float32))
    state, out = None, []
    with torch.no_grad():
        for n in range(xt.shape[1]):
            z, state = module(xt[:, n], state)
            out.append(z)
    return torch.stack(out, 1).numpy()


def alpha_kernel_mismatch(tau_s: float, dt_s: float, steps: int | None = None) -> dict:
    """How the CubaLIF pair stands in for the SRM's alpha kernel on the step ``dt_s``: the
    largest difference (in units of the kernel's peak, 1) of the exact continuous response
    sampled at the steps (0 up to rounding), and of the forward-Euler response a consumer
    integrating at ``dt_s`` gives, ``(e dt / tau) (n + 1) (1 - dt / tau)^n``."""
    k = dt_s / tau_s
    n = np.arange(steps or int(math.ceil(14.0 / k)) + 1, dtype=np.float64)
    srm = n * k * np.exp(1.0 - n * k)
    t = n * dt_s
    exact = (math.e / tau_s) * t * np.exp(-t / tau_s)  # r w_in / tau^2 * t exp(-t / tau)
    euler = math.e * k * (n + 1) * (1.0 - k) ** n
    return {
        "exact_max_abs": float(np.abs(exact - srm).max()),
        "euler_max_abs": float(np.abs(euler - srm).max()),
        "euler_peak_step_shift": int(np.argmax(euler)) - int(np.argmax(srm)),
    }


#: A decision of the package's network is clear when its class's neuron fires at least this
#: many spikes more than the runner-up's.
CLEAR_MARGIN = 2


def agreement(clf: Any, raster: np.ndarray) -> dict:
    """The NIR graph of ``clf`` run in Norse against ``clf`` itself on ``raster``
    ``(samples, steps, channels)``: the fraction of equal decisions (Norse's: the class whose
    neuron fires most, ties to the lowest class), also among the samples the package's
    network decides clearly (:data:`CLEAR_MARGIN`), the correlation of the output spike
    counts, and both networks' mean output spikes per sample."""
    graph = snn_to_nir(clf)
    own_counts = clf.output_counts(raster)
    own = clf.predict(raster)
    z = norse_run(graph, raster, clf.dt_s).sum(axis=1)
    theirs = clf.classes_[np.argmax(z, axis=1)]
    a, b = own_counts.ravel(), z.ravel()
    corr = float(np.corrcoef(a, b)[0, 1]) if a.std() > 0 and b.std() > 0 else float("nan")
    top2 = np.sort(own_counts, axis=1)[:, -2:] if own_counts.shape[1] > 1 else None
    clear = np.ones(len(own), bool) if top2 is None else top2[:, 1] - top2[:, 0] >= CLEAR_MARGIN
    return {
        "samples": int(raster.shape[0]),
        "agreement": float(np.mean(own == theirs)),
        "clear_samples": int(clear.sum()),
        "agreement_clear": float(np.mean(own[clear] == theirs[clear])) if clear.any() else None,
        "count_correlation": corr,
        "own_spikes_per_sample": float(own_counts.sum(1).mean()),
        "nir_spikes_per_sample": float(z.sum(1).mean()),
        "kernel": alpha_kernel_mismatch(float(clf.tau_sr_s), float(clf.dt_s)),
    }
