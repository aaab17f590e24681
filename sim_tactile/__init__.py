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
