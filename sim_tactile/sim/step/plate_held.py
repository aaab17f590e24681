"""The held steps that solve on cells of the plate's own rather than on the pad's node
lattice: patches clipped at the walls and the taxels' edges
(:class:`~sim_tactile.sim.skin.clipped.ClippedPatches`) and the lattice anchored to the
plate's walls (:class:`~sim_tactile.sim.skin.anchored.AnchoredLattice`). Each is a
:class:`~.held.HeldStep`."""

from __future__ import annotations

from ..skin.anchored import AnchoredLattice
from ..skin.clipped import ClippedPatches


class PlateHeldStep:
    """The frame of a held step that solves on cells of the plate's own: the pad's position
    on the plate is ``x0 + qpos[jx]``, its lowest point ``z0 + qpos[jz]`` above the base;
    ``c`` the cells' solver, ``area`` the pad lattice's node area (the total it is given is a
    pressure summed over those nodes)."""

    def __init__(self, cells, base_area_m2: float, x0: float, z0: float, jx: int):
        self.c = cells
        self.area = base_area_m2
        self.x0, self.z0, self.jx = x0, z0, jx

    def pose(self, qpos, jz) -> tuple[float, float]:
        """``(x_pad, z_low)``: the pad centre's x on the plate and its lowest point's height
        above the base [m]."""
        return self.x0 + float(qpos[self.jx]), self.z0 + float(qpos[jz])


class ClippedHeldStep(PlateHeldStep):
    """The held step on clipped patches (:class:`ClippedPatches`)."""

    c: ClippedPatches

    def describe(self) -> str:
        return (
            f"patches clipped at the walls and taxel edges ({self.c.sy.size - 1} rows, "
            f"{self.c.sx.size - 1} static columns)"
        )

    def step(self, qpos, jz, total, taxel_out) -> tuple[float, float]:
        x_pad, z_low = self.pose(qpos, jz)
        (cx, cy, hx, hy, cell, _), cand, p, d = self.c.solve(x_pad, z_low, total * self.area)
        qpos[jz] -= d
        loads = p * (4 * hx[cand] * hy[cand])
        self.c.taxel_loads(cell[cand], loads, out=taxel_out)
        return float(loads.sum()), self.c.deepest


class AnchoredHeldStep(PlateHeldStep):
    """The held step on the anchored lattice (:class:`AnchoredLattice`)."""

    c: AnchoredLattice

    def describe(self) -> str:
        c = self.c
        return (
            f"lattice anchored to the plate's walls ({c.m} columns per {c.P * 1e3:.3g} mm "
            f"period, {c.ny} rows, {c.n} cells in a {c.n_periods}-period window)"
        )

    def step(self, qpos, jz, total, taxel_out) -> tuple[float, float]:
        x_pad, z_low = self.pose(qpos, jz)
        dz, off = self.c.solve(x_pad, z_low, total * self.area)
        qpos[jz] -= dz
        self.c.taxel_loads(off, taxel_out)
        return float(self.c.f.sum()), float(self.c.pen.max())
