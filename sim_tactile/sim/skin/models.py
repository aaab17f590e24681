"""Skin models: from the nodes' penetration depths to their contact pressures.

A skin model answers three questions about the pad's skin, each on the penetration-depth map
of its nodes (m, ``-inf`` for nodes out of reach):

- ``solve``: the pressures [Pa] where the pad is;
- ``solve_force``: the pressures and the shift ``dz`` [m] of the pad at which they sum
  to a given total (the pad held at a normal force);
- ``stiffness``: the pad's contact stiffness [N/m] at its current contact.

:func:`make_skin` chooses one for a fidelity level, in one place:

- :class:`WinklerSkin` (L0): a local elastic foundation ``p = k max(pen, 0)``, no coupling
  between nodes, ``k = E* / thickness``;
- :class:`CoupledSkin` (L1, L2): an elastic skin whose nodes are coupled by a dense
  compliance ``C`` (a load on one node deflects its neighbours), solved exactly as a linear
  complementarity problem (:class:`~sim_tactile.sim.skin.contact.ActiveSet`). ``C`` is the
  elastic half-space's (:func:`~sim_tactile.scene.elastic.compliance_matrix`), or, when the
  finger has a ``stack``, that of its bonded layers on their backing
  (:func:`~sim_tactile.scene.layered.layered_compliance_matrix`); any symmetric positive
  definite compliance of the node grid takes the same path.

- :class:`SpectralSkin` (L1, L2 on many nodes): the same skin, its compliance applied as a
  convolution by FFT and the contact solved by constrained conjugate gradients
  (:class:`~sim_tactile.sim.skin.contact.spectral.Spectral`): no dense matrix, cost ``N log N``
  per iteration. :func:`make_skin` takes it above :data:`DENSE_MAX_NODES` nodes.

When the finger's skin carries its sliding friction (``Finger.skin_tractions``) and the skin
is not an incompressible half-space, the tractions ``q = mu p`` against the slide deflect
the surface normally too (:func:`~sim_tactile.scene.tractions.shear_normal_compliance`): the
normal problem's compliance becomes ``C - mu D``, no longer symmetric: the contact solve's
block updates then take their general formulas (``symmetric=False``).
"""

from __future__ import annotations

import numpy as np

from ...cache import SETUP, npz_bytes, read_arrays, setup_memo
from ...errors import ConfigError
from ...hashing import array_digest, blas_kernel, code_version, content_hash, one_blas_thread
from ...scene.elastic import compliance_matrix, compliance_table
from ...scene.layered import Stack, layered_compliance_matrix, layered_compliance_table
from ...scene.nodes import SkinGrid
from ...scene.tractions import shear_normal_compliance
from ...sensors.pad import Finger
from ..plan.fidelity import DENSE_MAX_NODES, friction_coupled
from . import contact
from .contact.spectral import TOL, Spectral


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


def _stack_name(st: Stack) -> str:
    layers = " / ".join(
        f"{la.thickness_m * 1e3:g} mm E {la.young_pa:.3g} Pa nu {la.poisson:g}" for la in st.layers
    )
    return f"layered skin: {layers} on a {st.backing} backing"


class _SolvedSkin:
    """What the coupled skins share: their ``solver`` answers the contact problem."""

    coupled = True

    def solve(self, pen_m: np.ndarray) -> np.ndarray:
        p, _ = self.solver.solve(pen_m)
        return p

    def solve_force(self, pen_m: np.ndarray, total_pa: float) -> tuple[np.ndarray, float]:
        return self.solver.solve_force(pen_m, total_pa)


class CoupledSkin(_SolvedSkin):
    """A skin of compliance ``C`` [m/Pa] (N x N) with, optionally, its inverse ``K``, which
    makes large contact sets cheap (:class:`~sim_tactile.sim.skin.contact.ActiveSet`). The solver
    keeps its contact set from one call to the next."""

    def __init__(
        self, C: np.ndarray, K: np.ndarray | None = None, what: str = "", *, symmetric: bool = True
    ) -> None:
        #: whether C is symmetric (reciprocity; no friction coupling); the contact solve's
        #: block updates take the general formulas when it is not
        self.symmetric = symmetric
        self.C, self.K = C, K
        self.solver = contact.ActiveSet(C, K, symmetric=symmetric)
        self.what = what
        #: the content key of ``C`` and ``K`` when they came through the set-up memo (what
        #: is derived from them, e.g. a mirror-halved solve's, is kept under it), else None
        self.key: str | None = None

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
        if _friction_coupled(finger):
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
        what = _stack_name(st)
        if _friction_coupled(finger):
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

    def stiffness(self, p: np.ndarray, area_m2: float) -> float:
        """``area * 1' inv(C_SS) 1`` on the current contact set [N/m]."""
        return area_m2 * self.solver.stiffness_per_area()

    def describe(self) -> str:
        return self.what or f"coupled skin of {self.C.shape[0]} nodes"


class SpectralSkin(_SolvedSkin):
    """A translation-invariant skin (half-space or stack of layers) on a node lattice, its
    contact solved spectrally (:class:`~sim_tactile.sim.skin.contact.spectral.Spectral`). Same
    interface and answers as :class:`CoupledSkin` (tested), without its dense matrices."""

    symmetric = True

    def __init__(self, table: np.ndarray, what: str = "", tol: float | None = None) -> None:
        self.solver = Spectral(table, tol=TOL if tol is None else tol)
        self.what = what

    @classmethod
    def of(cls, grid: SkinGrid, finger: Finger, tol: float | None = None) -> SpectralSkin:
        """The finger's skin (its stack, else the half-space) on ``grid``'s lattice; ``tol``:
        its solve's tolerance (None: the reference, :data:`~.contact.spectral.TOL`)."""
        nx, ny = grid.lattice
        st = finger.stack
        if st is None:
            what = f"elastic half-space, E* {finger.e_star_pa:.4g} Pa"
        else:
            what = _stack_name(st)
        parts = {"lattice": [nx, ny, grid.pitch_m, grid.pitch_y_m], "finger": finger.to_json()}
        (table,) = setup_memo(
            "spectral compliance table", parts, lambda: (_table(grid, finger),), SKIN_MODULES
        )
        to = "" if tol is None else f" to {tol:g}"
        return cls(table, f"{what}; spectral solve on {nx} x {ny} nodes{to}", tol)

    def stiffness(self, p: np.ndarray, area_m2: float) -> float:
        """``area * 1' inv(C_SS) 1`` on the contact set of ``p`` [N/m]."""
        return area_m2 * self.solver.stiffness_per_area(p)

    def describe(self) -> str:
        return self.what


def _table(grid: SkinGrid, finger: Finger) -> np.ndarray:
    """The finger's compliance kernel on ``grid``'s lattice (its stack's, else the
    half-space's)."""
    nx, ny = grid.lattice
    if finger.stack is None:
        return compliance_table(nx, ny, grid.pitch_m, finger.e_star_pa, grid.pitch_y_m)
    return layered_compliance_table(nx, ny, grid.pitch_m, finger.stack, grid.pitch_y_m)


#: Fewest nodes whose dense arrays go through the cache: a process computes a smaller skin's
#: (361 nodes: 8 ms; 729 nodes, pvdf2's: 60 ms, 0.2 s the first time in a process, where a
#: read of its 8.5 MB took 8 ms).
CACHE_MIN_NODES = 400
#: What the dense compliance and its inverse are computed by: their cache key holds the
#: source of these modules (and what they import) and the libraries' versions.
SKIN_MODULES = (__name__,)
SKIN_LIBRARIES = ("numpy", "scipy")


def _dense_key(grid: SkinGrid, finger: Finger, slide_dir, inverse: bool) -> str:
    """The content key of a coupled skin's dense arrays: the node grid (its centres
    whole), the finger (skin, stack, friction), the slide's direction, whether the inverse
    is kept, the code that computes them, and the BLAS kernel they are computed on (another
    CPU's kernel makes them bit-different in their last places: a slide that read them would
    then match neither kernel's own, bit for bit)."""
    return content_hash(
        {
            "what": "dense skin compliance",
            "xy": array_digest(np.asarray(grid.xy, dtype=np.float64)),
            "pitch_m": grid.pitch_m,
            "pitch_y_m": grid.pitch_y_m,
            "finger": finger.to_json(),
            "slide_dir": list(slide_dir),
            "inverse": inverse,
            "code": code_version(*SKIN_MODULES, libraries=SKIN_LIBRARIES),
            "blas": blas_kernel(),
        }
    )


def _cached_dense(grid, finger, slide_dir, inverse, cache) -> CoupledSkin:
    """:class:`CoupledSkin` of the finger on ``grid``, its arrays kept in this process
    (the set-up memo, :data:`~sim_tactile.cache.SETUP`: the BioTac's 2835 nodes make two
    64 MB matrices, which a slide had read from disk anew) or read from ``cache`` (an
    :class:`~sim_tactile.cache.ArtefactCache`) when they were computed before, else computed and stored there: the compliance of a
    large pad and its inverse take seconds (2835 nodes: 4 s and 3 s), reading them a tenth
    of that. The arrays are the computed ones bit for bit, so a slide does not depend on
    where they came from (tested)."""
    key = _dense_key(grid, finger, slide_dir, inverse)
    kept = SETUP.get(key)
    if kept is not None:
        return _keyed(key, *kept)
    names = ("C", "what", "symmetric", *(("K",) if inverse else ()))
    z = read_arrays(cache, key, "skin.npz", "a skin", names)
    if z is not None:
        C, K = z["C"], (z["K"] if inverse else None)
        what, symmetric = str(z["what"]), bool(z["symmetric"])
        SETUP.put(key, (C, K, what, symmetric))
        return _keyed(key, C, K, what, symmetric)
    skin = _dense(grid, finger, slide_dir, inverse)
    _store(cache, key, skin.C, skin.K, skin.what, skin.symmetric)
    SETUP.put(key, (skin.C, skin.K, skin.what, skin.symmetric))
    skin.key = key
    return skin


def _store(cache, key, C, K, what, symmetric) -> None:
    arrays = {"C": C, "what": np.array(what), "symmetric": np.array(symmetric)}
    if K is not None:
        arrays["K"] = K
    cache.put(key, "skin.npz", npz_bytes(arrays))  # its bytes: a function of the arrays


def _memo_dense(grid, finger, slide_dir, inverse) -> CoupledSkin:
    """:class:`CoupledSkin` of the finger on ``grid``, its arrays kept in this process
    (:data:`~sim_tactile.cache.SETUP`, by the disk cache's key) and not on disk: a small
    skin's (below :data:`CACHE_MIN_NODES`, whose arrays are about as quick to compute as to
    read)."""
    key = _dense_key(grid, finger, slide_dir, inverse)
    kept = SETUP.get(key)
    if kept is None:
        skin = _dense(grid, finger, slide_dir, inverse)
        kept = SETUP.put(key, (skin.C, skin.K, skin.what, skin.symmetric))
    return _keyed(key, *kept)


def _keyed(key, C, K, what, symmetric) -> CoupledSkin:
    skin = CoupledSkin(C, K, what, symmetric=symmetric)
    skin.key = key
    return skin


def _dense(grid, finger, slide_dir, inverse) -> CoupledSkin:
    """The dense skin, computed on one BLAS thread as a slide computes it, wherever it is
    asked for (BLAS's threads sum in another order: arrays kept under one key must not
    depend on who made them first; see :func:`~sim_tactile.cache.setup_memo`)."""
    with one_blas_thread():
        if finger.stack is not None:
            return CoupledSkin.layered(grid, finger, inverse=inverse, slide_dir=slide_dir)
        return CoupledSkin.half_space(grid, finger, inverse=inverse, slide_dir=slide_dir)


#: The contact solvers of a coupled skin.
SOLVERS = ("auto", "dense", "spectral")

SkinModel = WinklerSkin | CoupledSkin | SpectralSkin


_friction_coupled = friction_coupled  # its home is the planner's, which asks too


def make_skin(
    level: str,
    grid: SkinGrid,
    finger: Finger,
    *,
    winkler_k_pa_per_m: float,
    inverse: bool = True,
    slide_dir: tuple[float, float] = (1.0, 0.0),
    solver: str = "auto",
    tol: float | None = None,
    cache=None,
) -> SkinModel:
    """The skin model of a fidelity level: L0 the Winkler bed, L1 and L2 the coupled
    half-space (or the finger's layered stack). ``inverse``: also invert the compliance
    (cheap large contact sets; skip it for one static solve on a fine grid). ``slide_dir``:
    the direction the pad slides in, for a skin that carries its friction. ``solver``:
    ``dense``, ``spectral`` or ``auto`` (spectral above :data:`DENSE_MAX_NODES` nodes; a skin
    whose friction enters the normal problem is always dense). ``cache``: an
    :class:`~sim_tactile.cache.ArtefactCache` that keeps a dense skin's arrays from one slide
    to the next (from :data:`CACHE_MIN_NODES` nodes; a smaller skin's arrays are kept in the
    process only, by the same key, as computing them is as quick as reading them). ``tol``:
    the spectral solve's tolerance (None: its reference, :data:`~.contact.spectral.TOL`)."""
    if solver not in SOLVERS:
        raise ConfigError(f"solver = {solver!r}; valid: {', '.join(SOLVERS)}")
    if level == "L0":
        return WinklerSkin(winkler_k_pa_per_m)
    spectral = solver == "spectral" or (solver == "auto" and grid.n > DENSE_MAX_NODES)
    if spectral and _friction_coupled(finger):
        if solver == "spectral":
            raise ConfigError(
                "solver = 'spectral' needs a symmetric compliance; this finger's sliding "
                "friction enters its normal problem (valid: solver 'dense' or 'auto')"
            )
        spectral = False
    if spectral:
        return SpectralSkin.of(grid, finger, tol=tol)
    if grid.n < CACHE_MIN_NODES:
        return _memo_dense(grid, finger, slide_dir, inverse)
    if cache is not None:
        return _cached_dense(grid, finger, slide_dir, inverse, cache)
    return _dense(grid, finger, slide_dir, inverse)
