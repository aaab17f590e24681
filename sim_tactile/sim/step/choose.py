"""The one place where a slide's held step is chosen (:func:`make_held_step`)."""

from __future__ import annotations

import numpy as np

from ...errors import ConfigError
from ..plan.fidelity import Fidelity
from ..plan.lattices import check_anchorable, check_clippable
from ..skin.anchored import AnchoredLattice
from ..skin.clipped import ClippedPatches
from ..skin.models import SkinModel, SpectralSkin
from .held import CompiledHeldStep, HeldStep, PlainHeldStep
from .plate_held import AnchoredHeldStep, ClippedHeldStep


def node_margin(scene) -> float:
    """The skin nodes' collider margin [m] of ``scene`` (0 without nodes)."""
    nodes = np.flatnonzero(scene.node_of_geom >= 0)
    return float(scene.m_col.geom_margin[nodes[0]]) if nodes.size else 0.0


def make_held_step(
    scene,
    skin: SkinModel,
    collider,
    fid: Fidelity,
    *,
    plate,
    layout,
    finger,
    quasi_static: bool,
    x0_m: float,
    y0_m: float,
    z0_m: float,
    compiled: bool = True,
    reduce: bool = True,
    joint: bool = False,
) -> HeldStep | None:
    """The held step of a slide, chosen in this one place: None unless the force is held
    quasi-statically (``quasi_static``), else

    - the lattice anchored to the plate's walls where the fidelity names one (``wall_m``);
    - else patches clipped at the walls and the taxels' edges where it says so (``clipped``);
    - else the whole step in one compiled call where the collider is compiled, ``compiled``
      is set and the skin is dense (:class:`CompiledHeldStep`, on the reduced problem where
      ``reduce``, a changed contact set solved together with the height where ``joint``);
    - else the plain loop over the collider and the skin (:class:`PlainHeldStep`).

    A fidelity whose grid the scene does not serve is refused (ConfigError), under any
    force control. The pad's centre starts at ``(x0_m, y0_m)`` on the plate, its lowest point
    ``z0_m`` above the base [m]."""
    area = scene.grid.area_m2
    hold = None
    if fid.wall_m is not None:
        check_anchorable(plate, layout, fid.level, finger, quasi_static)
        lattice = AnchoredLattice(
            finger, layout, plate, y0_m, fid.pitch_m, fid.pitch_y_m, fid.wall_m
        )
        hold = AnchoredHeldStep(lattice, area, x0=x0_m, z0=z0_m, jx=scene.jx)
    elif fid.clipped:
        check_clippable(fid.level, finger, quasi_static)
        cells = ClippedPatches(scene.grid, finger, layout, plate, y0_m)
        hold = ClippedHeldStep(cells, area, x0=x0_m, z0=z0_m, jx=scene.jx)
    if not quasi_static:
        return None
    margin = node_margin(scene)
    if not margin > 0:
        raise ConfigError("quasi-static force control needs skin nodes with a collider margin")
    if hold is not None:
        return hold
    dense = not isinstance(skin, SpectralSkin)  # the compiled step is dense
    if collider.compiled and compiled and dense:
        return CompiledHeldStep(collider, skin, scene.W, area, margin, reduce, joint=joint)
    return PlainHeldStep(collider, skin, scene.W, area, margin)
