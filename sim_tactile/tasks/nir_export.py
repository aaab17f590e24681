"""``run --export-nir FILE.nir``: the spiking network a run trained (its last repeat) as a NIR
graph (:mod:`sim_tactile.learn.nir`), its output neurons named by the task's classes
(``classes``, as its report names them; a simulated task's plates in ``plates``), with the
task, the row and the encoding that makes its input in the metadata.

Checked before the run starts (:func:`check_nir_export`): the run has an ``snn`` row, the
nir library is installed and the file's folder exists. The file is written to a temporary
name beside it and renamed when whole."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..errors import ConfigError, require
from .registry import Run, TaskSpec


def nir_row(runs: list[Run]) -> Run | None:
    """The row whose network is exported: the first ``snn`` row on all channels, else the
    first ``snn`` row; None where there is none."""
    snn = [r for r in runs if r.classifier == "snn"]
    whole = [r for r in snn if r.channels == "all"]
    return (whole or snn or [None])[0]


def check_nir_export(path: str | Path, spec: TaskSpec, runs: list[Run]) -> Path:
    """``path`` checked against the run: an ``.nir`` file in an existing folder, a run with
    an ``snn`` row, the nir library present."""
    path = Path(path)
    if spec.parts:
        raise ConfigError(
            f"--export-nir saves one network; task {spec.id} is a suite of "
            f"{', '.join(spec.parts)}: run one of them"
        )
    if nir_row(runs) is None:
        raise ConfigError(
            f"--export-nir {path}: the run has no snn row to export; valid: a run with snn "
            "(e.g. --classifiers snn,svm-spike)"
        )
    if path.suffix.lower() != ".nir":
        raise ConfigError(f"--export-nir {str(path)!r}: valid: a file name ending in .nir")
    if not path.parent.is_dir():
        raise ConfigError(f"--export-nir {path}: folder {str(path.parent)!r} does not exist")
    require("nir", "nir")
    return path


def export_snn(path: Path, model: Any, spec: TaskSpec, run: Run, class_names, repeats: int):
    """Write the fitted ``model`` (the snn row's Pipeline, or its SNNClassifier) to
    ``path`` as a NIR graph; returns the path."""
    from ..learn.nir import write_nir

    snn = model.steps[-1][1] if hasattr(model, "steps") else model
    graph = snn.to_nir(class_names=list(class_names))
    graph.metadata.update(
        task=spec.id,
        row=run.name,
        repeat=f"the last of {repeats}",
        encoding=f"{spec.encoding}; then a 0/1 raster at dt_s",
    )
    plates = getattr(spec.get_data, "plates", None)  # a simulated task's, in class order
    if plates is not None and len(plates) == len(class_names):
        graph.metadata["plates"] = [str(p) for p in plates]
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        write_nir(graph, tmp)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
    return path
