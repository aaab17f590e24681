"""Data sets: loaders of real sensor data into :class:`~sim_tactile.records.TactileDataset`,
and data sets in Zarr stores (``sim-tactile generate``): :func:`open` reads one lazily,
:func:`from_tactile` writes any TactileDataset (e.g. the real recordings) in the same form,
:func:`export` writes plain numpy files."""

from __future__ import annotations

from ..errors import StoreError
from .export import export, from_tactile
from .reader import SlideStore, open_store, parts_of
from .real import load_biotac, load_icub

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
