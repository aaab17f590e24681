"""sim_tactile: a physics-simulated benchmark for tactile texture perception.

Data flows one way: plate -> scene -> simulation -> recording -> encoder -> spikes ->
classifier -> report. Heavy dependencies (cadquery, torch) are imported only by the stages
that need them.
"""

from __future__ import annotations

__version__ = "0.1.0"

from .errors import (  # noqa: F401  (re-exported)
    ConfigError,
    GeometryError,
    MissingDependencyError,
    PhysicsError,
    SimTactileError,
    UnknownNameError,
)


def __getattr__(name: str):
    """``sim_tactile.TactileTorchDataset``, the PyTorch ``Dataset``
    (:class:`~sim_tactile.formats.torch_data.TactileTorchDataset`), imported when first
    named, so that ``import sim_tactile`` does not import torch."""
    if name == "TactileTorchDataset":
        from .formats.torch_data import TactileTorchDataset

        return TactileTorchDataset
    raise AttributeError(f"module 'sim_tactile' has no attribute {name!r}")
