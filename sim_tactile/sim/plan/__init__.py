"""What to solve, and on which grid: the slide's protocol (:mod:`.protocol`), the probe rig
(:mod:`.rig`), the fidelity planner (:mod:`.fidelity`) with the errors measured against
physics (:mod:`.measured_errors`), and the lines of the grids that follow the plate's walls
(:mod:`.lattices`). Nothing here loads MuJoCo or numba (an import-linter contract forbids
both, and a test imports the planner in a fresh process), so a slide can be described and
planned without the simulator."""

from __future__ import annotations

from ..._lazy import lazy_exports

#: The public names and the module that defines each (loaded on first use).
_EXPORTS = {
    "Protocol": ".protocol",
    "SlideWindow": ".protocol",
    "ProbeRig": ".rig",
    "Fidelity": ".fidelity",
    "choose_fidelity": ".fidelity",
    "StepOptions": ".options",
    "Slide": ".slide",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
