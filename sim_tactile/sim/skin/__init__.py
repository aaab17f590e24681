"""Pressures from depths: the skin models (:mod:`.models`: Winkler, the coupled half-space
or stack, spectral), the contact solvers (:mod:`.contact`), and the solvers on the plate's
own cells: patches clipped at the walls (:mod:`.clipped`) and the lattice anchored to them
(:mod:`.anchored`)."""

from __future__ import annotations

from ..._lazy import lazy_exports

#: The public names and the module that defines each (loaded on first use).
_EXPORTS = {
    "WinklerSkin": ".models",
    "CoupledSkin": ".models",
    "SpectralSkin": ".models",
    "make_skin": ".models",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
