"""A user's own method on a task: an estimator, or an encoder and an estimator.

A method is scored under the task's own protocol (:func:`sim_tactile.tasks.evaluate`,
``sim-tactile run TASK --method NAME=module:callable``), beside the built-in rows:

- an **estimator** on scikit-learn's contract (``fit(X, y)``, ``predict(X)``, ``get_params``)
  takes the raw recordings, ``X`` of shape ``(samples, time, channels)``, as ``svm-raw`` does;
  it is cloned for every split and, where the task has time points, fitted again on each
  prefix (accuracy over time);
- an **(encoder, estimator)** pair: the encoder is a transformer (``fit``, ``transform``) from
  those recordings to whatever the estimator takes (spike trains, features). Where the task
  encodes its recordings once before any split (``TaskSpec.encode_once``: papers 001-003,
  which encoded offline), the encoder is fitted on all samples once and each split fits the
  estimator on its rows, exactly as the built-in rows do; otherwise the pair is one pipeline,
  fitted per split;
- a ``(TASK_ENCODER, estimator)`` pair (``("task", estimator)``): the task's own encoder
  feeds the estimator, as it feeds the built-in spiking rows. Only the classifier is the
  user's, so its result file stands in the task's *closed* track (an estimator on the raw
  recordings, or after an encoder of the user's, stands in the *open* one).

Each repeat's estimator gets ``random_state = derive_seed(seed, "model", name, repeat)`` where
its own is None (the built-in models are seeded the same way), so a run is repeatable; a
``rate_hz`` parameter that is None (the encoder's or the estimator's, or their steps') gets
the task's sampling rate, so one method serves tasks of any rate.

``--method`` imports the module the user names (a dotted name found from the working
directory and ``sys.path``, or a ``.py`` file) and calls the callable with no arguments: this
runs the user's code. Nothing is found by scanning.
"""

from __future__ import annotations

import importlib
import importlib.util
import re
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.pipeline import Pipeline

from ..errors import ConfigError
from ..hashing import derive_seed
from ..learn.precomputed import sample_index
from ..learn.protocols import EvalResult, evaluate
from .intervals import interval_list
from .registry import TaskSpec
from .report import ResultRow
from .splits import task_splits

#: What a method's name may be: it labels its report row and its baseline key.
NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+-]{0,63}$")
#: The encoder of a ``(TASK_ENCODER, estimator)`` method: the task's own.
TASK_ENCODER = "task"
#: The ``features`` column of a user's row (its baseline key; the method's description is in
#: the row's ``method``).
USER_FEATURES = "user method"


@dataclass(frozen=True)
class Method:
    """A user's method: ``estimator`` on the raw recordings, or after ``encoder``."""

    name: str
    estimator: Any
    encoder: Any = None
    #: the row's channel set and paper cell, as a built-in run's (all channels, no paper)
    channels: str = "all"
    paper: None = None

    @property
    def label(self) -> str:
        return self.name

    def describe(self) -> str:
        est = _short(self.estimator)
        if self.encoder is None:
            return est
        enc = "the task's encoder" if self.encoder is TASK_ENCODER else _short(self.encoder)
        return f"{enc} -> {est}"

    @property
    def encoder_kind(self) -> str:
        """``"task"`` (the task's encoder), ``"none"`` (the recordings) or the user's
        encoder, described (a result file's ``config.method.encoder``)."""
        if self.encoder is None:
            return "none"
        return TASK_ENCODER if self.encoder is TASK_ENCODER else _short(self.encoder)


def _short(obj: Any, limit: int = 300) -> str:
    text = " ".join(repr(obj).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def as_method(name: str, value: Any) -> Method:
    """Check ``value`` (an estimator, or an ``(encoder, estimator)`` pair) and name it."""
    if not isinstance(name, str) or not NAME.match(name):
        raise ConfigError(
            f"method name {name!r} is not valid; valid: 1-64 letters, digits and _ . + - "
            "starting with a letter or digit"
        )
    encoder = None
    if isinstance(value, tuple | list):
        if len(value) != 2:
            raise ConfigError(
                f"method {name!r}: a pair is (encoder, estimator), got {len(value)} items"
            )
        encoder, value = value
        if isinstance(encoder, str) and encoder == TASK_ENCODER:
            encoder = TASK_ENCODER
        else:
            _check(name, "encoder", encoder, ("fit", "transform"))
    _check(name, "estimator", value, ("fit", "predict"))
    return Method(name, value, encoder)


def _check(name: str, role: str, obj: Any, needs: tuple[str, ...]) -> None:
    missing = [m for m in needs if not callable(getattr(obj, m, None))]
    if missing:
        raise ConfigError(
            f"method {name!r}: its {role} {type(obj).__name__} has no {' or '.join(missing)}; "
            f"valid: an object with {', '.join(needs)} (scikit-learn's contract)"
        )
    try:
        clone(obj)
    except Exception as exc:  # noqa: BLE001 (any failure of a user's object is reported)
        raise ConfigError(
            f"method {name!r}: its {role} {type(obj).__name__} cannot be cloned "
            f"(scikit-learn's get_params / set_params contract): {exc}"
        ) from exc


def as_methods(methods: Mapping[str, Any] | None, taken: set[str] = frozenset()) -> list[Method]:
    """A mapping name -> estimator or pair, checked; names must differ from ``taken`` (the
    built-in rows' labels)."""
    if methods is None:
        return []
    if not isinstance(methods, Mapping):
        raise ConfigError(
            f"methods must map a name to an estimator or an (encoder, estimator) pair, got "
            f"{type(methods).__name__}"
        )
    out = [m if isinstance(m, Method) else as_method(n, m) for n, m in methods.items()]
    clash = sorted({m.name for m in out} & set(taken))
    if clash:
        raise ConfigError(f"method name(s) {clash} are the task's own rows; valid: another name")
    return out


def import_method(spec: str) -> Method:
    """``NAME=module:callable`` (or ``NAME=path/to/file.py:callable``): import the module the
    user named, call the callable, and check what it returns."""
    name, eq, target = spec.partition("=")
    module, colon, attr = target.rpartition(":")
    if not eq or not colon or not name or not module or not attr:
        raise ConfigError(
            f"--method {spec!r} is not valid; valid: NAME=module:callable or "
            "NAME=path/to/file.py:callable"
        )
    mod = _import(module, spec)
    fn = getattr(mod, attr, None)
    if not callable(fn):
        raise ConfigError(f"--method {spec!r}: {module} has no callable {attr!r}")
    try:
        value = fn()
    except Exception as exc:  # noqa: BLE001 (the user's code: report what it raised)
        raise ConfigError(
            f"--method {spec!r}: {module}:{attr}() raised {type(exc).__name__}: {exc}"
        ) from exc
    return as_method(name, value)


def _import(module: str, spec: str):
    if module.endswith(".py"):
        path = Path(module)
        if not path.is_file():
            raise ConfigError(f"--method {spec!r}: no file {path}")
        uspec = importlib.util.spec_from_file_location(f"sim_tactile_user_{path.stem}", path)
        mod = importlib.util.module_from_spec(uspec)
        try:
            uspec.loader.exec_module(mod)
        except Exception as exc:  # noqa: BLE001
            raise ConfigError(
                f"--method {spec!r}: importing {path} raised {type(exc).__name__}: {exc}"
            ) from exc
        return mod
    added = str(Path.cwd()) not in sys.path
    if added:  # a module beside the user, as `python -m` would find it
        sys.path.insert(0, str(Path.cwd()))
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        raise ConfigError(
            f"--method {spec!r}: no module named {module!r} (looked in the working directory "
            f"and on sys.path): {exc}"
        ) from exc
    except Exception as exc:  # noqa: BLE001
        raise ConfigError(
            f"--method {spec!r}: importing {module} raised {type(exc).__name__}: {exc}"
        ) from exc
    finally:
        if added:
            sys.path.remove(str(Path.cwd()))


def prepared(obj: Any, seed: int | None, rate_hz: float) -> Any:
    """A clone of ``obj`` whose unset (None) ``random_state`` parameters, its own and its
    steps', are ``seed`` (left alone when ``seed`` is None), and whose unset ``rate_hz``
    parameters are ``rate_hz``."""
    est = clone(obj)
    if not hasattr(est, "get_params"):
        return est
    unset = {}
    for k, v in est.get_params(deep=True).items():
        if v is not None:
            continue
        if seed is not None and (k == "random_state" or k.endswith("__random_state")):
            unset[k] = seed
        elif k == "rate_hz" or k.endswith("__rate_hz"):
            unset[k] = float(rate_hz)
    if unset:
        est.set_params(**unset)
    return est


class OnEncoded(ClassifierMixin, BaseEstimator):
    """``estimator`` fitted on the rows ``encoded[X]`` of a data set encoded once (``X``:
    sample indices, :func:`~sim_tactile.learn.precomputed.sample_index`). ``encoded`` is what
    the user's encoder returned for all samples: an array (rows are samples) or a list."""

    def __init__(self, estimator: Any, encoded: Any) -> None:
        self.estimator = estimator
        self.encoded = encoded

    def _rows(self, X: Any):
        idx = np.asarray(X).reshape(-1)
        if isinstance(self.encoded, np.ndarray):
            return self.encoded[idx]
        return [self.encoded[int(i)] for i in idx]

    def fit(self, X: Any, y: Any) -> OnEncoded:
        self.estimator_ = clone(self.estimator).fit(self._rows(X), y)
        self.classes_ = getattr(self.estimator_, "classes_", np.unique(y))
        return self

    def predict(self, X: Any) -> np.ndarray:
        return np.asarray(self.estimator_.predict(self._rows(X)))


def method_protocol(
    method: Method, data: np.ndarray, rate_hz: float, encode_once: bool, time_points_s, seed: int
):
    """What :func:`~sim_tactile.learn.protocols.evaluate` takes for ``method``: ``(X, make,
    times_s, encode_s)``. ``make(repeat)`` builds the repeat's estimator (seeded)."""

    def est(r: int):
        return prepared(method.estimator, derive_seed(seed, "model", method.name, r), rate_hz)

    if method.encoder is not None and encode_once:
        t0 = time.perf_counter()
        enc = prepared(method.encoder, None, rate_hz)
        encoded = _user_call(method, "encoder", lambda: enc.fit_transform(data))
        if len(encoded) != len(data):
            raise ConfigError(
                f"method {method.name!r}: its encoder returned {len(encoded)} rows for "
                f"{len(data)} samples; valid: one per sample"
            )
        enc_s = time.perf_counter() - t0
        return sample_index(len(data)), lambda r: OnEncoded(est(r), encoded), (), enc_s
    if method.encoder is not None:

        def pair(r: int):
            enc = prepared(method.encoder, None, rate_hz)
            return Pipeline([("encoder", enc), ("estimator", est(r))])

        return data, pair, tuple(time_points_s), 0.0
    return data, est, tuple(time_points_s), 0.0


def _user_call(method: Method, what: str, fn):
    try:
        return fn()
    except ConfigError:
        raise
    except Exception as exc:  # noqa: BLE001 (the user's code: say whose and what)
        raise ConfigError(
            f"method {method.name!r}: its {what} raised {type(exc).__name__}: {exc}"
        ) from exc


def classify_methods(spec, ds, methods, n_rep, results, wall, splits, quick, seed, log) -> float:
    """The user's methods under the task's split (:mod:`.methods`), into ``results`` and
    ``wall``; returns the time their encoders took on the whole data set (encode once)."""
    settings = spec.settings(quick)
    split = settings.split or spec.split
    enc_total = 0.0
    for m in methods:
        if split not in splits or len(splits[split]) < n_rep[m.name]:
            splits[split] = task_splits(ds.labels, split, max(n_rep.values()), seed)
        log(
            f"{spec.id}: {m.name} (your method: {m.describe()}), split {split}, {n_rep[m.name]} repeat(s)"
        )
        t0 = time.perf_counter()
        run_m = m
        if m.encoder is TASK_ENCODER:  # the task's own encoder, as its built-in rows have it
            run_m = replace(m, encoder=Pipeline(spec.encoder(spec.context(ds, quick))))
        x, make, times_s, enc_s = method_protocol(
            run_m, ds.data, ds.rate_hz, spec.encode_once, settings.time_points_s, seed
        )
        enc_total += enc_s
        results[m.name] = _user_call(
            m,
            "estimator (fitting or predicting)",
            lambda m=m, x=x, make=make, times_s=times_s: evaluate(
                make,
                x,
                ds.labels,
                splits[split][: n_rep[m.name]],
                times_s=times_s,
                rate_hz=ds.rate_hz,
                time_repeats=settings.time_repeats,
                log=log,
                name=m.name,
            ),
        )
        wall[m.name] = time.perf_counter() - t0 - enc_s
        r = results[m.name]
        log(f"{spec.id}: {m.name} accuracy {r.mean:.3f} +- {r.std:.3f} ({wall[m.name]:.1f} s)")
    return enc_total


def method_row(spec: TaskSpec, m: Method, r: EvalResult, wall_s: float, quick: bool) -> ResultRow:
    extra = {k: v for k, v in r.to_json().items() if k not in ("accuracy_mean", "accuracy_std")}
    extra.update(user_method=True, method=m.describe(), encoder=m.encoder_kind)
    return ResultRow(
        classifier=m.name,
        label=m.name,
        features=USER_FEATURES,
        accuracy_mean=round(r.mean, 4),
        accuracy_std=round(r.std, 4),
        accuracy_ci95=interval_list(r.accuracies),
        paper=None,
        repeats=len(r.accuracies),
        comparison={"status": "no paper value", "message": "your method"},
        wall_s=round(wall_s, 2),
        channels="all",
        split=spec.settings(quick).split or spec.split,
        extra=extra,
    )
