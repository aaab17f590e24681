"""Data sets: loaders of real sensor data into :class:`~sim_tactile.records.TactileDataset`."""

from __future__ import annotations

from .real import load_biotac, load_icub

__all__ = ["load_biotac", "load_icub"]
