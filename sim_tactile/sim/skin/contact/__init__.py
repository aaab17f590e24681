"""Quasi-static skin contact: from the penetration-depth map of the undeformed pad to the
pressure on each skin node.

- :func:`winkler`: local elastic foundation, ``p = k_w * pen`` (no coupling).
- :func:`halfspace`: elastic contact of a coupled skin, the linear complementarity problem
  ``p >= 0, C p >= pen, p (C p - pen) = 0`` solved exactly by an active-set method (the
  deflection of the surface, ``u = C p``, must lift every penetrating node out of the plate;
  nodes whose deflection would lift them further carry no load). ``C`` is the dense
  compliance of the skin (:mod:`sim_tactile.sim.skin.models`): the elastic coupling.
- :class:`ActiveSet`: the same problem solved step after step, its inverse kept up to date,
  and held at a given normal force (:meth:`ActiveSet.solve_force`); its compiled kernels are
  in :mod:`.kernels`.

Only nodes that penetrate (pen > 0) can carry load: u = C p >= 0 everywhere, so a node that
does not touch the undeformed pad cannot be pushed into the plate by its neighbours.

:mod:`.reference` holds the plain solutions the fast paths are tested against.
"""

from __future__ import annotations

from .active_set import JOINT_REFRESH, REFRESH, ActiveSet
from .reference import MAX_ITER, TOL_REL, halfspace, winkler, winkler_force

__all__ = [
    "JOINT_REFRESH",
    "MAX_ITER",
    "REFRESH",
    "TOL_REL",
    "ActiveSet",
    "halfspace",
    "winkler",
    "winkler_force",
]
