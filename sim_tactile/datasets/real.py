"""Loaders of the real data behind seed paper 000 (20 materials x 50 slides).

The data set is the public ``BioTac_slide_20_50`` release; the project never ships it. Give
its folder (the one holding ``raw_data/`` and ``compiled_data/``) as ``path``.

- :func:`load_biotac`: the raw BioTac CSVs ``raw_data/matX/matX_N_bio.csv`` (X = material
  1..20, N = slide 1..50, 100 Hz). As in the paper, the 19 electrode channels ``ele1..ele19``
  from the 1st to the 5th second: 400 samples.
- :func:`load_icub`: the compiled iCub forearm RoboSkin arrays
  ``compiled_data/icub_{test,val_0,..,val_3}.npy`` (each ``(200, 6, 10, 75)`` float32: 6
  patches x 10 taxels, 75 samples at 50 Hz = 1.5 s) with their ``labels_*.npy``.

Both return a :class:`~sim_tactile.records.TactileDataset` with labels 0..19. BioTac label
``X - 1`` is material ``matX``; the iCub labels are those of the release's label files, which
it shares with its compiled BioTac files (the materials are common to both sensors), so class
``k`` is named ``mat{k+1}`` for both.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._validate import integer, positive
from ..errors import ConfigError
from ..records import TactileDataset

N_MATERIALS = 20
N_SLIDES = 50
BIOTAC_RATE_HZ = 100.0
BIOTAC_ELECTRODES = tuple(f"ele{k}" for k in range(1, 20))
ICUB_RATE_HZ = 50.0
ICUB_FILES = ("test", "val_0", "val_1", "val_2", "val_3")
ICUB_GRID = (6, 10)
SOURCE = "dexrob/BioTac_slide_20_50 (Taunyazov et al. 2020, IROS)"


def _root(path: object, what: str, needed: str) -> Path:
    if path is None:
        raise ConfigError(
            f"the {what} data set needs its folder: pass --data PATH (the "
            f"biotac_slide_20_50 folder holding {needed})"
        )
    root = Path(path).expanduser()
    if not root.is_dir():
        raise ConfigError(
            f"data path {str(root)!r} does not exist or is not a folder; pass --data PATH "
            f"pointing at the biotac_slide_20_50 folder (holding {needed})"
        )
    if not (root / needed).exists():
        raise ConfigError(
            f"data path {str(root)!r} has no {needed}; pass --data PATH pointing at the "
            f"biotac_slide_20_50 folder"
        )
    return root


def read_biotac_csv(
    file: Path, *, start: int, n_samples: int, channels: tuple[str, ...] = BIOTAC_ELECTRODES
) -> np.ndarray:
    """The named columns of one BioTac CSV, rows ``start .. start + n_samples``: (T, C)."""
    with open(file, encoding="ascii") as fh:
        header = fh.readline().strip().split(",")
    missing = [c for c in channels if c not in header]
    if missing:
        raise ConfigError(f"{file} has no column(s) {missing}; is it a BioTac recording?")
    cols = [header.index(c) for c in channels]
    rows = np.loadtxt(file, delimiter=",", skiprows=1, usecols=cols, dtype=np.float64, ndmin=2)
    if rows.shape[0] < start + n_samples:
        raise ConfigError(
            f"{file} has {rows.shape[0]} samples; the window needs rows {start} to "
            f"{start + n_samples - 1}"
        )
    return rows[start : start + n_samples]


def load_biotac(
    path: object,
    *,
    start_s: float = 1.0,
    duration_s: float = 4.0,
    slides: int = N_SLIDES,
    materials: int = N_MATERIALS,
) -> TactileDataset:
    """BioTac slides ``(materials * slides, 400, 19)``: electrodes, ``start_s`` to
    ``start_s + duration_s`` (paper: 1 s to 5 s) at 100 Hz, in the sensor's raw counts.

    ``slides`` / ``materials`` take the first slides of the first materials (for quick tests).
    """
    root = _root(path, "BioTac", "raw_data/")
    start = round(positive("start_s", start_s, unit="s") * BIOTAC_RATE_HZ)
    n = round(positive("duration_s", duration_s, unit="s") * BIOTAC_RATE_HZ)
    slides = integer("slides", slides, 1, N_SLIDES)
    materials = integer("materials", materials, 1, N_MATERIALS)
    data, labels = [], []
    for m in range(1, materials + 1):
        for s in range(1, slides + 1):
            f = root / "raw_data" / f"mat{m}" / f"mat{m}_{s}_bio.csv"
            if not f.is_file():
                raise ConfigError(f"BioTac file {str(f)!r} is missing from the data set")
            data.append(read_biotac_csv(f, start=start, n_samples=n))
            labels.append(m - 1)
    return TactileDataset(
        np.stack(data).astype(np.float32),
        np.asarray(labels),
        BIOTAC_RATE_HZ,
        BIOTAC_ELECTRODES,
        tuple(f"mat{m}" for m in range(1, materials + 1)),
        units="BioTac electrode counts",
        meta={
            "sensor": "biotac19",
            "source": SOURCE,
            "path": str(root),
            "window_s": [float(start_s), float(start_s + duration_s)],
        },
    )


def load_icub(path: object) -> TactileDataset:
    """iCub RoboSkin slides ``(1000, 75, 60)`` at 50 Hz; channel ``p{patch}t{taxel}``
    (6 patches x 10 taxels, patch-major: ``meta["grid_shape"] = [6, 10]``)."""
    root = _root(path, "iCub", "compiled_data/")
    data, labels = [], []
    for name in ICUB_FILES:
        fx = root / "compiled_data" / f"icub_{name}.npy"
        fy = root / "compiled_data" / f"labels_{name}.npy"
        for f in (fx, fy):
            if not f.is_file():
                raise ConfigError(f"iCub file {str(f)!r} is missing from the data set")
        x = np.load(fx, allow_pickle=False)
        y = np.load(fy, allow_pickle=False)
        if x.ndim != 4 or x.shape[1:3] != ICUB_GRID or x.shape[0] != y.shape[0]:
            raise ConfigError(
                f"{fx} has shape {x.shape} with {y.shape[0]} labels; expected "
                f"(n, 6, 10, 75) and n labels"
            )
        data.append(x.reshape(x.shape[0], -1, x.shape[-1]).transpose(0, 2, 1))
        labels.append(y)
    names = tuple(f"p{p}t{t}" for p in range(ICUB_GRID[0]) for t in range(ICUB_GRID[1]))
    y = np.concatenate(labels).astype(np.int64)
    return TactileDataset(
        np.concatenate(data).astype(np.float32),
        y,
        ICUB_RATE_HZ,
        names,
        tuple(f"mat{k + 1}" for k in range(int(y.max()) + 1)),
        units="RoboSkin capacitance counts",
        meta={
            "sensor": "icub60",
            "source": SOURCE,
            "path": str(root),
            "grid_shape": list(ICUB_GRID),
            "files": list(ICUB_FILES),
        },
    )
