"""The one place where a scene's collider is chosen (:func:`make_collider`), and the one
dispatch of the compiled depth kernels on a collider's ``probe`` (:func:`probe_depths`):
its class (:class:`~.primitive.PrimitiveProbe`, :class:`~.height.SurfaceProbe`) picks the
kernel, in compiled code, so a compiled caller (the held step) is compiled once per kind of
collider."""

from __future__ import annotations

from ..._jit import njit, when_numba
from ...plates.define.surface import surface_of
from .height import SurfaceCollider, SurfaceProbe, surface_depths
from .primitive import PrimitiveCollider, PrimitiveProbe, depths_kernel
from .reference import MujocoCollider


def make_collider(scene, primitive: bool = True):
    """The compiled collider of the scene's plate where ``primitive`` is set: the sampled
    surface's (:class:`~.height.SurfaceCollider`: a rough plate's profile, a height map), or
    the features' (:class:`~.primitive.PrimitiveCollider`); else, or where neither takes
    the plate, MuJoCo's (:class:`~.reference.MujocoCollider`, the reference). The bone must
    be at its starting pose (its world position is read here)."""
    if primitive:
        sampled = surface_of(scene.plate).arrays is not None
        c = (SurfaceCollider if sampled else PrimitiveCollider).from_scene(scene)
        if c is not None:
            return c
    return MujocoCollider(scene)


def node_depths(bone, probe, pen):
    """The depth map of ``probe`` (a compiled collider's ``probe``) for the bone at
    world position ``bone`` into ``pen``; whether any node is within its margin (compiled
    code only: :func:`probe_depths` from Python)."""
    raise NotImplementedError("node_depths runs in compiled code only")


def _node_depths(bone, probe, pen):
    kind = getattr(probe, "instance_class", None)
    if kind is PrimitiveProbe:
        return lambda bone, probe, pen: depths_kernel(
            bone,
            probe.local,
            probe.radius,
            probe.margin,
            probe.kind,
            probe.pos,
            probe.mat,
            probe.size,
            probe.top,
            probe.origin,
            probe.cell,
            probe.shape,
            probe.start,
            probe.items,
            probe.cell_top,
            pen,
        )
    if kind is SurfaceProbe:
        return lambda bone, probe, pen: surface_depths(
            bone, probe.local, probe.radius, probe.margin, probe.surface, probe.order, pen
        )
    return None


@when_numba
def _register(numba) -> None:
    """The compiled implementation of :func:`node_depths`."""
    from numba.extending import overload

    overload(node_depths)(_node_depths)


@njit
def probe_depths(bone, probe, pen):
    """:func:`node_depths`, callable from Python and from compiled code: the compiled
    collider's depth map (its own kernel, the same numbers) for the bone at ``bone`` (3,)."""
    return node_depths(bone, probe, pen)
