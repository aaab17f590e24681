"""The batched contact solve (torch) against the numpy spectral solve it batches, on the skin
of every task scene that the planner solves spectrally, and the device it runs on.

The scenes are the tasks' own skins (finger, lattice and kernel as the planner chooses them
for the plate) pressed on the plate's analytic heights at a few places along the slide:
the iCub's 265 x 23 lattice on textures20's 1.5 mm grating, its 93 x 67 lattice on the
4.5 mm boxes, and finger7-v2's curved 89 x 65 pad on the 3 x 3 bumps (its nodes in reach
fill a block of the lattice: the block solve), which slides under position control (the
plain solve). The two solves are not equal bit for bit, and cannot be: torch's FFTs are
MKL's (or cuFFT's), the numpy solve's are scipy's pocketfft, and the sums over the nodes
are taken in other orders; they agree to the tolerance and take the same iterations.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from sim_tactile.errors import ConfigError, PhysicsError
from sim_tactile.plates import surface_of
from sim_tactile.scene.nodes import skin_grid
from sim_tactile.sensors import resolve_sensor
from sim_tactile.sim.plan.fidelity import choose_fidelity
from sim_tactile.sim.skin.contact import batched, device
from sim_tactile.sim.skin.contact.spectral import TOL, Spectral
from sim_tactile.sim.skin.models import SpectralSkin
from sim_tactile.tasks import get_task

#: Two solves stopped by the same rule, each where a step changed the pressures by ``tol`` of
#: their sum, agree to a few times ``tol`` (summed over the nodes, relative to their sum;
#: measured on these scenes: at most 2.5e-10 at 1e-10, 1.2e-4 at 1e-4).
AGREE = 20.0
#: The iterations of a pose may differ by one where its change crosses the tolerance within
#: the two solves' rounding (measured: equal on these scenes but for one pose in 64).
ITER_SLACK = 1

#: The FFT product of the batched solve against the numpy solve's, relative to the largest
#: deflection: torch's FFTs (MKL's here) round otherwise than scipy's pocketfft (measured:
#: 6e-16 on the iCub's lattice), so no iteration can be bit for bit.
PRODUCT_ROUNDING = 1e-14

#: (task, plate): the task scenes whose skin is solved spectrally
SCENES = {
    "icub-grating": ("textures20-icub60-v2", "textures20-long/grating-1.5mm"),
    "icub-boxes": ("textures20-icub60-v2", "textures20-long/boxes-4.5mm"),
    "finger7-v2": ("finger7-v2", "finger7/bumps-3x3"),
}
_SKINS: dict = {}


@pytest.fixture
def torch():
    return pytest.importorskip("torch", reason="the batched solve needs torch (an extra)")


def scene(name: str):
    """The scene's spectral skin, its node grid, plate and the pressures' total of its
    force (kept for the module)."""
    if name not in _SKINS:
        task, plate_name = SCENES[name]
        job = next(j for j in get_task(task).get_data.jobs(seed=0) if j.plate.name == plate_name)
        sensor = resolve_sensor(job.sensor)
        finger = job.finger or sensor.finger
        proto = job.protocol.at_rate(sensor.rate_hz).drawn(job.seed)
        fid = choose_fidelity(
            job.plate, sensor.layout, finger, proto, job.fidelity, pitch_m=job.pitch_m
        )
        grid = skin_grid(finger, fid.pitch_m, fid.pitch_y_m)
        skin = SpectralSkin.of(grid, finger)
        _SKINS[name] = (skin, grid, job.plate, proto.force_n / grid.area_m2)
    return _SKINS[name]


def depths(name: str, xs_m, press_m: float = 0.3e-3) -> np.ndarray:
    """(B, n): the node depths [m] of the scene's pad pressed ``press_m`` into the plate's
    highest point under it, its centre at each x of ``xs_m``; ``-inf`` beyond the
    collider's margin."""
    _, grid, plate, _ = scene(name)
    margin = surface_of(plate).margin_m
    out = []
    for x in xs_m:
        top = surface_of(plate).height(x + grid.xy[:, 0], grid.xy[:, 1])
        pen = top - grid.z - (np.nanmax(top - grid.z) - press_m)
        out.append(np.where(pen > -margin, pen, -np.inf))
    return np.array(out)


def numpy_chain(skin, pens, totals, tol):
    """Each pose by the numpy solve, warm-started from the last (as a slide's steps are):
    the pressures, shifts, iterations and the warm starts it had; its products in double
    precision, as the batched solve's in float64 (at a loose tolerance a slide's are single)."""
    sp = Spectral(skin.solver.table, tol=tol, single=False)
    p, dz, its, warm = [], [], [], []
    for pen, total in zip(pens, totals, strict=True):
        warm.append(sp.p.copy())
        if total is None:
            q, _ = sp.solve(pen)
            d = 0.0
        else:
            q, d = sp.solve_force(pen, total)
        p.append(q)
        dz.append(d)
        its.append(sp.iterations)
    return np.array(p), np.array(dz), np.array(its), np.array(warm)


def rel_l1(a, b):
    return np.abs(a - b).sum(axis=1) / np.abs(b).sum(axis=1)


@pytest.mark.parametrize("name", ["icub-grating", "icub-boxes", "finger7-v2"])
def test_the_fft_product_is_the_numpy_solves_to_rounding(torch, name):
    skin = scene(name)[0]
    bs = batched.BatchedSpectral(skin)
    prod = bs._product(skin.solver.ny, skin.solver.nx)
    p = np.random.default_rng(0).random((3, skin.solver.n))
    u = prod(torch.as_tensor(p)).numpy()
    for k in range(3):
        ref = skin.solver.apply(p[k])
        np.testing.assert_allclose(u[k], ref, rtol=0, atol=PRODUCT_ROUNDING * np.abs(ref).max())


@pytest.mark.parametrize(
    "name,tol",
    [
        pytest.param("icub-grating", TOL, marks=pytest.mark.slow),  # some 50 iterations
        ("icub-grating", 1e-4),
        ("icub-boxes", TOL),
        ("icub-boxes", 1e-4),
        ("finger7-v2", TOL),
        ("finger7-v2", 1e-4),
    ],
)
def test_the_batched_solve_equals_the_numpy_solve_on_every_spectral_task_scene(torch, name, tol):
    skin, grid, _, total = scene(name)
    pens = depths(name, np.arange(3) * 0.37e-3)
    held = name != "finger7-v2"  # finger7-v2 slides under position control: the plain solve
    totals = [total] * len(pens) if held else [None] * len(pens)
    ref, dz_ref, its_ref, warm = numpy_chain(skin, pens, totals, tol)
    bs = batched.BatchedSpectral(skin, tol=tol)
    if held:
        p, dz, its = bs.solve_force(pens, total, warm=warm)
        np.testing.assert_allclose(dz, dz_ref, rtol=AGREE * tol)
        np.testing.assert_allclose(p.sum(axis=1), total, rtol=1e-12)
    else:
        p, its = bs.solve(pens, warm=warm)
    assert (ref > 0).sum(axis=1).min() > 50  # a real contact patch
    assert rel_l1(p, ref).max() < AGREE * tol
    assert np.all(p[~np.isfinite(pens)] == 0.0)  # nodes beyond the margin carry nothing
    assert np.abs(its - its_ref).max() <= ITER_SLACK
    if name == "finger7-v2":  # the block of the nodes in reach, not the lattice
        assert bs.products and max(bs._products) != (grid.lattice[1], grid.lattice[0])


def test_without_warm_starts_each_pose_starts_afresh(torch):
    skin, _, _, total = scene("icub-boxes")
    pens = depths("icub-boxes", [0.0, 0.5e-3])
    p, dz, its = batched.BatchedSpectral(skin).solve_force(pens, total)
    for k in range(2):
        sp = Spectral(skin.solver.table)
        q, d = sp.solve_force(pens[k], total)
        assert rel_l1(p[k : k + 1], q[None])[0] < AGREE * TOL
        assert abs(its[k] - sp.iterations) <= ITER_SLACK


def test_each_pose_stops_at_its_own_tolerance_and_keeps_that_answer(torch):
    """A pose started from its answer converges at once; beside a pose that needs many
    iterations it still stops there, with the answer it has alone."""
    skin, _, _, total = scene("icub-boxes")
    pens = depths("icub-boxes", [0.0, 1.1e-3])
    sp = Spectral(skin.solver.table)
    answer, _ = sp.solve_force(pens[0], total)
    warm = np.array([answer, np.zeros_like(answer)])
    bs = batched.BatchedSpectral(skin)
    p, _, its = bs.solve_force(pens, total, warm=warm)
    alone, _, its_alone = bs.solve_force(pens[:1], total, warm=warm[:1])
    assert its[0] == its_alone[0] <= 2 < its[1]
    assert bs.steps == its_alone[0]
    np.testing.assert_allclose(p[0], alone[0], rtol=0, atol=1e-13 * answer.max())


def test_the_gpu_path_run_on_the_cpu_gives_the_same_answers(torch):
    """On a GPU the host looks at the batch every CHECK_EVERY iterations, the poses done in
    between iterate on (their answers were taken), the deflections are taken again for the
    whole batch and the batch shrinks in powers of two: the same answers."""
    skin, _, _, total = scene("icub-boxes")
    pens = depths("icub-boxes", np.arange(4) * 0.3e-3)
    _, _, _, warm = numpy_chain(skin, pens, [total] * 4, TOL)
    warm[2] = 0.0  # (a pose from the uniform start: it takes longest)
    cpu = batched.BatchedSpectral(skin)
    p1, dz1, its1 = cpu.solve_force(pens, total, warm=warm)
    gpu_like = batched.BatchedSpectral(skin)
    gpu_like.check_every = batched.CHECK_EVERY
    p2, dz2, its2 = gpu_like.solve_force(pens, total, warm=warm)
    np.testing.assert_array_equal(its2, its1)
    assert rel_l1(p2, p1).max() < 1e-12
    np.testing.assert_allclose(dz2, dz1, rtol=1e-12)


@pytest.mark.parametrize("check_every", [1, batched.CHECK_EVERY])
def test_a_pose_that_cycles_from_both_starts_takes_the_numpy_solves_last_start(
    torch, monkeypatch, check_every
):
    """Where the plain iteration cycles from the warm and the uniform starts, the pose takes
    the last start (few nodes join at a time) in the numpy solve; made to happen here by
    calling every iteration a cycle. On a GPU (``check_every`` > 1) a pose whose start
    failed waits for the host's next look to take its next start."""
    monkeypatch.setattr(batched, "CYCLE_CHANGE", -1.0)
    monkeypatch.setattr(batched, "CYCLE_ITER", 1)
    skin, _, _, total = scene("icub-boxes")
    pens = depths("icub-boxes", [0.2e-3, 0.9e-3])
    warm, _ = Spectral(skin.solver.table).solve_force(pens[1], total)
    bs = batched.BatchedSpectral(skin)
    bs.check_every = check_every
    p, _, _ = bs.solve_force(pens, total, warm=np.array([warm, warm]))
    assert bs.steps == 2 * check_every  # one iteration from each start, then the last
    for k in range(2):
        q, _ = Spectral(skin.solver.table).solve_force(pens[k], total)
        assert rel_l1(p[k : k + 1], q[None])[0] < AGREE * TOL


def test_float32_holds_its_tolerance_as_float64_does(torch):
    skin, _, _, total = scene("icub-grating")
    pens = depths("icub-grating", [0.0, 0.45e-3])
    truth, _, _, warm = numpy_chain(skin, pens, [total] * 2, TOL)
    tol = 1e-4
    p64, _, _ = batched.BatchedSpectral(skin, tol=tol).solve_force(pens, total, warm=warm)
    p32, _, _ = batched.BatchedSpectral(skin, tol=tol, dtype="float32").solve_force(
        pens, total, warm=warm
    )
    assert p32.dtype == np.float64
    assert rel_l1(p32, truth).max() < 2 * rel_l1(p64, truth).max() + tol


def test_bad_input_is_refused_in_one_line(torch):
    skin, _, _, total = scene("icub-boxes")
    bs = batched.BatchedSpectral(skin)
    pens = depths("icub-boxes", [0.0])
    with pytest.raises(ConfigError, match=r"pen_m has shape \(1, 10\); valid: \(B, 6231\)"):
        bs.solve_force(pens[:, :10], total)
    with pytest.raises(ConfigError, match="warm has shape"):
        bs.solve_force(pens, total, warm=np.zeros((2, skin.solver.n)))
    with pytest.raises(PhysicsError, match="positive total pressure"):
        bs.solve_force(pens, -1.0)
    with pytest.raises(PhysicsError, match="pose 1: no skin node lies within"):
        bs.solve_force(np.vstack([pens, np.full_like(pens, -np.inf)]), total)
    with pytest.raises(ConfigError, match="tol = 1e-06 in float32; valid: at least 1e-05"):
        batched.BatchedSpectral(skin, tol=1e-6, dtype="float32")
    with pytest.raises(ConfigError, match="dtype = 'float16'; valid: float64, float32"):
        batched.BatchedSpectral(skin, dtype="float16")
    with pytest.raises(ConfigError, match="needs a spectral skin"):
        batched.BatchedSpectral(object())


def test_nothing_touching_is_no_load_in_the_plain_solve(torch):
    skin, _, _, _ = scene("icub-boxes")
    pens = depths("icub-boxes", [0.0, 0.3e-3])
    pens[1] = np.where(np.isfinite(pens[1]), -1e-4, -np.inf)  # above the plate
    p, its = batched.BatchedSpectral(skin, tol=1e-4).solve(pens)
    assert p[0].sum() > 0 and not p[1].any() and its[1] == 0


# -- the device
def test_an_unknown_device_name_is_refused_without_torch():
    for name in ("gpu", "cpu:0", "cuda:x", "CUDA", ""):
        with pytest.raises(ConfigError, match=r"is not a device; valid: cpu, cuda, cuda:N$"):
            device.require_device(name)


def test_a_device_without_torch_names_the_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "torch", None)  # makes `import torch` fail
    with pytest.raises(ConfigError, match=r"'cuda' needs torch with CUDA, and torch is not "):
        device.require_device("cuda")
    with pytest.raises(ConfigError, match=r"'cpu' for the batched contact solve needs torch"):
        device.require_device("cpu")


def test_cuda_where_torch_sees_no_gpu_is_an_error_never_the_cpu(torch, monkeypatch):
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    monkeypatch.setattr(torch.version, "cuda", None)
    with pytest.raises(ConfigError, match=r"'cuda' but torch .* is a build without CUDA; valid"):
        device.require_device("cuda")
    monkeypatch.setattr(torch.version, "cuda", "12.4")
    with pytest.raises(ConfigError, match=r"'cuda:0' but torch .* \(CUDA 12.4\) sees no GPU"):
        device.require_device("cuda:0")
    with pytest.raises(ConfigError, match="sees no GPU"):
        batched.BatchedSpectral(scene("icub-boxes")[0], device="cuda")
    assert device.require_device("cpu") == torch.device("cpu")


def test_a_gpu_index_past_the_gpus_is_refused(torch, monkeypatch):
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 2)
    with pytest.raises(ConfigError, match=r"'cuda:2' but torch sees 2 GPUs; valid: cuda, "):
        device.require_device("cuda:2")
    assert device.require_device("cuda:1") == torch.device("cuda:1")


def test_the_cpu_path_and_these_modules_load_no_torch():
    """Importing the package, the skin models, the batched solve's modules and solving on
    the CPU leave torch unloaded (the core install has none)."""
    code = (
        "import sys, numpy as np\n"
        "import sim_tactile, sim_tactile.sim.skin.models\n"
        "from sim_tactile.sim.skin.contact import batched, device\n"
        "from sim_tactile.sim.skin.contact.spectral import Spectral\n"
        "device.check_device_name('cuda:1')\n"
        "Spectral(np.ones((3, 3))).solve_force(np.full(9, 1e-4), 1.0)\n"
        "print('torch' in sys.modules)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=300
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False"


def test_a_phase_tables_phases_solved_at_once_are_the_ones_solved_one_by_one(cache, monkeypatch):
    """The batched held step (sim/step/batched_held.py) on the CPU against the plain loop: a
    phase table of a spectral skin solved a grid at a time, and one phase after another,
    agree at every phase both solved, to the solve's tolerance; asked for a dense skin or the
    CPU, there is nothing to batch. Both over the whole period: the loop's mirrored half
    period (a device's batch solves the whole) is another grid, tested in test_sim_mirror."""
    pytest.importorskip("torch")
    from dataclasses import replace as _replace

    from sim_tactile.plates import get_plate
    from sim_tactile.sim import Protocol, Slide, StepOptions
    from sim_tactile.sim.step import batched_held as bh
    from sim_tactile.sim.step import tabled

    opts = StepOptions(skin_solver="spectral", path="phase-table", solve_tol=1e-8)
    slide = Slide(
        get_plate("finger7/bumps-6x6"),
        "grid3x3",
        Protocol(duration_s=0.25, start="texture"),
        pitch_m=0.5e-3,  # the pad's own lattice (auto would anchor it to the boxes' walls)
        options=opts,
    )
    proto, fid, plan = slide.drawn(), slide.resolved, slide.table_plan()
    monkeypatch.setattr(tabled, "mirror_centre", lambda plate, plan: None)
    one = tabled.solve_table(slide, proto, fid, plan, proto.force_n, cache)
    assert bh.batched_held(object(), "cuda") is None  # not the plain loop: not batched
    monkeypatch.setattr(tabled, "batched_held", lambda hold, device: bh.BatchedHeld(hold, "cpu"))
    many = tabled.solve_table(_replace(slide, options=opts), proto, fid, plan, proto.force_n, cache)
    common = sorted(set(one.phases.tolist()) & set(many.phases.tolist()))
    assert len(common) >= 0.8 * len(one.phases)
    a = one.loads[np.searchsorted(one.phases, common)]
    b = many.loads[np.searchsorted(many.phases, common)]
    assert np.abs(a).max() > 0
    np.testing.assert_allclose(b, a, rtol=0, atol=1e-5 * np.abs(a).max())
