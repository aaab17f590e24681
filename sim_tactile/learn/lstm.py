"""LSTM classifier of seed paper 000 (its "ANN" baseline).

Input: raw arrays ``(samples, time, channels)``, standardised per channel with the training
mean and standard deviation. Two stacked LSTM layers (hidden size 60), a linear read-out of
the hidden state at the last time step, softmax cross-entropy. For spatially arranged taxels
(the iCub forearm: 6 patches x 10 taxels) an optional small convolutional front maps each
time step's taxel image to features before the LSTM (``grid_shape`` gives the image shape;
channel ``k`` goes to row ``k // width``, column ``k % width``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validate import in_range, integer, positive
from ..errors import ConfigError
from ._torch import TorchClassifier


def _build_net(torch, n_in: int, n_out: int, p: dict, gen):
    nn = torch.nn

    class LSTMNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            grid = p["grid_shape"]
            if grid is not None:
                c = p["conv_channels"]
                self.front = nn.Sequential(
                    nn.Conv2d(1, c, kernel_size=3, padding=1),
                    nn.ReLU(),
                    nn.Flatten(),
                )
                width = c * grid[0] * grid[1]
            else:
                self.front = None
                width = n_in
            self.lstm = nn.LSTM(
                width,
                p["hidden_size"],
                p["num_layers"],
                batch_first=True,
                dropout=p["dropout"] if p["num_layers"] > 1 else 0.0,
            )
            self.drop = nn.Dropout(p["dropout"])
            self.head = nn.Linear(p["hidden_size"], n_out)
            with torch.no_grad():  # torch's default initialisations, drawn from our generator
                for mod in self.modules():
                    if isinstance(mod, nn.LSTM):
                        k = 1.0 / math.sqrt(mod.hidden_size)
                        for w in mod.parameters():
                            w.uniform_(-k, k, generator=gen)
                    elif isinstance(mod, nn.Linear | nn.Conv2d):
                        fan_in = mod.weight[0].numel()
                        k = 1.0 / math.sqrt(fan_in)
                        mod.weight.uniform_(-k, k, generator=gen)
                        mod.bias.uniform_(-k, k, generator=gen)

        def forward(self, x):
            """``x``: ``(B, T, C)`` -> class logits ``(B, K)`` from the last step."""
            if self.front is not None:
                b, t, _ = x.shape
                img = x.reshape(b * t, 1, *p["grid_shape"])
                x = self.front(img).reshape(b, t, -1)
            h, _ = self.lstm(x)
            return self.head(self.drop(h[:, -1]))

    return LSTMNet()


class LSTMClassifier(TorchClassifier):
    """Stacked LSTM on standardised raw signals, prediction from the last time step.

    Parameters:
        hidden_size, num_layers: LSTM size (paper: 60 and 2).
        grid_shape: ``(rows, cols)`` with ``rows * cols = channels`` to add the convolutional
            front (paper: used for the iCub RoboSkin); ``None`` for none.
        conv_channels: feature maps of the 3 x 3 convolution of the front.
        dropout: dropout probability between the LSTM layers and before the read-out.
        epochs, batch_size, lr, weight_decay: Adam training (paper: 2000 epochs).
        lr_schedule: ``cosine`` (the learning rate decays to 0 over the epochs) or ``constant``.
        grad_clip: largest Euclidean norm of the gradient (clipped above; None: no clipping).
        random_state, device, num_threads, verbose: as in :class:`~sim_tactile.learn.snn.SNNClassifier`.
    """

    def __init__(
        self,
        hidden_size: int = 60,
        num_layers: int = 2,
        *,
        grid_shape: Sequence[int] | None = None,
        conv_channels: int = 8,
        dropout: float = 0.0,
        epochs: int = 200,
        batch_size: int = 32,
        lr: float = 3e-3,
        weight_decay: float = 0.0,
        grad_clip: float | None = 1.0,
        lr_schedule: str = "cosine",
        random_state: int | None = None,
        device: str = "auto",
        num_threads: int | None = None,
        verbose: int = 0,
    ) -> None:
        self.hidden_size = hidden_size
        self.num_layers = num_layers
        self.grid_shape = grid_shape
        self.conv_channels = conv_channels
        self.dropout = dropout
        self.epochs = epochs
        self.batch_size = batch_size
        self.lr = lr
        self.weight_decay = weight_decay
        self.grad_clip = grad_clip
        self.lr_schedule = lr_schedule
        self.random_state = random_state
        self.device = device
        self.num_threads = num_threads
        self.verbose = verbose

    def _params(self, n_in: int) -> dict:
        grid = None
        if self.grid_shape is not None:
            grid = tuple(integer("grid_shape", g, 1, None) for g in self.grid_shape)
            if len(grid) != 2 or grid[0] * grid[1] != n_in:
                raise ConfigError(
                    f"grid_shape = {tuple(self.grid_shape)} must be (rows, cols) with "
                    f"rows * cols = {n_in} (the number of channels)"
                )
        return {
            "hidden_size": integer("hidden_size", self.hidden_size, 1, None),
            "num_layers": integer("num_layers", self.num_layers, 1, None),
            "grid_shape": grid,
            "conv_channels": integer("conv_channels", self.conv_channels, 1, None),
            "dropout": in_range("dropout", self.dropout, 0.0, 1.0, hi_open=True),
        }

    def _fit_prepare(self, x: np.ndarray) -> None:
        flat = x.reshape(-1, x.shape[2])
        self.mean_ = flat.mean(axis=0)
        std = flat.std(axis=0)
        self.scale_ = np.where(std > 0, std, 1.0)

    def _build(self, torch: Any, n_in: int, n_out: int, gen):
        return _build_net(torch, n_in, n_out, self._params(n_in), gen)

    def _after_backward(self, torch: Any, module: Any) -> None:
        if self.grad_clip is not None:
            torch.nn.utils.clip_grad_norm_(
                module.parameters(), positive("grad_clip", self.grad_clip)
            )

    def _optimizer(self, torch: Any, module: Any):
        return torch.optim.Adam(module.parameters(), lr=self.lr, weight_decay=self.weight_decay)

    def _prepare(self, torch: Any, x: np.ndarray, dev):
        z = (x - self.mean_) / self.scale_
        return torch.as_tensor(z, dtype=torch.float32, device=dev)

    def _batch_loss(self, torch: Any, module: Any, xb, yb):
        return torch.nn.functional.cross_entropy(module(xb), yb)

    def _scores(self, torch: Any, module: Any, xb):
        return torch.softmax(module(xb), dim=1)
