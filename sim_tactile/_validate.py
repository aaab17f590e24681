"""Input checks that name the parameter, the value and the valid range.

Never ``assert``: these run under ``python -O`` too.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from .errors import ConfigError


def _fmt(value: object) -> str:
    return repr(value) if isinstance(value, str) else f"{value}"


def finite(name: str, value: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number, got {_fmt(value)}") from None
    if not math.isfinite(v):
        raise ConfigError(f"{name} must be finite, got {_fmt(value)}")
    return v


def in_range(
    name: str,
    value: float,
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
    unit: str = "",
) -> float:
    """Return ``float(value)`` if it lies in the interval, else raise a ConfigError that
    names the interval (also for a non-finite value)."""
    left = "(" if lo_open else "["
    right = ")" if hi_open else "]"
    lo_s = "-inf" if lo is None else f"{lo:g}"
    hi_s = "inf" if hi is None else f"{hi:g}"
    u = f" {unit}" if unit else ""
    valid = f"valid: {left}{lo_s}, {hi_s}{right}{u}"
    try:
        v = finite(name, value)
    except ConfigError as exc:
        raise ConfigError(f"{exc}; {valid}") from None
    bad = (lo is not None and (v <= lo if lo_open else v < lo)) or (
        hi is not None and (v >= hi if hi_open else v > hi)
    )
    if bad:
        raise ConfigError(f"{name} = {v:g}{u} is out of range; {valid}")
    return v


def positive(name: str, value: float, *, unit: str = "") -> float:
    return in_range(name, value, 0.0, None, lo_open=True, unit=unit)


def non_negative(name: str, value: float, *, unit: str = "") -> float:
    return in_range(name, value, 0.0, None, unit=unit)


def integer(name: str, value: object, lo: int | None = None, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, int | float) or int(value) != value:
        raise ConfigError(f"{name} must be an integer, got {_fmt(value)}")
    v = int(value)
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        lo_s = "-inf" if lo is None else str(lo)
        hi_s = "inf" if hi is None else str(hi)
        raise ConfigError(f"{name} = {v} is out of range; valid: [{lo_s}, {hi_s}]")
    return v


def one_of(name: str, value: object, allowed: Iterable[str]) -> str:
    allowed = list(allowed)
    if value not in allowed:
        raise ConfigError(f"{name} = {_fmt(value)} is not valid; valid: {', '.join(allowed)}")
    return str(value)


def known_keys(
    where: str, table: object, valid: Iterable[str], *, prefix: str = "", describe=None
) -> None:
    """Refuse the keys of ``table`` (a mapping, or the keys themselves) that are not in
    ``valid``, in the one message every reader gives: ``<where>: unknown key(s) a, b;
    valid: ...``. ``where`` names the table (a file, a section; empty: none); ``prefix`` is
    put before every key named (``pad.``); ``describe`` maps a valid key to its text in the
    message (default: the prefixed key)."""
    valid = list(valid)
    bad = sorted(set(table) - set(valid), key=str)
    if not bad:
        return
    text = describe or (lambda k: f"{prefix}{k}")
    head = f"{where}: " if where else ""
    raise ConfigError(
        f"{head}unknown key(s) {', '.join(f'{prefix}{b}' for b in bad)}; valid: "
        + ", ".join(text(k) for k in valid)
    )


def finite_array(name: str, arr: np.ndarray, hint: str = "") -> np.ndarray:
    """Return ``arr`` if every value is finite, else raise a ConfigError naming the first
    non-finite value, its index and how many there are (``hint``: what to do about it)."""
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ConfigError(
            f"{name} must be finite; found {arr[idx]} at index {idx} ({int(bad.sum())} "
            f"non-finite value(s) in all)" + (f": {hint}" if hint else "")
        )
    return arr


# ------------------------------------------------------------------ data arrays
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
