"""The MuJoCo scene of a slide and the skin's elasticity.

- :mod:`.model`: the plate and the finger whose skin nodes probe it, built with MjSpec;
- :mod:`.nodes`: the skin's nodes on the pad's undeformed surface;
- :mod:`.elastic`: the elastic half-space in closed form (Boussinesq, Love's rectangles);
- :mod:`.layered`: a stack of bonded layers on a backing, solved per wave number;
- :mod:`.tractions`: the skin's sliding tractions, their stress at depth and their normal
  deflection;
- :mod:`.spline_grid`: a periodic cubic spline read on a tensor grid of points.
"""

from __future__ import annotations

from .._lazy import lazy_exports

#: The public names and the module that defines each (loaded on first use).
_EXPORTS = {
    "Scene": ".model",
    "build_scene": ".model",
    "taxel_weights": ".model",
    "SkinGrid": ".nodes",
    "skin_grid": ".nodes",
    "compliance_matrix": ".elastic",
    "layered_compliance_matrix": ".layered",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
