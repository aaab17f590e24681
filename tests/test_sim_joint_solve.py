"""The held force solved with its contact set (``joint_loop``, the loosened slides' held
solve) against the reference's Newton iteration on the shift (``force_loop``) and a
non-negative least-squares solve of the contact problem at the shift it found."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import nnls

from sim_tactile.scene.elastic import compliance_matrix
from sim_tactile.sim.skin.contact import JOINT_REFRESH, REFRESH, ActiveSet
from sim_tactile.sim.skin.contact.inverse import NO_K
from sim_tactile.sim.skin.contact.kernels import (
    NOT_TRIED,
    force_loop,
    force_same_set,
    joint_loop,
    set_trial,
)
from sim_tactile.sim.skin.contact.reference import MAX_ITER, TOL_REL

PITCH = 0.5e-3


def _grid():
    xs = (np.arange(25) - 12) * PITCH
    ys = (np.arange(9) - 4) * PITCH
    X, Y = np.meshgrid(xs, ys)
    return np.column_stack([X.ravel(), Y.ravel()])


def _skin(kind: str, xy: np.ndarray) -> np.ndarray:
    if kind == "half-space":
        return compliance_matrix(xy, PITCH, 0.3e6, pitch_y_m=PITCH)
    from sim_tactile.scene.layered import layered_compliance_matrix
    from sim_tactile.sensors.stack import Layer, Stack

    # a 1 mm layer on the bone: it bulges around a load (C < 0 off the diagonal's band)
    return layered_compliance_matrix(xy, PITCH, Stack((Layer(1e-3, 0.3e6, 0.5),)), pitch_y_m=PITCH)


def _depths(xy: np.ndarray, x0: float) -> np.ndarray:
    """Hemispherical caps of 1.5 mm radius, 4 mm apart, on a base 0.3 mm below their tops,
    under a flat pad whose level the caps' tops reach 50 um into: the pad slides ``x0``
    along them."""
    cx = np.round((xy[:, 0] + x0) / 4e-3) * 4e-3 - x0
    cy = np.round(xy[:, 1] / 4e-3) * 4e-3
    r2 = (xy[:, 0] - cx) ** 2 + (xy[:, 1] - cy) ** 2
    cap = np.sqrt(np.maximum(1.5e-3**2 - r2, 0.0)) - 1.2e-3
    return np.maximum(cap, 0.0) - 0.25e-3


def _total(C: np.ndarray, xy: np.ndarray) -> float:
    """The summed pressure of the pad pressed to the caps' level at the slide's start."""
    p, _ = ActiveSet(C).solve(_depths(xy, 0.0))
    return float(p.sum())


class _Joint(ActiveSet):
    """The held step's order (:func:`~sim_tactile.sim.step.held._held_kernel`): the set
    that holds, else the joint loop, else the Newton iteration from where it stopped."""

    def __init__(self, C, max_iter=MAX_ITER, refresh=REFRESH, reuse=True):
        super().__init__(C, np.linalg.inv(C), refresh)
        self.max_iter, self.joined, self.stopped, self.reuse = max_iter, 0, 0, reuse

    def solve_force(self, pen, total, max_iter=MAX_ITER):
        p = np.empty_like(pen)
        if self.S.size:
            M, S, in_set, C, _ = self.same_set_state()
            rowsum = M @ np.ones(S.size)  # as the held kernel forms it after a change
            tried = set_trial(M, S, pen, C, in_set, TOL_REL, total, rowsum, self.floor)
            dz, pS, drop, A = tried
            if dz == dz and not drop.any() and A.size == 0:
                p[:] = 0.0
                p[S] = pS
                return p, dz
            st, dz, M, S, updates, rb, b = joint_loop(
                *(self.M, self.S, self._in, self.C, self.K, pen, TOL_REL, float(total)),
                *(self.updates, self.refresh, self.max_iter, p, self.floor, True, self._cu),
                (rowsum, *tried) if self.reuse else NOT_TRIED,
            )
            self._take(M, S, updates, rb)
            if st == 1:
                assert np.array_equal(b, M @ np.ones(S.size))  # M 1 of the M it returns
                self.joined += 1
                return p, dz
            assert b.size == 0
            self.stopped += 1
        return super().solve_force(pen, total, max_iter)


def _reference(C: np.ndarray, pen: np.ndarray) -> np.ndarray:
    """min 1/2 p'Cp - pen'p, p >= 0 (whose KKT conditions are the contact problem), as an
    NNLS problem through the Cholesky factor C = L L': another solver of the same problem."""
    L = np.linalg.cholesky(C)
    p, _ = nnls(L.T, np.linalg.solve(L, pen), maxiter=10_000)
    return p


@pytest.mark.parametrize("kind", ["half-space", "layered"])
def test_the_joint_loop_holds_the_force_as_the_newton_iteration_does(kind):
    xy = _grid()
    C = _skin(kind, xy)
    total = _total(C, xy)
    ref, joint = ActiveSet(C, np.linalg.inv(C)), _Joint(C)
    for k in range(120):
        pen = _depths(xy, k * 0.13e-3)  # 65 mm/s, a solve every 2 ms
        p_ref, dz_ref = ref.solve_force(pen.copy(), total)
        p, dz = joint.solve_force(pen.copy(), total)
        assert p.sum() == pytest.approx(total, rel=1e-12)
        np.testing.assert_allclose(p, p_ref, rtol=0, atol=1e-9 * p_ref.max())
        assert dz == pytest.approx(dz_ref, rel=0, abs=1e-12)
        if k % 30 == 0:  # the same problem, by another solver
            want = _reference(C, pen + dz)
            np.testing.assert_allclose(p, want, rtol=0, atol=1e-7 * want.max())
    assert joint.joined > 40, "the sliding caps must change the set at many steps"
    assert joint.stopped == 0


@pytest.mark.parametrize("kind", ["half-space", "layered"])
def test_the_joint_loop_goes_on_from_the_failed_same_set_check_bit_for_bit(kind):
    """The held step passes the joint loop its failed same-set check (``tried``): the loop's
    first pass is not made again, and its answers, set and inverse are those it makes when
    it tries the set itself, bit for bit, at every step of a slide whose set changes."""
    xy = _grid()
    C = _skin(kind, xy)
    total = _total(C, xy)
    again, reused = _Joint(C, reuse=False), _Joint(C)
    for k in range(120):
        pen = _depths(xy, k * 0.13e-3)
        p_a, dz_a = again.solve_force(pen.copy(), total)
        p_r, dz_r = reused.solve_force(pen.copy(), total)
        assert np.array_equal(p_a, p_r) and dz_a == dz_r
        assert np.array_equal(again.S, reused.S) and np.array_equal(again.M, reused.M)
    assert reused.joined > 40 and reused.joined == again.joined


@pytest.mark.parametrize("kind", ["half-space", "layered"])
def test_the_joint_solves_inverse_is_rebuilt_where_its_drift_check_asks(kind):
    """``auto``'s joint held solve rebuilds its inverse where the drift check asks, not at
    the reference's fixed schedule: over a long slide its block updates pass
    :data:`REFRESH` with fewer rebuilds, and its pressures stay the reference's (whose
    inverse is rebuilt every REFRESH updates), its inverse the inverse of its set."""
    xy = _grid()
    C = _skin(kind, xy)
    total = _total(C, xy)
    ref, scheduled = ActiveSet(C, np.linalg.inv(C)), _Joint(C)
    joint = _Joint(C, refresh=JOINT_REFRESH)
    updates = 0
    for k in range(400):
        pen = _depths(xy, k * 0.13e-3)
        p_ref, dz_ref = ref.solve_force(pen.copy(), total)
        scheduled.solve_force(pen.copy(), total)
        before = joint.updates
        p, dz = joint.solve_force(pen.copy(), total)
        updates += max(joint.updates - before, 0)
        np.testing.assert_allclose(p, p_ref, rtol=0, atol=1e-9 * p_ref.max())
        assert dz == pytest.approx(dz_ref, rel=0, abs=1e-12)
    S = joint.S
    np.testing.assert_allclose(joint.M @ C[np.ix_(S, S)], np.eye(S.size), atol=1e-8)
    assert updates > 2 * REFRESH, "the slide must pass the reference's schedule"
    assert joint.rebuilds < scheduled.rebuilds


def test_the_held_steps_rebuild_schedule_follows_the_held_solve():
    """The joint held solve takes :data:`JOINT_REFRESH`; the reference's Newton iteration
    keeps :data:`REFRESH`, on which the golden slides are bit for bit."""
    from dataclasses import replace

    from sim_tactile.sim.slide import prepare

    job = replace(_quick_slide("roughness8-v1"), ideal=True)
    ref = replace(job, options=replace(job.options, path="per-step"))
    assert prepare(job).runner.hold.solver.refresh == JOINT_REFRESH > REFRESH
    assert prepare(ref).runner.hold.solver.refresh == REFRESH


def test_a_joint_loop_that_stops_leaves_a_state_the_newton_iteration_goes_on_from():
    """Allowed one set change, the joint loop stops short at most steps; the Newton
    iteration then goes on from the set it left, to the same answer."""
    xy = _grid()
    C = _skin("half-space", xy)
    total = _total(C, xy)
    ref, short = ActiveSet(C, np.linalg.inv(C)), _Joint(C, max_iter=1)
    for k in range(60):
        pen = _depths(xy, k * 0.13e-3)
        p_ref, _ = ref.solve_force(pen.copy(), total)
        p, _ = short.solve_force(pen.copy(), total)
        np.testing.assert_allclose(p, p_ref, rtol=0, atol=1e-9 * p_ref.max())
        S = short.S  # the inverse it keeps is the inverse of its set
        np.testing.assert_allclose(short.M @ C[np.ix_(S, S)], np.eye(S.size), atol=1e-8)
    assert short.stopped > 10


def test_the_joint_loop_refuses_a_set_it_cannot_start_from():
    """An empty set, and a set with a node out of reach: status 0, nothing changed."""
    xy = _grid()
    C = _skin("half-space", xy)
    pen = _depths(xy, 0.0)
    p = np.zeros(len(pen))
    empty = (np.zeros((0, 0)), np.zeros(0, np.int64))
    common = (np.zeros(len(pen), bool), C, NO_K)
    st, *_ = joint_loop(
        *empty, *common, pen, TOL_REL, 1.0, 0, 100, 50, p, 0.0, True, np.zeros((0, 2)), NOT_TRIED
    )
    assert st == 0
    S = np.flatnonzero(pen > 0)
    M = np.linalg.inv(C[np.ix_(S, S)])
    far = pen.copy()
    far[S[0]] = -np.inf
    in_set = np.zeros(len(pen), bool)
    in_set[S] = True
    st, _, M2, S2, *_ = joint_loop(
        M,
        S,
        in_set,
        C,
        NO_K,
        far,
        TOL_REL,
        1.0,
        0,
        100,
        50,
        p,
        0.0,
        True,
        np.zeros((0, 2)),
        NOT_TRIED,
    )
    assert st == 0 and M2 is M and S2 is S


def test_the_newton_iteration_is_unchanged_where_the_joint_loop_is_not_asked_for():
    """The reference's held solve does not go through the joint loop: its answer is
    force_loop's own, bit for bit, at every step of the slide."""
    xy = _grid()
    C = _skin("layered", xy)
    total = _total(C, xy)
    a, b = ActiveSet(C, np.linalg.inv(C)), ActiveSet(C, np.linalg.inv(C))
    for k in range(40):
        pen = _depths(xy, k * 0.13e-3)
        p_a, dz_a = a.solve_force(pen.copy(), total)
        p_b = np.empty_like(pen)
        if b.S.size:
            M, S, in_set, Cb, rowsum = b.same_set_state()
            dz_b = force_same_set(M, S, pen, Cb, in_set, TOL_REL, total, p_b, rowsum, b.floor)
            if dz_b == dz_b:
                assert np.array_equal(p_a, p_b) and dz_a == dz_b
                continue
        st, dz_b, M, S, up, rb = force_loop(
            *(b.M, b.S, b._in, b.C, b.K, pen, TOL_REL, float(total), b.updates, b.refresh),
            *(MAX_ITER, p_b, False, b.floor, b.symmetric, b._cu),
        )
        b._take(M, S, up, rb)
        assert st == 1 and np.array_equal(p_a, p_b) and dz_a == dz_b


def _quick_slide(task: str, k: int = 0):
    from sim_tactile.tasks import get_task

    return get_task(task).get_data.jobs(seed=0, quick=True)[k]


def test_auto_takes_the_joint_solve_where_the_compiled_dense_step_runs():
    """``auto`` solves a dense skin's held step jointly (a rough plate under the PVDF film,
    the multilayer's dense full problem at every 2nd step); the reference by name, a
    spectral skin, position control and the probe rig keep the Newton iteration. The knob
    enters the key where it is set, so nothing either made is served for the other."""
    from dataclasses import replace

    for task in ("roughness8-v1", "multilayer3-v1", "textures20-biotac19-v1"):
        for job in (_quick_slide(task, k) for k in (0, 1)):
            if job.table_plan() is None:
                assert job.how.held_solve == "joint", (task, job.label)
            ref = replace(job, options=replace(job.options, path="per-step"))
            assert ref.how.held_solve == "newton"
            assert job.describe() != ref.describe()
    icub = [_quick_slide("textures20-icub60-v1", k) for k in range(12)]
    spectral = [j for j in icub if j.spectral or j.how.skin_solver == "spectral"]
    assert spectral and all(j.how.held_solve == "newton" for j in spectral)
    for task in ("finger7-v2", "multilayer3-v2"):  # position control; the probe rig
        assert _quick_slide(task).how.held_solve == "newton"


def test_a_jointly_solved_slide_records_what_the_reference_records(cache):
    """A PVDF slide on a rough plate (``auto``: every step, the joint solve) against the
    same slide by the reference (``path = per-step``): the runner's held step says which it
    solves, and the recordings agree to float32's rounding."""
    from dataclasses import replace

    from sim_tactile.sim.slide import prepare, run

    job = replace(_quick_slide("roughness8-v1"), ideal=True)
    ref = replace(job, options=replace(job.options, path="per-step"))
    assert prepare(job, cache=cache).runner.hold.joint
    assert not prepare(ref, cache=cache).runner.hold.joint
    a, b = run(job, cache).recording, run(ref, cache).recording
    np.testing.assert_allclose(a.data, b.data, rtol=1e-5, atol=1e-6 * np.abs(b.data).max())
    np.testing.assert_allclose(a.meta["normal_force_n"], b.meta["normal_force_n"], rtol=1e-9)
