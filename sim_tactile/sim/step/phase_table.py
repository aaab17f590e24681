"""The skin's answer tabulated over one texture period: :class:`PhaseTable`.

Where a held slide's loads are a function of the pad's phase in the plate's period
(:func:`~sim_tactile.sim.plan.phase.phase_plan`), :func:`tabulate` solves the held step
(:class:`~.held.HeldStep`, the same one the per-step slide calls) at phases of one period and
keeps, per phase, the taxel loads [N], the normal force [N], the deepest node [m] and the
pad's height; a step of the slide reads them off the table, linearly between the two phases
on either side (:meth:`PhaseTable.at`). The phases are chosen adaptively: a first even grid
of about one phase per node pitch, then every interval whose midpoint's loads differ from
the line between its ends by more than :data:`PHASE_TOL` of the loads' RMS is halved, down
to :data:`MIN_PHASE_FRACTION` of a node pitch; the largest midpoint difference that remains
is the table's own error estimate (:attr:`PhaseTable.error`). A uniform stretch (a flat
plate) is one phase. A rough profile with no period (:func:`~sim_tactile.sim.plan.span.span_plan`)
is tabulated the same way over positions along its whole stretch, which never wrap round.
The tables the slides of a set share, and their cache, are in :mod:`.shared_tables`.

The table is solved in a scene of its own, from the plan's reference position (not from
the slide's history), so the same plan, grid and force give the same table bit for bit,
whichever slide asks first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...errors import PhysicsError
from ..plan.phase import PhasePlan
from ..plan.span import SPAN_MIN_FRACTION
from .held import HeldStep

#: Largest midpoint difference, relative to the loads' RMS over the table (the RMS over
#: phases of the taxel-load vector's norm), at which an interval is not halved again. The
#: slide reads the loads between phases off a line; measured against the per-step solve on
#: every task scene (perf/bench_phase.py), this keeps whole slides well within 2% (relative
#: L2 of the taxel loads).
PHASE_TOL = 0.005
#: Smallest interval between two phases, as a share of the node pitch along the slide: the
#: loads jump where a node row crosses a wall, and a finer table narrows the jump's smear
#: only as the square root of its interval (measured on the iCub's gratings, 0.51% -> 0.23%
#: relative L2 over a slide from 1 to 1/8 of a step's travel); a quarter of the pitch is
#: about the travel of one of the iCub's steps (56 um at 0.224 mm nodes against 34-73 um).
MIN_PHASE_FRACTION = 1 / 8
#: Most phases one table may hold.
MAX_PHASES = 1024
#: Most positions a table over a stretch with no period may hold (a profile's: the iCub's
#: 120 mm strips start with some 300, one a node pitch).
MAX_SPAN_PHASES = 4096
#: A phase's held step is taken again from the height it found until the height moves by
#: less than this [m]: the held step collides once more only where the pad moved beyond the
#: collider's margin, so from a height far from its answer (a table's first phase, sunk from
#: above the plate) it stops on a depth map read up to half a millimetre away, where a
#: node deep in a narrow feature is read to its nearest face: on finger7's bumps one taxel
#: was 4-35% off until the step was taken again from where it ended (the per-step slide
#: starts each step from the last one's height, microns away). Measured: a second step
#: moves the height by microns, a third by tens of nanometres, a fourth by none.
SETTLE_M = 1e-8
#: The same for a table's phases [m], looser: a phase starts from the last one's height
#: (or its neighbours'), microns from its own, as a per-step slide's step starts from the
#: last step's, and a vertical move shifts every depth by itself except where a node crosses
#: a wall. Measured on six task plates (finger7, multilayer3, BioTac and iCub; ideal loads
#: over a slide): the table's loads move by at most 0.01% (relative L2) against settling to
#: :data:`SETTLE_M`, and the iCub's boxes table costs 25% less.
PHASE_SETTLE_M = 1e-6
#: Most times a phase's held step is taken (see :data:`SETTLE_M`).
SETTLE_STEPS = 8


@dataclass(frozen=True)
class PhaseTable:
    """A held slide's answer over one period (see the module docstring): ``phases`` (K,)
    [m] in ``[0, period)``, sorted, and per phase the taxel ``loads`` (K, N) [N], the normal
    ``force`` (K,) [N], the deepest node ``top`` (K,) [m] and the pad's lowest point ``z``
    (K,) [m above the plate's base surface]; ``solves`` held steps made it; ``error`` is the
    largest relative midpoint difference left (0 for one phase)."""

    plan: PhasePlan
    phases: np.ndarray
    loads: np.ndarray
    force: np.ndarray
    top: np.ndarray
    z: np.ndarray
    solves: int
    error: float

    @property
    def n_taxels(self) -> int:
        return self.loads.shape[1]

    def at(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(loads (n, N), force (n,), top (n,), z (n,))`` of the pad centred at ``x`` (n,)
        [m], each in the plan's interior: linear in the phase between the table's phases
        (the last phase joins the first one period on)."""
        x = np.asarray(x, dtype=float)
        period = self.plan.period_m
        k = len(self.phases)
        if k == 1 or self.plan.uniform:
            idx = np.zeros(x.shape, dtype=np.intp)
            return self.loads[idx], self.force[idx], self.top[idx], self.z[idx]
        if self.plan.span:  # positions along the stretch, its ends included: no wrap
            grid = self.phases
            phi = np.clip(x - self.plan.x_ref, grid[0], grid[-1])
            i = np.clip(np.searchsorted(grid, phi, side="right") - 1, 0, k - 2)
            j = i + 1
        else:
            phi = np.mod(x - self.plan.x_ref, period)
            grid = np.append(self.phases, period)
            i = np.clip(np.searchsorted(grid, phi, side="right") - 1, 0, k - 1)
            j = (i + 1) % k
        w = (phi - grid[i]) / (grid[i + 1] - grid[i])

        def lerp(a: np.ndarray) -> np.ndarray:
            wa = w if a.ndim == 1 else w[:, None]
            return (1.0 - wa) * a[i] + wa * a[j]

        return lerp(self.loads), lerp(self.force), lerp(self.top), lerp(self.z)

    def describe(self) -> str:
        if self.plan.uniform:
            return f"phase table: {self.plan.describe()}, 1 phase"
        kind, unit = self.plan.units
        solved = ""
        if self.solves < len(self.phases):
            solved = f" ({self.solves} solved, the rest their mirror images)"
        return (
            f"{kind} table: {self.plan.describe()}, {len(self.phases)} {unit}{solved}, "
            f"interpolation error below {max(self.error, 1e-6):.2g} of the loads"
        )


def tabulate(
    hold: HeldStep,
    qpos: np.ndarray,
    jx: int,
    jz: int,
    x_scene_m: float,
    z_scene_m: float,
    plan: PhasePlan,
    total_pa: float,
    n_taxels: int,
    pitch_m: float,
    tol: float = PHASE_TOL,
    check=None,
    many=None,
    mirror=None,
    finest: float = SPAN_MIN_FRACTION,
) -> PhaseTable:
    """Solve ``hold`` over one period of ``plan`` (see the module docstring). ``qpos``: the
    table scene's joint positions at rest (its pad centred at ``x_scene_m``, its lowest point
    ``z_scene_m`` above the base at ``qpos[jz] = 0``), copied, never written; ``total_pa``:
    the force as the held step takes it (the node pressures' sum [Pa]); ``pitch_m``: the node
    pitch along the slide, which sets the first grid and the smallest interval (neither
    depends on the slide's speed or step, so slides at any speed share a table), and
    ``finest`` that of a table along the slide (:func:`~sim_tactile.sim.plan.span.span_fraction`).
    ``check(z, force, top)``: raises where a solved phase is not trustworthy
    (:meth:`~.runner.Runner.check_held`). ``mirror``: ``(s, write)`` where the problem at
    phase ``s + u`` is the mirror image of the one at ``s - u`` (:mod:`.mirror`),
    ``write(out)`` the taxel loads of the last step's image: then half a period, ``(s, s +
    P/2)``, is solved and refined, the other half read off the images (on the CPU; a
    device's batch solves the whole period), its phases kept as ``u``, from ``s``."""
    q = np.array(qpos, dtype=float)
    solved: dict[float, tuple] = {}
    period = plan.period_m
    if many is not None or period is None:
        mirror = None
    shift, image = mirror if mirror is not None else (0.0, None)

    def solve(u: float) -> None:
        out = np.zeros(n_taxels)
        q[jx] = plan.x_ref + shift + u - x_scene_m
        for _ in range(SETTLE_STEPS):  # until the height it ends at is the one it read
            z = float(q[jz])
            force, top = hold.step(q, jz, total_pa, out)
            if abs(float(q[jz]) - z) <= PHASE_SETTLE_M:
                break
        mirrored = None
        if image is not None:
            mirrored = np.zeros(n_taxels)
            image(mirrored)
        keep(u, out, float(force), float(top), float(q[jz]), mirrored)

    def keep(u: float, out, force: float, top: float, z: float, mirrored=None) -> None:
        if not (np.isfinite(force) and np.isfinite(out).all()):
            raise PhysicsError("the skin load is not finite (NaN or infinity)")
        if check is not None:
            check(z, force, top)
        solved[u] = (out, force, top, float(z_scene_m + z), mirrored)

    def solve_all(phis, near=None) -> None:
        """Solve ``phis``, one after another or at once (``many``), each from the mean height
        of its solved neighbours ``near`` (None: the last one's height, the first the scene's
        start above the plate): a pad started far below its height misreads depths (a node
        deep in a narrow feature is read to its nearest face)."""
        z0 = near and [0.5 * (solved[a][3] + solved[b % period][3]) - z_scene_m for a, b in near]
        if many is None:
            for k, phi in enumerate(phis):
                if z0:
                    q[jz] = z0[k]
                solve(float(phi))
            return
        qs = np.repeat(q[None, :], len(phis), axis=0)
        qs[:, jx] = plan.x_ref + np.asarray(phis, dtype=float) - x_scene_m
        if z0:
            qs[:, jz] = z0
        outs, forces, tops = _settle_many(many, qs, jz, total_pa, n_taxels)
        for k, phi in enumerate(phis):
            keep(float(phi), outs[k], float(forces[k]), float(tops[k]), float(qs[k, jz]))
        q[jz] = qs[-1, jz]

    if plan.span:  # the whole stretch, its ends included, refined without a wrap
        period = math.inf  # (the refinement's neighbours: b % inf is b)
        return _span_table(solve_all, solved, plan, pitch_m, pitch_m * finest, tol)
    if period is None:
        solve(0.0)
        return _table(plan, solved, 0.0)
    if image is None:
        n0 = max(4, int(np.ceil(period / pitch_m)))
        solve_all([float(phi) for phi in np.arange(n0) * (period / n0)])
        todo = [(float(a), float(b)) for a, b in zip(*_ends(sorted(solved), period), strict=True)]
    else:  # half a period, short of its symmetric ends by half the smallest interval
        # (see _half_grid), each phase with its image
        us = _half_grid(period, pitch_m)
        solve_all(us)
        todo = list(zip(us[:-1], us[1:], strict=True))[::-1]  # back from where it ended
    most = MAX_PHASES if image is None else MAX_PHASES // 2
    smallest = pitch_m * MIN_PHASE_FRACTION
    worst = _refine(solve_all, solved, todo, period, smallest, tol, most, image is not None)
    if image is None:
        return _table(plan, solved, worst)
    return _table(plan, _unfold(solved, shift, period), worst, solves=len(solved))


def _span_table(solve_all, solved: dict, plan: PhasePlan, pitch_m: float, smallest, tol):
    """The table of a stretch with no period (``plan.span``): an even grid of about one
    position a node pitch from its start to its end, both included, refined as a period's
    phases are (down to intervals of ``smallest`` [m]) but never wrapping round, up to
    :data:`MAX_SPAN_PHASES` positions."""
    length = plan.x_hi - plan.x_lo
    n0 = max(2, int(np.ceil(length / pitch_m)))
    us = [float(u) for u in np.arange(n0 + 1) * (length / n0)]
    solve_all(us)
    todo = list(zip(us[:-1], us[1:], strict=True))
    worst = _refine(solve_all, solved, todo, math.inf, smallest, tol, MAX_SPAN_PHASES, False)
    return _table(plan, solved, worst)


def _settle_many(many, qs: np.ndarray, jz: int, total_pa: float, n_taxels: int):
    """The held steps of the poses ``qs`` (B, nq) at once, each taken again until its height
    moves by less than :data:`PHASE_SETTLE_M` (written into ``qs``); their taxel loads
    (B, N), normal forces (B,) and deepest nodes (B,)."""
    b = len(qs)
    outs, forces, tops = np.zeros((b, n_taxels)), np.zeros(b), np.zeros(b)
    rows = np.arange(b)
    for _ in range(SETTLE_STEPS):  # each until the height it ends at is the one it read
        z = qs[rows, jz].copy()
        sub, out = qs[rows], np.zeros((len(rows), n_taxels))
        f, t = many.step_many(sub, jz, total_pa, out)
        qs[rows], outs[rows], forces[rows], tops[rows] = sub, out, f, t
        rows = rows[np.abs(sub[:, jz] - z) > PHASE_SETTLE_M]
        if not rows.size:
            break
    return outs, forces, tops


def _refine(solve_all, solved: dict, todo: list, period, smallest, tol, most, turn) -> float:
    """Halve the intervals ``todo`` (pairs of solved phases), pass after pass, while an
    interval's midpoint differs from the line between its ends by more than ``tol`` of the
    loads' RMS, down to ``smallest`` and up to ``most`` phases; returns the largest
    difference left. A full period's passes wrap around to where they began; half a period's
    (``turn``) turn back at its end: a dense step whose pad jumps half a period rebuilt its
    contact set (0.9 s on the iCub's cylinders, against 2 ms a step)."""
    scale = _rms(solved)
    worst = 0.0
    while todo:
        nxt = []
        solve_all([0.5 * (a + b) for a, b in todo], todo)
        for a, b in todo:
            mid = 0.5 * (a + b)
            fa, fb = solved[a][0], solved[b % period][0]
            err = float(np.linalg.norm(solved[mid][0] - 0.5 * (fa + fb))) / scale
            if err > tol and (b - a) / 2 > smallest and len(solved) < most:
                nxt += [(a, mid), (mid, b)]
            else:
                worst = max(worst, err)
        todo = sorted(nxt, reverse=todo[0] < todo[-1]) if turn else nxt
    return worst


def _half_grid(period: float, pitch_m: float) -> list[float]:
    """The first phases ``u`` of a mirrored table, from the mirror's centre: an even grid of
    about one a node pitch over ``[d, P/2 - d]``, ``d`` half the smallest interval
    (:data:`MIN_PHASE_FRACTION`), so that the line across each symmetric point joins a phase
    and its image one smallest interval apart. Not from the symmetric points themselves:
    on a texture whose features are whole node pitches wide (the BioTac's 6 mm grating, 3 mm
    ridges, 0.75 mm nodes) a grid from there put a row of nodes exactly on a wall at every
    phase of it, where a node's depth is either side of the step (that grating's mirrored
    table read 1.97% off the per-step slide, relative L2, and 1.45% from this grid; such
    ridges on a dense step take no mirror since: :func:`~.mirror.mirrored_loads`)."""
    d = 0.5 * pitch_m * MIN_PHASE_FRACTION
    span = 0.5 * period - 2.0 * d
    n0 = max(2, int(np.ceil(span / pitch_m)))
    return [d + float(u) for u in np.arange(n0 + 1) * (span / n0)]


def _unfold(solved: dict, shift: float, period: float) -> dict:
    """Half a period's phases ``u`` in ``(0, P/2)`` from the mirror's centre ``shift``, as
    the table's phases ``(shift + u) mod P``, each with its image at ``(shift - u) mod P``:
    the same force, deepest node and height, the mirrored loads."""
    out = {}
    for u, (loads, force, top, z, mirrored) in solved.items():
        out[_wrap(shift + u, period)] = (loads, force, top, z)
        out[_wrap(shift - u, period)] = (mirrored, force, top, z)
    return out


def _wrap(phi: float, period: float) -> float:
    """``phi mod period`` in ``[0, period)`` (a rounding up to the period itself is 0)."""
    phi = float(np.mod(phi, period))
    return 0.0 if phi >= period else phi


def _ends(phases: list[float], period: float) -> tuple[list[float], list[float]]:
    """The intervals between successive phases, the last closing at ``period``."""
    return phases, [*phases[1:], period]


def _rms(solved: dict) -> float:
    norms = [float(np.linalg.norm(v[0])) for v in solved.values()]
    rms = float(np.sqrt(np.mean(np.square(norms))))
    return rms if rms > 0 else 1.0


def _table(plan: PhasePlan, solved: dict, error: float, solves: int | None = None) -> PhaseTable:
    phases = np.array(sorted(solved))
    rows = [solved[p] for p in phases]
    return PhaseTable(
        plan,
        phases,
        np.array([r[0] for r in rows]),
        np.array([r[1] for r in rows]),
        np.array([r[2] for r in rows]),
        np.array([r[3] for r in rows]),
        len(solved) if solves is None else solves,
        float(error),
    )
