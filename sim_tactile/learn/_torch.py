"""Shared machinery of the torch classifiers (LSTM, SNN).

torch is an optional dependency: it is imported only when a torch model is fitted or used,
and its absence raises :class:`~sim_tactile.errors.MissingDependencyError` with the install
command. Randomness comes only from ``random_state``: it seeds a private ``torch.Generator``
for the initial weights and the mini-batch order, and, for dropout (which draws from torch's
global generator), the global generator inside ``torch.random.fork_rng``, which restores the
caller's generator state afterwards. Two fits with the same seed on the same machine give
equal weights and predictions (CPU).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin

from .._validate import check_array, check_classes, check_labels, integer, one_of, positive
from ..errors import ConfigError, require
from ..hashing import derive_seed

DEVICES = ("auto", "cpu", "cuda")
LR_SCHEDULES = ("constant", "cosine")


def import_torch():
    """torch, or MissingDependencyError naming ``pip install 'sim-tactile[learn]'``."""
    return require("torch", "learn")


def resolve_device(torch: Any, device: str):
    """``auto`` -> the first CUDA GPU when present, else the CPU."""
    one_of("device", device, DEVICES)
    if device == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if device == "cuda" and not torch.cuda.is_available():
        raise ConfigError("device = 'cuda' but torch sees no CUDA GPU; valid here: 'auto', 'cpu'")
    return torch.device(device)


def seed_from(random_state: int | None) -> int:
    """A 63-bit seed from ``random_state`` (fresh OS entropy when it is None)."""
    if random_state is None:
        return int(np.random.SeedSequence().generate_state(1, np.uint64)[0] >> 1)
    return derive_seed(integer("random_state", random_state, 0, None), bits=63)


@contextmanager
def torch_threads(torch: Any, num_threads: int | None) -> Iterator[None]:
    """Run with ``num_threads`` intra-op CPU threads and restore the previous number after.

    One thread is the robust choice on a shared machine: small recurrent models gain little
    from more, and OpenMP threads that wait for a descheduled peer can slow an epoch tenfold.
    """
    if num_threads is None:
        yield
        return
    n = integer("num_threads", num_threads, 1, None)
    before = torch.get_num_threads()
    torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(before)


class TorchClassifier(ClassifierMixin, BaseEstimator):
    """Base of the torch classifiers over arrays ``(samples, time, channels)``.

    Subclasses define ``_build(torch, n_channels, n_classes, generator)`` returning a module,
    ``_prepare(torch, x)`` (array -> input tensor on the device), ``_batch_loss(torch, module,
    xb, yb)`` and ``_scores(torch, module, xb)`` (class scores, larger is better). Learned
    state: ``classes_``, ``module_``, ``n_features_in_``, ``n_time_``, ``loss_curve_`` (mean
    training loss per epoch) and ``epoch_times_s_`` (wall time of each epoch [s]).
    """

    # names of the constructor parameters every subclass has
    epochs: int
    batch_size: int
    lr: float
    random_state: int | None
    lr_schedule: str
    device: str
    num_threads: int | None
    verbose: int

    def _check_params(self) -> None:
        integer("epochs", self.epochs, 1, None)
        integer("batch_size", self.batch_size, 1, None)
        positive("lr", self.lr)
        one_of("lr_schedule", self.lr_schedule, LR_SCHEDULES)
        integer("verbose", self.verbose, 0, None)

    def _check_X(self, X: object, *, fitted: bool) -> np.ndarray:
        x = check_array(X, "X", ndim=(3,))
        if fitted and x.shape[2] != self.n_features_in_:
            raise ConfigError(
                f"X has {x.shape[2]} channels but the model was fitted on {self.n_features_in_}"
            )
        return x

    def _log(self, msg: str) -> None:
        print(f"[{type(self).__name__}] {msg}", file=sys.stderr, flush=True)

    def fit(self, X: object, y: object) -> TorchClassifier:
        torch = import_torch()
        self._check_params()
        seed = seed_from(self.random_state)
        dev = resolve_device(torch, self.device)
        devices = [dev.index or 0] if dev.type == "cuda" else []
        with torch_threads(torch, self.num_threads), torch.random.fork_rng(devices=devices):
            torch.manual_seed(seed)  # dropout only; restored when fork_rng exits
            return self._fit(torch, X, y, seed, dev)

    def _fit(self, torch: Any, X: object, y: object, seed: int, dev) -> TorchClassifier:
        x = self._check_X(X, fitted=False)
        y_arr = check_labels(y, x.shape[0])
        self.classes_ = check_classes(y_arr)
        y_idx = np.searchsorted(self.classes_, y_arr)
        gen = torch.Generator().manual_seed(seed)
        self.n_features_in_ = x.shape[2]
        self.n_time_ = x.shape[1]
        self._fit_prepare(x)
        module = self._build(torch, x.shape[2], len(self.classes_), gen).to(dev)
        xt = self._prepare(torch, x, dev)
        yt = torch.as_tensor(y_idx, dtype=torch.long, device=dev)
        opt = self._optimizer(torch, module)
        sched = None
        if self.lr_schedule == "cosine":
            sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=self.epochs)
        n = x.shape[0]
        self.loss_curve_, self.epoch_times_s_ = [], []
        module.train()
        for epoch in range(self.epochs):
            t0 = time.perf_counter()
            order = torch.randperm(n, generator=gen).to(dev)
            total = 0.0
            for start in range(0, n, self.batch_size):
                idx = order[start : start + self.batch_size]
                opt.zero_grad(set_to_none=True)
                loss = self._batch_loss(torch, module, xt[idx], yt[idx])
                loss.backward()
                self._after_backward(torch, module)
                opt.step()
                total += float(loss.detach()) * len(idx)
            if sched is not None:
                sched.step()
            self.loss_curve_.append(total / n)
            self.epoch_times_s_.append(time.perf_counter() - t0)
            if self.verbose and (epoch + 1) % self.verbose == 0:
                self._log(
                    f"epoch {epoch + 1}/{self.epochs} loss {self.loss_curve_[-1]:.4g} "
                    f"({self.epoch_times_s_[-1]:.2f} s)"
                )
        module.eval()
        self.module_ = module
        self.device_ = str(dev)
        return self

    def _optimizer(self, torch: Any, module: Any):
        return torch.optim.Adam(module.parameters(), lr=self.lr)

    def _after_backward(self, torch: Any, module: Any) -> None:
        """Hook between ``backward`` and the optimiser step (e.g. gradient clipping)."""

    def _fit_prepare(self, x: np.ndarray) -> None:
        """Learn any input statistics (e.g. standardisation) before training."""

    def decision_function(self, X: object) -> np.ndarray:
        """Class scores, shape ``(samples, classes)`` (larger is more likely)."""
        torch = import_torch()
        if not hasattr(self, "module_"):
            from sklearn.exceptions import NotFittedError

            raise NotFittedError(f"this {type(self).__name__} is not fitted yet; call fit first")
        x = self._check_X(X, fitted=True)
        dev = next(self.module_.parameters()).device
        out = []
        with torch.no_grad(), torch_threads(torch, self.num_threads):
            for start in range(0, x.shape[0], max(self.batch_size, 64)):
                xb = self._prepare(torch, x[start : start + max(self.batch_size, 64)], dev)
                out.append(self._scores(torch, self.module_, xb).cpu().numpy())
        return np.concatenate(out).astype(np.float64)

    def predict(self, X: object) -> np.ndarray:
        scores = self.decision_function(X)
        return self.classes_[np.argmax(scores, axis=1)]
