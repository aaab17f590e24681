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

from __future__ import annotations

from .._lazy import lazy_exports

#: The public names and the module that defines each (loaded on first use: torch, Tonic and
#: the data hubs' libraries only when a name that needs them is read).
_EXPORTS = {
    "TactileEvents": ".events",
    "EventLayout": ".layout",
    "TactileTorchDataset": ".torch_data",
    "export_parquet": ".hub",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
