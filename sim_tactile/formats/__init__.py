"""Bridges to the formats of the libraries the package's users stand on.

- :mod:`.events`: spikes as Tonic events (``x``, ``y``, ``t`` in us, ``p``) and
  :class:`~.events.TactileEvents`, a data set of ``(events, target)`` (extra ``[tonic]``);
- :mod:`.torch_data`: :class:`~.torch_data.TactileTorchDataset`, a PyTorch ``Dataset`` that
  reads a store lazily, raw or encoded, with a task's splits (extra ``[learn]``);
- :mod:`.hub`: ``sim-tactile export --format parquet``: Parquet shards of a task's splits, a
  dataset card and Croissant metadata (extra ``[hub]``).

The spiking network's NIR graph and the NeuroBench figures live with the network:
:mod:`sim_tactile.learn.nir`, :mod:`sim_tactile.learn.neurobench`.
"""

__all__ = ["TactileTorchDataset"]


def __getattr__(name: str):
    """``sim_tactile.formats.TactileTorchDataset``, the PyTorch ``Dataset``
    (:class:`~.torch_data.TactileTorchDataset`), imported when first named, so that
    importing the package does not import torch."""
    if name == "TactileTorchDataset":
        from .torch_data import TactileTorchDataset

        return TactileTorchDataset
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
