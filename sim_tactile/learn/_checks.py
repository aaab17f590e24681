"""Input checks shared by the classifiers and the protocols (errors name what is wrong)."""

from __future__ import annotations

import numpy as np

from .._validate import finite_array
from ..errors import ConfigError


def check_array(X: object, name: str = "X", *, ndim: tuple[int, ...] = (3,)) -> np.ndarray:
    """Return ``X`` as a float array of one of the allowed ``ndim``; NaN or inf raise.

    3-D arrays are ``(samples, time, channels)``; 2-D arrays are ``(samples, features)``.
    """
    try:
        arr = np.asarray(X, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{name} must be a numeric array, got {type(X).__name__}") from exc
    if arr.ndim not in ndim:
        shapes = " or ".join(
            {2: "(samples, features)", 3: "(samples, time, channels)"}.get(d, f"{d}-D")
            for d in ndim
        )
        raise ConfigError(f"{name} must have shape {shapes}, got {arr.shape}")
    if arr.shape[0] == 0 or 0 in arr.shape[1:]:
        raise ConfigError(f"{name} is empty (shape {arr.shape}); at least one sample is needed")
    return finite_array(name, arr, "remove or impute them first")


def check_labels(y: object, n_samples: int, name: str = "y") -> np.ndarray:
    """Return ``y`` as a 1-D array of length ``n_samples`` (ConfigError otherwise)."""
    arr = np.asarray(y)
    if arr.ndim != 1:
        raise ConfigError(f"{name} must be a 1-D array of class labels, got shape {arr.shape}")
    if arr.shape[0] != n_samples:
        raise ConfigError(
            f"{name} has {arr.shape[0]} labels but X has {n_samples} samples; they must match"
        )
    if arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} holds NaN or infinite labels")
    return arr


def check_classes(y: np.ndarray, *, minimum: int = 2) -> np.ndarray:
    """The sorted classes of ``y``; at least ``minimum`` of them."""
    classes = np.unique(y)
    if classes.size < minimum:
        raise ConfigError(
            f"y has {classes.size} class(es) ({classes.tolist()}); a classifier needs at least "
            f"{minimum}"
        )
    return classes
