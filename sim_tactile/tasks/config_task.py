"""A configuration file's slide set as a task: ``sim-tactile run my-set.toml`` scores it.

The file is a ``generate`` configuration (:mod:`sim_tactile.slides.config`) with an optional
``[evaluate]`` table::

    [evaluate]
    classifiers = ["svm-raw", "svm-spike"]   # names of sim_tactile.learn (the default)
    split = "7:3"                            # train:test per class, or "n_train/n_test"
    repeats = 5                              # random splits (quick: 2)

Its task id is ``config:<name>`` (the file's ``name``, else its file name). ``run`` simulates
what the slide cache does not hold, or with ``--store`` reads the store that ``generate``
made of the same file, after checking that the store holds this configuration (its hash and
the slide code's version).
"""

from __future__ import annotations

from pathlib import Path

from .. import _validate as v
from ..errors import ConfigError
from ..learn.classifiers import classifier_names
from ..slides.config import config_slide_set, is_config_path, load_config  # noqa: F401
from .registry import Settings, TaskSpec

#: The id prefix of a configuration's task.
PREFIX = "config:"
EVALUATE_KEYS = ("classifiers", "split", "repeats")
DEFAULT_CLASSIFIERS = ("svm-raw", "svm-spike")


def config_task(path: str | Path) -> tuple[TaskSpec, int]:
    """The task of the configuration file ``path`` (its slide set, scored as ``[evaluate]``
    says) and the file's seed. Every value is checked before anything runs."""
    path = Path(path)
    cfg = load_config(path)
    where = f"configuration file {path}"
    ev = cfg.pop("evaluate", {})
    if not isinstance(ev, dict):
        raise ConfigError(f"{where}: evaluate must be a table, got {ev!r}")
    v.known_keys(where, ev, EVALUATE_KEYS, prefix="evaluate.")
    names = ev.get("classifiers", list(DEFAULT_CLASSIFIERS))
    if not isinstance(names, list) or not names:
        raise ConfigError(f"{where}: evaluate.classifiers must be a non-empty list, got {names!r}")
    for n in names:
        v.one_of("evaluate.classifiers", n, classifier_names())
    split = ev.get("split", "7:3")
    if not isinstance(split, str):
        raise ConfigError(f'{where}: evaluate.split must be a string such as "7:3", got {split!r}')
    repeats = v.integer("evaluate.repeats", ev.get("repeats", 5), 1, 10_000)
    ss, seed, name = config_slide_set(cfg, where, path.parent)
    spec = TaskSpec(
        id=PREFIX + (name or path.stem),
        title=f"the slide set of {path.name}",
        get_data=ss,
        classifiers=tuple(names),
        split=split,
        full=Settings(repeats=repeats),
        quick=Settings(repeats=min(2, repeats)),
        remarks=(
            f"A configuration file's slide set ({path.name}), not a released task: "
            f"{len(ss.plates)} plates, {ss.slides} slides each ({ss.quick_slides} quick), "
            f"sensor {ss.sensor}.",
        ),
    )
    return spec, seed
