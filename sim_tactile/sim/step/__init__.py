"""One step of the finger: the held step's interface and its compiled and plain forms
(:mod:`.held`), the held steps on the plate's own cells (:mod:`.plate_held`), the one
function that chooses among them (:mod:`.choose`), the runner that steps MuJoCo
(:mod:`.runner`) and the sample averaging the drivers share (:mod:`.sampling`)."""

from __future__ import annotations

from ..._lazy import lazy_exports

#: The public names and the module that defines each (loaded on first use).
_EXPORTS = {
    "HeldStep": ".held",
    "PlainHeldStep": ".held",
    "CompiledHeldStep": ".held",
    "ClippedHeldStep": ".plate_held",
    "AnchoredHeldStep": ".plate_held",
    "make_held_step": ".choose",
    "Runner": ".runner",
    "SimResult": ".sampling",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
