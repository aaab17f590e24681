"""Colliders: the penetration-depth map of the skin's probe spheres against the plate.

A collider answers one question, ``depths_at``
(:meth:`~.primitive.PrimitiveCollider.depths_at`): with the finger's joints at ``qpos``, how
deep is each skin node in the plate (``-inf`` where no plate geom lies within the node's
margin), and is any node that close. :func:`~.choose.make_collider` chooses one, in one place (the plate's
:func:`~sim_tactile.plates.define.surface.surface_of` says whether it is sampled):

- :class:`~.primitive.PrimitiveCollider`: a compiled narrow phase for plates of features: boxes,
  spherical caps, upright cylinders and drafted ridges (which MuJoCo holds as convex meshes).
  One numba loop, tested equal to MuJoCo's map at random poses on every plate kind.
- :class:`~.height.SurfaceCollider`: a sampled plate: a rough plate's profile z(x) across its
  textured area, or a height map (heights sampled on a grid, bilinear between them, NaN
  where there is no material), on its base: each node's depth below the surface at its
  centre, in one numba loop (the surface's own height, bit for bit). MuJoCo's height-field
  collider had served them, several contacts a node and at most 50 a field.
- :class:`~.reference.MujocoCollider`: MuJoCo's own collider on the scene's collision model, for any
  geometry: the reference the tests compare the others with, and the collider of a plate
  none of them takes (a mesh that is not a drafted ridge of the plate's features, a rotated
  plate). No preset plate steps it.
"""

from __future__ import annotations

from ..._lazy import lazy_exports

#: The public names and the module that defines each (loaded on first use).
_EXPORTS = {
    "PrimitiveCollider": ".primitive",
    "SurfaceCollider": ".height",
    "MujocoCollider": ".reference",
    "make_collider": ".choose",
}

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
