"""Spiking network classifier of seed paper 000: two fully connected layers of SRM neurons.

Input: spike rasters ``(samples, steps, channels)`` (0/1 per time step, e.g. from
:class:`~sim_tactile.learn.preprocess.SpikeRaster`); one output neuron per class. The
decision is the class whose output neuron fires most; ties (common at the very start of a
recording) are broken by the mean membrane potential, which never overrides a difference of
one spike.

Training (SLAYER-style, written in plain torch because lava-dl does not install on Python
3.11): the spike function's derivative is replaced by the surrogate
``rho(u) = scale_rho / (tau_rho theta) exp(-|u - theta| / (tau_rho theta))``, the PSP
convolutions are differentiated exactly, the refractory response is treated as a constant
(as SLAYER does), and the loss is the paper's spike-count loss (eq. 3)

    L = 1/2 sum_classes (sum_t o(t) - target)^2,   target = target_true for the true class,
                                                   target_false for the others

(paper: 250 / 30 for BioTac (400 steps), 70 / 3 for iCub (75 steps)). Because the network
is causal, the output counts up to step ``n`` are those of the first ``n`` input steps:
:meth:`SNNClassifier.predict_upto` gives the decision from the counts up to a time ``t``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validate import in_range, integer, positive
from ..errors import ConfigError
from ._srm import alpha_kernel, refractory_constants, srm_spikes_numba, srm_spikes_torch
from ._torch import TorchClassifier

#: Tie-breaking weight of the mean membrane potential in the class scores (< 1 spike).
TIE_WEIGHT = 0.4


def _spike_fn(torch):
    class SpikeFn(torch.autograd.Function):
        """Heaviside spikes forward, SLAYER's exponential surrogate backward."""

        @staticmethod
        def forward(ctx, v, spikes, theta, width, scale):
            ctx.save_for_backward(v)
            ctx.theta, ctx.width, ctx.scale = theta, width, scale
            return spikes

        @staticmethod
        def backward(ctx, grad):
            (v,) = ctx.saved_tensors
            rho = ctx.scale / ctx.width * torch.exp(-(v - ctx.theta).abs() / ctx.width)
            return grad * rho, None, None, None, None

    return SpikeFn


def _build_net(torch, n_in: int, n_hidden: int, n_out: int, cfg: dict, gen):
    nn = torch.nn
    spike_fn = _spike_fn(torch)

    class SRMNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.fc1 = nn.Linear(n_in, n_hidden, bias=False)
            self.fc2 = nn.Linear(n_hidden, n_out, bias=False)
            with torch.no_grad():
                for fc in (self.fc1, self.fc2):
                    bound = cfg["weight_scale"] / math.sqrt(fc.in_features)
                    fc.weight.uniform_(-bound, bound, generator=gen)
            self.register_buffer("eps", torch.from_numpy(alpha_kernel(cfg["tau_sr"])))

        def spikes(self, u):
            theta = cfg["theta"]
            d, c = cfg["ref"]
            ref = srm_spikes_numba if u.device.type == "cpu" else srm_spikes_torch
            s, r = ref(torch, u, theta, d, c)
            v = u + r
            return spike_fn.apply(v, s, theta, cfg["tau_rho"] * theta, cfg["scale_rho"]), v

        def layers(self, xf):
            """``xf``: PSP-filtered input ``(B, C, T)`` -> the hidden spikes ``(B, H, T)``,
            the output spikes and the output potentials ``(B, K, T)``."""
            u1 = torch.einsum("hc,bct->bht", self.fc1.weight, xf)
            s1, _ = self.spikes(u1)
            a2 = torch.einsum("kh,bht->bkt", self.fc2.weight, s1)
            u2 = causal_filter(torch, a2, self.eps)
            return (s1, *self.spikes(u2))

        def forward(self, xf):
            """``xf``: PSP-filtered input ``(B, C, T)`` -> output spikes and potentials."""
            return self.layers(xf)[1:]

    return SRMNet()


def causal_filter(torch, x, kernel):
    """``y[..., n] = sum_m kernel[m] x[..., n - m]`` along the last axis (zero before 0)."""
    shape = x.shape
    k = kernel.numel()
    flat = torch.nn.functional.pad(x.reshape(-1, 1, shape[-1]), (k - 1, 0))
    y = torch.nn.functional.conv1d(flat, kernel.flip(0).view(1, 1, k))
    return y.reshape(shape)


class SNNClassifier(TorchClassifier):
    """Two fully connected layers of SRM neurons trained on a spike-count loss.

    Parameters:
        hidden: hidden layer size (paper: 60 for BioTac, 1200 for iCub).
        target_true, target_false: desired output spike counts over the training window for
            the true class and the other classes (paper: 250 / 30 BioTac, 70 / 3 iCub).
        dt_s: duration of one input step [s] (1 / sampling rate of the raster).
        theta: firing threshold (membrane units).
        tau_sr_s: time constant of the synaptic alpha kernel [s].
        tau_ref_s, scale_ref: time constant [s] and depth (in units of theta) of the
            refractory kernel.
        tau_rho, scale_rho: width (in units of theta) and height of the surrogate derivative.
        weight_scale: initial weights are uniform in ``+-weight_scale / sqrt(fan_in)``.
        epochs, batch_size, lr, weight_decay: Adam training (paper: 300 epochs).
        lr_schedule: ``cosine`` (the learning rate decays to 0 over the epochs) or ``constant``.
        random_state: seed of the initial weights and the mini-batch order.
        device: ``auto`` (GPU when present), ``cpu`` or ``cuda``.
        num_threads: CPU threads of torch during fit / predict (None: torch's setting).
        verbose: log the loss every ``verbose`` epochs to stderr (0: silent).
    """

    def __init__(
        self,
        hidden: int = 60,
        target_true: float = 250.0,
        target_false: float = 30.0,
        *,
        dt_s: float = 0.01,
        theta: float = 10.0,
        tau_sr_s: float = 0.05,
        tau_ref_s: float = 0.01,
        scale_ref: float = 2.0,
        tau_rho: float = 1.0,
        scale_rho: float = 1.0,
        weight_scale: float = 30.0,
        epochs: int = 300,
        batch_size: int = 32,
        lr: float = 1e-3,
        weight_decay: float = 0.0,
        lr_schedule: str = "cosine",
        random_state: int | None = None,
        device: str = "auto",
        num_threads: int | None = None,
        verbose: int = 0,
    ) -> None:
        self.hidden = hidden
        self.target_true = target_true
        self.target_false = target_false
        self.dt_s = dt_s
        self.theta = theta
        self.tau_sr_s = tau_sr_s
        self.tau_ref_s = tau_ref_s
        self.scale_ref = scale_ref
        self.tau_rho = tau_rho
        self.scale_rho = scale_rho
        self.weight_scale = weight_scale
        self.epochs = epochs
        self.batch_size = batch_size
        self.lr = lr
        self.weight_decay = weight_decay
        self.lr_schedule = lr_schedule
        self.random_state = random_state
        self.device = device
        self.num_threads = num_threads
        self.verbose = verbose

    # ------------------------------------------------------------------ parameters
    def _config(self) -> dict:
        dt = positive("dt_s", self.dt_s, unit="s")
        theta = positive("theta", self.theta)
        tau_ref = positive("tau_ref_s", self.tau_ref_s, unit="s") / dt
        return {
            "theta": theta,
            "tau_sr": positive("tau_sr_s", self.tau_sr_s, unit="s") / dt,
            "ref": refractory_constants(theta, tau_ref, in_range("scale_ref", self.scale_ref, 0)),
            "tau_rho": positive("tau_rho", self.tau_rho),
            "scale_rho": positive("scale_rho", self.scale_rho),
            "weight_scale": positive("weight_scale", self.weight_scale),
        }

    def _check_params(self) -> None:
        super()._check_params()
        integer("hidden", self.hidden, 1, None)
        lo = in_range("target_false", self.target_false, 0)
        hi = in_range("target_true", self.target_true, 0)
        if not hi > lo:
            raise ConfigError(
                f"target_true = {hi:g} must exceed target_false = {lo:g} (output spike counts)"
            )
        in_range("weight_decay", self.weight_decay, 0)
        self._config()

    # ------------------------------------------------------------------ torch hooks
    def _build(self, torch: Any, n_in: int, n_out: int, gen):
        return _build_net(torch, n_in, self.hidden, n_out, self._config(), gen)

    def _optimizer(self, torch: Any, module: Any):
        return torch.optim.Adam(module.parameters(), lr=self.lr, weight_decay=self.weight_decay)

    def _prepare(self, torch: Any, x: np.ndarray, dev):
        spikes = torch.as_tensor(np.ascontiguousarray(x.transpose(0, 2, 1)), dtype=torch.float32)
        kernel = torch.from_numpy(alpha_kernel(self._config()["tau_sr"]))
        return causal_filter(torch, spikes, kernel).to(dev)

    def _batch_loss(self, torch: Any, module: Any, xb, yb):
        out, _ = module(xb)
        counts = out.sum(-1)
        target = torch.full_like(counts, float(self.target_false))
        target.scatter_(1, yb[:, None], float(self.target_true))
        return 0.5 * ((counts - target) ** 2).sum(1).mean()

    def _scores(self, torch: Any, module: Any, xb):
        out, v = module(xb)
        tie = (1.0 + torch.tanh(v.mean(-1) / self._config()["theta"])) / 2.0
        return out.sum(-1) + TIE_WEIGHT * tie

    def predict_upto(self, X: object, t_s: float) -> np.ndarray:
        """Decisions from the output spike counts up to ``t_s`` seconds (the first
        ``round(t_s / dt_s)`` steps of each raster; at least one)."""
        t = positive("t_s", t_s, unit="s")
        x = np.asarray(X)
        n = min(max(1, round(t / self.dt_s)), x.shape[1] if x.ndim == 3 else 1)
        return self.predict(x[:, :n] if x.ndim == 3 else x)

    def output_counts(self, X: object) -> np.ndarray:
        """Output spike counts per class, shape ``(samples, classes)``."""
        return np.floor(self.decision_function(X))

    def neuromorphic_metrics(self, X: object) -> dict:
        """NeuroBench's figures of the fitted network on the rasters ``X`` (footprint,
        parameters, connection and activation sparsity, synaptic operations per sample):
        :func:`~sim_tactile.learn.neurobench.snn_metrics`."""
        from .neurobench import snn_metrics

        return snn_metrics(self, X)

    def to_nir(self, class_names: Sequence[str] | None = None):
        """The fitted network as a NIR graph (:func:`~sim_tactile.learn.nir.snn_to_nir`);
        ``class_names`` (indexed by the labels, e.g. a task's plates) name its outputs."""
        from .nir import snn_to_nir

        return snn_to_nir(self, class_names)
