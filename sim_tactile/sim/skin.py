"""Skin models: from the nodes' penetration depths to their contact pressures.

A skin model answers three questions about the pad's skin, each on the penetration-depth map
of its nodes (m, ``-inf`` for nodes out of reach):

- :meth:`solve`: the pressures [Pa] where the pad is;
- :meth:`solve_force`: the pressures and the shift ``dz`` [m] of the pad at which they sum
  to a given total (the pad held at a normal force);
- :meth:`stiffness`: the pad's contact stiffness [N/m] at its current contact.

:func:`make_skin` chooses one for a fidelity level, in one place:

- :class:`WinklerSkin` (L0): a local elastic foundation ``p = k max(pen, 0)``, no coupling
  between nodes, ``k = E* / thickness``;
- :class:`CoupledSkin` (L1, L2): an elastic skin whose nodes are coupled by a dense
  compliance ``C`` (a load on one node deflects its neighbours), solved exactly as a linear
  complementarity problem (:class:`~sim_tactile.sim.contact.ActiveSet`). ``C`` is the
  elastic half-space's (:func:`~sim_tactile.scene.elastic.compliance_matrix`), or, when the
  finger has a ``stack``, that of its bonded layers on their backing
  (:func:`~sim_tactile.scene.layered.layered_compliance_matrix`); any symmetric positive
  definite compliance of the node grid takes the same path.

When the finger's skin carries its sliding friction (``Finger.skin_tractions``) and the skin
is not an incompressible half-space, the tractions ``q = mu p`` against the slide deflect
the surface normally too (:func:`~sim_tactile.scene.layered.shear_normal_compliance`): the
normal problem's compliance becomes ``C - mu D``, no longer symmetric: the contact solve's
block updates then take their general formulas (``symmetric=False``).
"""

from __future__ import annotations

import numpy as np

from ..scene.elastic import compliance_matrix
from ..scene.layered import Stack, layered_compliance_matrix
from ..scene.nodes import SkinGrid
from ..scene.tractions import shear_normal_compliance
from ..sensors.pad import Finger
from . import contact


class WinklerSkin:
    """The Winkler bed of stiffness ``k_pa_per_m`` [Pa/m]."""

    coupled = False

    def __init__(self, k_pa_per_m: float) -> None:
        self.k = float(k_pa_per_m)

    def solve(self, pen_m: np.ndarray) -> np.ndarray:
        return contact.winkler(pen_m, self.k)

    def solve_force(self, pen_m: np.ndarray, total_pa: float) -> tuple[np.ndarray, float]:
        return contact.winkler_force(pen_m, self.k, total_pa)

    def stiffness(self, p: np.ndarray, area_m2: float) -> float:
        """Nodes in contact times their stiffness ``k * area`` [N/m]."""
        return self.k * area_m2 * float(np.count_nonzero(p))

    def describe(self) -> str:
        return f"Winkler bed, k {self.k:.4g} Pa/m"


class CoupledSkin:
    """A skin of compliance ``C`` [m/Pa] (N x N) with, optionally, its inverse ``K``, which
    makes large contact sets cheap (:class:`~sim_tactile.sim.contact.ActiveSet`). The solver
    keeps its contact set from one call to the next."""

    coupled = True

    def __init__(
        self, C: np.ndarray, K: np.ndarray | None = None, what: str = "", *, symmetric: bool = True
    ) -> None:
        #: whether C is symmetric (reciprocity; no friction coupling); the contact solve's
        #: block updates take the general formulas when it is not
        self.symmetric = symmetric
        self.C, self.K = C, K
        self.solver = contact.ActiveSet(C, K, symmetric=symmetric)
        self.what = what

    @classmethod
    def half_space(
        cls,
        grid: SkinGrid,
        finger: Finger,
        *,
        inverse: bool = True,
        slide_dir: tuple[float, float] = (1.0, 0.0),
    ) -> CoupledSkin:
        """The elastic half-space of the finger's plane-strain modulus on ``grid``'s nodes
        (with friction's coupling when the skin carries it and is compressible)."""
        C = compliance_matrix(grid.xy, grid.pitch_m, finger.e_star_pa, pitch_y_m=grid.pitch_y_m)
        what = f"elastic half-space, E* {finger.e_star_pa:.4g} Pa"
        if finger.skin_tractions and finger.friction > 0 and finger.poisson < 0.5:
            stack = Stack.half_space(finger.thickness_m, finger.young_pa, finger.poisson)
            C, what = cls._with_friction(C, grid, finger, stack, slide_dir, what)
            return cls(C, np.linalg.inv(C) if inverse else None, what, symmetric=False)
        return cls(C, np.linalg.inv(C) if inverse else None, what)

    @classmethod
    def layered(
        cls,
        grid: SkinGrid,
        finger: Finger,
        *,
        inverse: bool = True,
        slide_dir: tuple[float, float] = (1.0, 0.0),
    ) -> CoupledSkin:
        """The finger's stack of bonded layers on its backing, on ``grid``'s nodes (with
        friction's coupling when the skin carries it)."""
        st = finger.stack
        C = layered_compliance_matrix(grid.xy, grid.pitch_m, st, pitch_y_m=grid.pitch_y_m)
        layers = " / ".join(
            f"{la.thickness_m * 1e3:g} mm E {la.young_pa:.3g} Pa nu {la.poisson:g}"
            for la in st.layers
        )
        what = f"layered skin: {layers} on a {st.backing} backing"
        if finger.skin_tractions and finger.friction > 0:
            C, what = cls._with_friction(C, grid, finger, st, slide_dir, what)
            return cls(C, np.linalg.inv(C) if inverse else None, what, symmetric=False)
        return cls(C, np.linalg.inv(C) if inverse else None, what)

    @staticmethod
    def _with_friction(C, grid, finger, stack, slide_dir, what):
        """``C - mu D``: the tractions ``mu p`` against the slide (along ``-slide_dir``)
        deflect the surface too."""
        D = shear_normal_compliance(
            grid.xy, grid.pitch_m, stack, pitch_y_m=grid.pitch_y_m, direction=slide_dir
        )
        return (
            C - finger.friction * D,
            f"{what}, coupled to sliding friction mu {finger.friction:g}",
        )

    def solve(self, pen_m: np.ndarray) -> np.ndarray:
        p, _ = self.solver.solve(pen_m)
        return p

    def solve_force(self, pen_m: np.ndarray, total_pa: float) -> tuple[np.ndarray, float]:
        return self.solver.solve_force(pen_m, total_pa)

    def stiffness(self, p: np.ndarray, area_m2: float) -> float:
        """``area * 1' inv(C_SS) 1`` on the current contact set [N/m]."""
        return area_m2 * self.solver.stiffness_per_area()

    def describe(self) -> str:
        return self.what or f"coupled skin of {self.C.shape[0]} nodes"


SkinModel = WinklerSkin | CoupledSkin


def make_skin(
    level: str,
    grid: SkinGrid,
    finger: Finger,
    *,
    winkler_k_pa_per_m: float,
    inverse: bool = True,
    slide_dir: tuple[float, float] = (1.0, 0.0),
) -> SkinModel:
    """The skin model of a fidelity level: L0 the Winkler bed, L1 and L2 the coupled
    half-space (or the finger's layered stack). ``inverse``: also invert the compliance
    (cheap large contact sets; skip it for one static solve on a fine grid). ``slide_dir``:
    the direction the pad slides in, for a skin that carries its friction."""
    if level == "L0":
        return WinklerSkin(winkler_k_pa_per_m)
    if finger.stack is not None:
        return CoupledSkin.layered(grid, finger, inverse=inverse, slide_dir=slide_dir)
    return CoupledSkin.half_space(grid, finger, inverse=inverse, slide_dir=slide_dir)
