"""The spectral contact solve (FFT products, constrained conjugate gradients) against the
dense active-set solve it stands in for on large pads."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sim_tactile.errors import ConfigError, PhysicsError
from sim_tactile.scene.elastic import compliance_matrix, compliance_table
from sim_tactile.scene.layered import layered_compliance_matrix, layered_compliance_table
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import resolve_sensor
from sim_tactile.sensors.stack import Layer, Stack
from sim_tactile.sim.skin.contact import ActiveSet, spectral
from sim_tactile.sim.skin.contact.spectral import TOL, Spectral
from sim_tactile.sim.skin.models import CoupledSkin, SpectralSkin, make_skin
from sim_tactile.sim.slide import simulate
from sim_tactile.sim.step.runner import StepOptions

E = 0.4e6
#: How close the two solves' pressures come, relative to the peak: the iteration stops when
#: a step changes the pressures by TOL of their sum; the answer is then about that close
#: (measured: 1e-11 to 2e-10 on these problems).
AGREE = 1e4 * TOL


def _lattice(nx: int, ny: int, px: float, py: float) -> np.ndarray:
    xs = (np.arange(nx) - (nx - 1) / 2) * px
    ys = (np.arange(ny) - (ny - 1) / 2) * py
    X, Y = np.meshgrid(xs, ys, indexing="xy")  # as skin_grid numbers the nodes
    return np.column_stack([X.ravel(), Y.ravel()])


def _bumps(xy: np.ndarray, shift: float, rng) -> np.ndarray:
    """A curved pad over 2 mm square bumps, rough, one node beyond the collider's margin."""
    bx = ((xy[:, 0] + shift) % 4e-3) < 2e-3
    by = (xy[:, 1] % 4e-3) < 2e-3
    pen = np.where(bx & by, 0.3e-3, 0.0) - 0.2e-3 - (xy**2).sum(axis=1) / (2 * 20e-3)
    pen += 2e-6 * rng.standard_normal(len(pen))
    pen[7] = -np.inf
    return pen


# nx, ny, px, py: square and oblong nodes, odd and even counts
LATTICES = [(17, 17, 0.5e-3, 0.5e-3), (24, 15, 0.4e-3, 0.7e-3)]


@pytest.mark.parametrize("nx,ny,px,py", LATTICES)
def test_the_kernel_table_is_the_compliance_matrix_and_the_fft_product_is_its_product(
    nx, ny, px, py
):
    xy = _lattice(nx, ny, px, py)
    C = compliance_matrix(xy, px, E, pitch_y_m=py)
    sp = Spectral(compliance_table(nx, ny, px, E, py))
    p = np.random.default_rng(0).random(nx * ny)
    u = C @ p
    np.testing.assert_allclose(sp.apply(p), u, rtol=0, atol=1e-13 * np.abs(u).max())


def test_the_layered_table_is_the_layered_matrix():
    nx, ny, px, py = 15, 11, 0.5e-3, 0.8e-3
    st = Stack((Layer(1e-3, 2 * E, 0.45), Layer(2e-3, E, 0.49)))
    xy = _lattice(nx, ny, px, py)
    C = layered_compliance_matrix(xy, px, st, pitch_y_m=py)
    sp = Spectral(layered_compliance_table(nx, ny, px, st, py))
    p = np.random.default_rng(1).random(nx * ny)
    np.testing.assert_allclose(sp.apply(p), C @ p, rtol=0, atol=1e-12 * np.abs(C @ p).max())


@pytest.mark.parametrize("nx,ny,px,py", LATTICES)
def test_spectral_solves_equal_the_dense_solves_while_a_pad_slides(nx, ny, px, py):
    rng = np.random.default_rng(2)
    xy = _lattice(nx, ny, px, py)
    C = compliance_matrix(xy, px, E, pitch_y_m=py)
    dense, sp = ActiveSet(C, np.linalg.inv(C)), Spectral(compliance_table(nx, ny, px, E, py))
    total = 0.5 / (px * py)  # 0.5 N
    for k in range(6):  # the bumps move under the pad: the contact set changes
        pen = _bumps(xy, k * 0.3e-3, rng)
        p1, dz1 = dense.solve_force(pen, total)
        p2, dz2 = sp.solve_force(pen, total)
        assert np.abs(p2 - p1).max() < AGREE * p1.max()
        assert dz2 == pytest.approx(dz1, rel=AGREE)
        assert p2.sum() == pytest.approx(total, rel=1e-12)
        assert p2[7] == 0.0  # beyond the margin: never loaded
        # the pad where it is: the same problem without the force
        q1, on1 = dense.solve(pen + dz1)
        q2, on2 = sp.solve(pen + dz1)
        assert np.abs(q2 - q1).max() < AGREE * q1.max()
    assert sp.stiffness_per_area(p2) == pytest.approx(dense.stiffness_per_area(), rel=1e-6)


def test_a_layered_skin_that_bulges_is_solved_alike():
    """On a layer over a rigid base a load lifts its neighbours (negative compliance entries):
    nodes short of the plate can touch; both solves agree."""
    nx, ny, px = 21, 21, 0.5e-3
    st = Stack((Layer(1.5e-3, E, 0.3),))
    xy = _lattice(nx, ny, px, px)
    C = layered_compliance_matrix(xy, px, st)
    assert (C < 0).any()
    dense = ActiveSet(C, np.linalg.inv(C))
    sp = Spectral(layered_compliance_table(nx, ny, px, st))
    pen = _bumps(xy, 0.1e-3, np.random.default_rng(3))
    p1, dz1 = dense.solve_force(pen, 1.0 / px**2)
    p2, dz2 = sp.solve_force(pen, 1.0 / px**2)
    assert np.abs(p2 - p1).max() < AGREE * p1.max()
    assert dz2 == pytest.approx(dz1, rel=AGREE)


def test_nothing_in_reach_gets_no_load_or_a_named_error():
    sp = Spectral(compliance_table(5, 5, 1e-3, E))
    p, on = sp.solve(np.full(25, -1e-4))
    assert not p.any() and not on.any()
    with pytest.raises(PhysicsError, match="margin"):
        sp.solve_force(np.full(25, -np.inf), 1e5)
    with pytest.raises(PhysicsError, match="positive total"):
        sp.solve_force(np.zeros(25), 0.0)


def test_make_skin_goes_spectral_above_the_dense_cap_and_says_so():
    finger = resolve_sensor("grid3x3").finger
    small = make_skin("L1", skin_grid(finger, 1e-3), finger, winkler_k_pa_per_m=1.0)
    big = make_skin("L1", skin_grid(finger, 0.25e-3), finger, winkler_k_pa_per_m=1.0)
    assert isinstance(small, CoupledSkin) and isinstance(big, SpectralSkin)
    assert "spectral solve on 65 x 65 nodes" in big.describe()
    with pytest.raises(ConfigError, match="solver.*valid: auto, dense, spectral"):
        make_skin("L1", skin_grid(finger, 1e-3), finger, winkler_k_pa_per_m=1.0, solver="cg")
    rough = finger.__class__(**{**finger.__dict__, "poisson": 0.45, "skin_tractions": True})
    with pytest.raises(ConfigError, match="symmetric compliance"):
        make_skin("L1", skin_grid(rough, 1e-3), rough, winkler_k_pa_per_m=1.0, solver="spectral")


def test_a_slide_on_the_spectral_skin_records_what_the_dense_skin_records(cache):
    kw = dict(ideal=True, pitch_m=0.8e-3, cache=cache)
    a = simulate("finger7/bumps-3x3", "grid3x3", options=StepOptions(skin_solver="dense"), **kw)
    b = simulate("finger7/bumps-3x3", "grid3x3", options=StepOptions(skin_solver="spectral"), **kw)
    assert "spectral solve" in b.recording.meta["skin_problem"]
    x, y = a.recording.data.astype(float), b.recording.data.astype(float)
    assert x.max() > 0
    np.testing.assert_allclose(y, x, rtol=0, atol=1e-6 * x.max())


@pytest.mark.slow
def test_a_warm_start_that_cycles_gives_way_to_a_fresh_one():
    """A held step of finger7/bumps-6x6 at 0.333 mm (slide 5 of finger7-v1): from the last
    step's 45 loaded nodes the iteration cycled (the pressures changing by 41% of their sum
    each iteration, for good); started afresh it converges to the dense answer."""
    with np.load(Path(__file__).parent / "data" / "spectral_cycle.npz") as z:
        pen, total, warm = z["pen"], float(z["total"]), z["warm"]
    n, pitch = 49, 1e-3 / 3
    sp = Spectral(compliance_table(n, n, pitch, E))
    sp.p = warm.copy()
    p, dz = sp.solve_force(pen, total)
    C = compliance_matrix(_lattice(n, n, pitch, pitch), pitch, E)
    p1, dz1 = ActiveSet(C, np.linalg.inv(C)).solve_force(pen, total)
    assert np.abs(p - p1).max() < AGREE * p1.max()
    assert dz == pytest.approx(dz1, rel=AGREE)


def test_a_one_node_warm_start_lets_the_overlapping_nodes_join():
    """A pad that touched one node (a feature's corner) and then, one step on, overlaps the
    plate with its whole face: the warm start is one node, whose gap has no gradient, so the
    iteration has no direction on its set at once. It must not stop there: the nodes off the
    set that overlap the plate join (that stop returned the one-node answer, the pad's shift
    0 against the dense solve's 1.9 mm, when the collider first read boxes as the height
    map does)."""
    n, pitch = 9, 1e-3
    sp = Spectral(compliance_table(n, n, pitch, E))
    C = compliance_matrix(_lattice(n, n, pitch, pitch), pitch, E)
    one = np.full(n * n, -1e-3)
    one[40] = 1e-4
    sp.solve_force(one, 1e4)
    assert (sp.p > 0).sum() == 1  # the warm start: one node
    rng = np.random.default_rng(3)
    face = 2e-3 + 1e-4 * rng.random(n * n)  # every node deep in the plate
    p, dz = sp.solve_force(face, 1e5)
    p1, dz1 = ActiveSet(C, np.linalg.inv(C)).solve_force(face, 1e5)
    assert (p1 > 0).sum() > 1
    assert np.abs(p - p1).max() < AGREE * p1.max()
    assert dz == pytest.approx(dz1, rel=AGREE)


@pytest.mark.parametrize(
    "rounding,refresh,compiled",
    [
        (spectral.ROUNDING, 16, True),
        (spectral.ROUNDING, 1000, True),
        (spectral.ROUNDING, 16, False),
        (spectral.ROUNDING, 1000, False),
        (0.0, 1000, False),
    ],
)
def test_a_gradient_at_the_rounding_of_the_deflections_ends_the_solve(
    rounding, refresh, compiled, monkeypatch
):
    """A held step of finger7/bumps-3x3 at 0.8 mm: 12 nodes converge until the gaps on the
    set agree to 1e-19 m, where the gradient is the rounding of ``C p``; a step along it
    (1e12 times the last) threw the pressures 24% off the answer and stopped there. The
    iteration ends at the rounding floor instead, on the dense answer; without that floor it
    does not (the last case: the deflections carried for 1000 iterations, as in that slide's
    run, which shows the test can fail). The whole lattice is solved (no block): the
    recorded iterates are the whole lattice's. The case without the floor runs the numpy
    iteration, whose rounding the recorded iterates are; the compiled one sums in another
    order and need not meet that trap, so it takes the cases with the floor."""
    monkeypatch.setattr(spectral, "BLOCK_SHARE", 0.0)
    monkeypatch.setattr(Spectral, "compiled", compiled)
    monkeypatch.setattr(spectral, "ROUNDING", rounding)
    monkeypatch.setattr(spectral, "REFRESH_EVERY", refresh)
    with np.load(Path(__file__).parent / "data" / "spectral_rounding.npz") as z:
        pen, total, warm = z["pen"], float(z["total"]), z["warm"]
    n, pitch = 21, 0.8e-3
    sp = Spectral(compliance_table(n, n, pitch, E))
    sp.p = warm.copy()
    p, _ = sp.solve_force(pen, total)
    C = compliance_matrix(_lattice(n, n, pitch, pitch), pitch, E)
    p1, _ = ActiveSet(C, np.linalg.inv(C)).solve_force(pen, total)
    close = np.abs(p - p1).max() < AGREE * p1.max()
    assert close == (rounding > 0), np.abs(p - p1).max() / p1.max()


@pytest.mark.parametrize("share", [spectral.JOIN_SHARE, None])
def test_a_cycling_iteration_converges_when_few_nodes_join_at_a_time(share, monkeypatch):
    """icub60 pressed on textures20/boxes-4.5mm at 0.385 mm (6231 nodes, 5926 in reach, a
    recorded step): the plain iteration alternates between two contact sets, some 1600
    nodes leaving and joining each time, from the last step's pressures and from a uniform
    start alike. Letting at most JOIN_SHARE of the set join an iteration converges: equal
    gaps on the set, none overlapping off it, the force held. Without that last start the
    solve fails with the named error (the second case, which shows the test can fail)."""
    with np.load(Path(__file__).parent / "data" / "spectral_joins.npz") as z:
        pen, total, warm = z["pen"], float(z["total"]), z["warm"]
    sp = Spectral(compliance_table(93, 67, 0.3854496446637726e-3, E))
    sp.p = warm.copy()
    if share is None:
        starts = sp._starts
        monkeypatch.setattr(sp, "_starts", lambda *a: (s for s in starts(*a) if s[2] is None))
        with pytest.raises(PhysicsError, match="did not converge"):
            sp.solve_force(pen, total)
        return
    p, dz = sp.solve_force(pen, total)
    ok = np.isfinite(pen)
    g = sp.apply(p) - np.where(ok, pen, 0.0)
    on = p > 0
    span = np.ptp(pen[ok])
    assert np.ptp(g[on]) < 1e-9 * span  # the gaps on the set are equal ...
    assert (g[ok & ~on] - g[on].mean()).min() > -1e-9 * span  # ... and none off it overlaps
    assert p.sum() == pytest.approx(total, rel=1e-12) and p.min() >= 0
    assert dz == pytest.approx(float(g[on].mean()), rel=1e-6)  # the pad's shift


def test_a_slide_stepped_gives_up_a_cycling_warm_start_sooner_to_the_same_answer(monkeypatch):
    """The recorded iCub step whose warm start cycles: a solver that steps a slide
    (:meth:`Spectral.stepwise`) gives that start up after STEP_CYCLE_ITER iterations, not
    CYCLE_ITER, and the fresh starts after it find the same answer, bit for bit."""
    with np.load(Path(__file__).parent / "data" / "spectral_joins.npz") as z:
        pen, total, warm = z["pen"], float(z["total"]), z["warm"]
    table = compliance_table(93, 67, 0.3854496446637726e-3, E)
    out = {}
    for stepped in (False, True):
        sp = Spectral(table)
        if stepped:
            sp.stepwise()
        sp.p = warm.copy()
        tries = []
        cg = sp._cg

        def counted(*a, _cg=cg, _tries=tries, **k):
            r = _cg(*a, **k)
            _tries.append((r[0] is not None, r[1]))
            return r

        monkeypatch.setattr(sp, "_cg", counted)
        out[stepped] = sp.solve_force(pen, total), tries
    (p0, dz0), tries0 = out[False]
    (p1, dz1), tries1 = out[True]
    # the warm start given up after the same first iterations and its patience's large changes
    assert not tries0[0][0] and not tries1[0][0]
    assert tries0[0][1] - spectral.CYCLE_ITER == tries1[0][1] - spectral.STEP_CYCLE_ITER >= 0
    assert tries0[1:] == tries1[1:] and tries1[-1][0]
    np.testing.assert_array_equal(p1, p0)
    assert dz1 == dz0


def test_a_slide_solved_step_by_step_steps_its_spectral_solver(cache, monkeypatch):
    """A per-step slide on the spectral skin sets its solver to step (and its blocks)."""
    seen = []
    judge = Spectral._judge

    def spy(self, change, stuck, patience=spectral.CYCLE_ITER):
        seen.append(self.warm_cycle_iter)
        return judge(self, change, stuck, patience)

    monkeypatch.setattr(Spectral, "_judge", spy)
    opts = StepOptions(skin_solver="spectral", path="per-step")
    simulate("finger7/bumps-3x3", "grid3x3", ideal=True, pitch_m=0.8e-3, cache=cache, options=opts)
    assert seen and seen[-1] == spectral.STEP_CYCLE_ITER


def test_the_cycling_case_converges_with_single_products_as_with_double():
    """The recorded step above at auto's tolerance: the single-precision products take the
    same path through the cycle (its last start) as the double ones, to the tolerance."""
    with np.load(Path(__file__).parent / "data" / "spectral_joins.npz") as z:
        pen, total, warm = z["pen"], float(z["total"]), z["warm"]
    table = compliance_table(93, 67, 0.3854496446637726e-3, E)
    got = {}
    for single in (True, False):
        sp = Spectral(table, tol=1e-4, single=single)
        sp.p = warm.copy()
        got[single] = (*sp.solve_force(pen, total), sp.iterations)
    (ps, dzs, its), (pd, dzd, itd) = got[True], got[False]
    assert np.abs(ps - pd).sum() < 1e-4 * np.abs(pd).sum()
    assert dzs == pytest.approx(dzd, rel=1e-4)
    assert abs(its - itd) <= max(3, itd // 4)


def test_a_pad_touching_a_patch_of_its_lattice_is_solved_on_that_block_alike(monkeypatch):
    """A curved pad: only a patch of its lattice is within reach of the plate, so the solve
    runs on the block of rows and columns around that patch (its own, smaller FFTs). While
    the patch slides and grows (blocks of several shapes, warm starts carried between them)
    each step equals the whole lattice's solve and the dense one; a patch wider than
    BLOCK_SHARE of the lattice is solved whole."""
    nx, ny, px = 40, 30, 0.5e-3
    table = compliance_table(nx, ny, px, E)
    xy = _lattice(nx, ny, px, px)
    C = compliance_matrix(xy, px, E)
    dense = ActiveSet(C, np.linalg.inv(C))
    block, whole = Spectral(table), Spectral(table)
    monkeypatch.setattr(whole, "_box", lambda ok: None)
    shapes = set()
    path = zip(np.linspace(-6e-3, 5e-3, 9), np.linspace(2e-3, 4e-3, 9), strict=True)
    for step, (cx, r) in enumerate(path):
        d2 = (xy[:, 0] - cx) ** 2 + (xy[:, 1] - 1e-3) ** 2
        pen = 2e-5 - d2 / (2 * 0.01) + 1e-6 * np.sin(3e3 * xy[:, 0])  # a sphere, R 10 mm
        pen[d2 > r * r] = -np.inf  # beyond the collider's margin
        box = block._box(np.isfinite(pen))
        assert box is not None
        shapes.add((box[1] - box[0], box[3] - box[2]))
        total = 3e6 * (1 + 0.1 * step)
        p, dz = block.solve_force(pen, total)
        p2, dz2 = whole.solve_force(pen, total)
        p1, dz1 = dense.solve_force(pen, total)
        assert (p1 > 0).sum() > 10 and p[~np.isfinite(pen)].max() == 0.0
        for q, z in ((p2, dz2), (p1, dz1)):
            assert np.abs(p - q).max() < AGREE * q.max()
            assert dz == pytest.approx(z, rel=AGREE)
    assert len(shapes) > 2 and len(block._blocks) == min(len(shapes), spectral.BLOCKS_KEPT)
    wide = np.full(nx * ny, 1e-5)  # every node in reach: the whole lattice
    assert block._box(np.isfinite(wide)) is None


@pytest.mark.parametrize("total", [None, 1e6])
def test_the_compiled_iteration_agrees_with_the_numpy_one(total, monkeypatch):
    """The compiled vector work (sums in node order) against the numpy iteration (pairwise
    and BLAS sums): the same pressures to the iteration's tolerance, a pad of a curved
    indenter's depths on a 30 x 24 lattice, cold and then warm (a sliding step)."""
    n_x, n_y, pitch = 30, 24, 0.25e-3
    X, Y = np.meshgrid((np.arange(n_x) - n_x / 2) * pitch, (np.arange(n_y) - n_y / 2) * pitch)
    R = 8e-3
    pen0 = (0.05e-3 - (X**2 + Y**2) / (2 * R)).ravel()
    pen0 += 5e-6 * np.sin(X.ravel() / 0.7e-3)  # a texture under it
    table = compliance_table(n_x, n_y, pitch, E)
    out = {}
    for compiled in (True, False):
        monkeypatch.setattr(Spectral, "compiled", compiled)
        sp = Spectral(table)
        res = []
        for shift in (0.0, 0.1e-3, 0.2e-3):  # the texture slides under the pad
            pen = pen0 + 5e-6 * np.sin((X.ravel() + shift) / 0.7e-3)
            p, dz = sp.solve_force(pen, total) if total else (sp.solve(pen)[0], 0.0)
            res.append((p, dz, sp.iterations))
        out[compiled] = res
    for (pa, dza, ia), (pb, dzb, ib) in zip(out[True], out[False], strict=True):
        assert pa.max() > 0 and (pa > 0).sum() > 20
        assert np.abs(pa - pb).max() < AGREE * pb.max()
        assert dza == pytest.approx(dzb, rel=AGREE, abs=1e-15)
        assert abs(ia - ib) <= max(3, ib // 4)  # the same iteration, give or take rounding


@pytest.mark.parametrize("shape", [(1, 1), (2, 3), (7, 5), (25, 30), (68, 95)])
def test_the_direct_transforms_are_scipy_ffts_bit_for_bit(shape):
    """The product through scipy.fft's pocketfft binding is the public functions' product,
    to the bit, and again with the buffers reused."""
    from sim_tactile.sim.skin.contact import spectral

    spectral._load_fft()
    assert spectral._DIRECT  # this scipy has the binding: the fast path is the one tested
    rng = np.random.default_rng(shape[0] * 100 + shape[1])
    table = np.abs(rng.standard_normal(shape))
    for tol in (TOL, spectral.FLOAT32_MIN_TOL):  # double, and single products
        s = spectral.Spectral(table, tol=tol)
        for _ in range(3):
            p = rng.standard_normal(s.n)
            assert np.array_equal(s.apply(p), s.apply_public(p))


#: How far a product in single precision may lie from the double one, relative to the
#: largest deflection: float32's precision (6e-8) times the FFT's rounding growth.
SINGLE_PRODUCT = 2e-6


@pytest.mark.parametrize("nx,ny,px,py", LATTICES)
def test_a_loose_solve_takes_single_products_within_its_tolerance_of_the_double_solve(
    nx, ny, px, py
):
    """At a tolerance of at least FLOAT32_MIN_TOL the products are single (returned as
    double), the reference's stay double; the held solves of a sliding pad agree with the
    double-product solve at the same tolerance to that tolerance, in about as many
    iterations."""
    xy = _lattice(nx, ny, px, py)
    table = compliance_table(nx, ny, px, E, py)
    tol = 1e-4
    single, double = Spectral(table, tol=tol), Spectral(table, tol=tol, single=False)
    assert single.single and not double.single and not Spectral(table).single
    p = np.random.default_rng(3).random(nx * ny)
    u1, u2 = single.apply(p), double.apply(p)
    assert u1.dtype == np.float64
    assert 0 < np.abs(u1 - u2).max() < SINGLE_PRODUCT * np.abs(u2).max()
    rng = np.random.default_rng(4)
    total = 0.5 / (px * py)
    for k in range(6):
        pen = _bumps(xy, k * 0.3e-3, rng)
        pa, dza = single.solve_force(pen, total)
        pb, dzb = double.solve_force(pen, total)
        assert np.abs(pa - pb).max() < 10 * tol * pb.max()
        assert dza == pytest.approx(dzb, rel=10 * tol)
        assert pa.sum() == pytest.approx(total, rel=1e-12)
        assert abs(single.iterations - double.iterations) <= max(3, double.iterations // 4)


def test_a_loose_held_solve_starts_from_the_last_answers_product(monkeypatch):
    """A solve of single products (``auto``'s tolerance) held at a force starts from the
    last answer with that answer's product, taken for its shift, instead of taking it
    again: one FFT product fewer a solve, the answers within the tolerance of a solver that
    takes its own. The reference's solves (double products) take their own."""
    nx, ny, px = 24, 15, 0.4e-3
    xy = _lattice(nx, ny, px, px)
    table = compliance_table(nx, ny, px, E)
    total = 0.5 / px**2
    out = {}
    for carried in (True, False):
        sp = Spectral(table, tol=1e-4)
        assert sp.single
        if not carried:
            monkeypatch.setattr(sp, "_warm_product", lambda ok, total: None)
        products = []
        apply = sp.apply

        def counted(p, _apply=apply, _n=products):
            _n[-1] += 1
            return _apply(p)

        monkeypatch.setattr(sp, "apply", counted)
        answers = []
        for k in range(6):  # the bumps move under the pad (no node beyond the margin)
            pen = _bumps(xy, k * 0.1e-3, np.random.default_rng(k))
            pen[7] = 0.0
            products.append(0)
            answers.append(sp.solve_force(pen, total))
        out[carried] = answers, products
    (with_, n_with), (without, n_without) = out[True], out[False]
    assert n_with[0] == n_without[0]  # the first solve has no answer before it
    assert n_with[1:] == [n - 1 for n in n_without[1:]]
    for (p1, dz1), (p0, dz0) in zip(with_, without, strict=True):
        assert np.abs(p1 - p0).max() < 1e-3 * p0.max()
        assert dz1 == pytest.approx(dz0, rel=1e-3)
    ref = Spectral(table)  # the reference: double products
    ref.solve_force(_bumps(xy, 0.0, np.random.default_rng(0)), total)
    assert ref._warm_product(np.ones(nx * ny, bool), total) is None
