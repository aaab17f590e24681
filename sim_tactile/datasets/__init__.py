"""Data sets: loaders of real sensor data into :class:`~sim_tactile.records.TactileDataset`,
and data sets in Zarr stores (``sim-tactile generate``): :func:`open` reads one lazily,
:func:`from_tactile` writes any TactileDataset (e.g. the real recordings) in the same form,
:func:`export` writes plain numpy files."""

from __future__ import annotations

from .real import load_biotac, load_icub
from .store import SlideStore, StoreError, export, from_tactile, open_store, parts_of

#: ``sim_tactile.datasets.open(path, part=None)``: a store's data set, read lazily
open = open_store  # noqa: A001

__all__ = [
    "SlideStore",
    "StoreError",
    "export",
    "from_tactile",
    "load_biotac",
    "load_icub",
    "open",
    "open_store",
    "parts_of",
]
