"""The one place where a scene's collider, and the skin nodes' collider margin, are chosen."""

from __future__ import annotations

from .height import MapCollider, ProfileCollider
from .primitive import PrimitiveCollider
from .reference import MujocoCollider

#: Collider margin [m] of the skin nodes when the pad is held at a force: nodes this far above
#: the plate are reported, so they can join the contact when the pad sinks; a step that would
#: move the pad further than this is re-collided at the new height.
QS_MARGIN_M = 0.5e-3
#: The margin on roughness plates: the profile collider keeps the one MuJoCo's height-field
#: collider had there (each node within it was a contact MuJoCo generated, which filled its
#: contact buffer at 0.5 mm), so that their slides stayed unchanged but for the depths; a
#: step that sinks further is re-collided.
QS_MARGIN_MUJOCO_M = 0.1e-3


def node_margin_m(plate) -> float:
    """The skin nodes' collider margin for a held force on ``plate``: wide where the compiled
    collider serves (every plate of features, and height maps; it costs nothing there),
    narrow on roughness."""
    if plate.texture.kind == "roughness":
        return QS_MARGIN_MUJOCO_M
    return QS_MARGIN_M


def make_collider(scene, primitive: bool = True):
    """The compiled collider on a plate of features, the profile collider on a roughness
    plate, the map collider on a height map (each where ``primitive`` is set), else MuJoCo's.
    The bone must be at its starting pose (its world position is read here)."""
    if primitive:
        for kind in (PrimitiveCollider, ProfileCollider, MapCollider):
            c = kind.from_scene(scene)
            if c is not None:
                return c
    return MujocoCollider(scene)
