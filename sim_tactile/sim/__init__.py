"""The simulation, in floors that read as its pipeline, each importing only those below:

- :mod:`.plan`: what to solve, and on which grid: the slide's protocol, the probe rig, the
  fidelity planner with its measured errors, and the lattices that follow the plate's walls.
  No MuJoCo and no compiled kernel (an import contract forbids both);
- :mod:`.collide`: each skin node's depth in the plate;
- :mod:`.skin`: pressures from depths: the skin models and the contact solvers;
- :mod:`.step`: one step: the held step (its interface declared once, chosen in
  :func:`~.step.choose.make_held_step`), the runner, the sample averaging;
- the drivers on top: :mod:`.slide` (:func:`run` of a :class:`~.plan.slide.Slide`,
  :func:`simulate`, :func:`prepare`),
  :mod:`.static_press` (:func:`press`) and :mod:`.rig_sim` (the probe rig's slide), beside
  :mod:`.micro` (micro-roughness through the contact patch) and :mod:`.plots`.

The names of :data:`__all__` load their module on first use (PEP 562), so that
``Protocol`` describes a slide without loading MuJoCo and ``simulate`` loads it when asked
for. This package imports none of its modules itself: a module's code version (and a
compiled kernel's cache stamp) follows only what that module imports.
"""

from __future__ import annotations

from .._lazy import lazy_exports

#: The public names and the module that defines each.
_EXPORTS = {
    "Protocol": ".plan.protocol",
    "SlideWindow": ".plan.protocol",
    "Fidelity": ".plan.fidelity",
    "choose_fidelity": ".plan.fidelity",
    "StepOptions": ".plan.options",
    "Slide": ".plan.slide",
    "run": ".slide",
    "SimResult": ".step.sampling",
    "simulate": ".slide",
    "prepare": ".slide",
    "press": ".static_press",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
