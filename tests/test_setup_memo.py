"""A worker's set-up kept between slides: content-keyed, read-only, and the slides equal bit
for bit whether their set-up was computed or kept."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile import cache as cache_module
from sim_tactile.cache import forget_process_memos, setup_memo
from sim_tactile.hashing import array_digest
from sim_tactile.scene import model as model_module
from sim_tactile.sim.plan.protocol import Protocol
from sim_tactile.sim.slide import simulate


@pytest.fixture(autouse=True)
def _fresh(fresh_memo):
    """Each test starts with nothing kept in the process."""


def test_the_key_holds_every_part_and_the_value_is_kept_read_only(fresh_memo):
    calls = []

    def compute(v):
        calls.append(v)
        return (np.full(3, float(v)), "label")

    mods = ("sim_tactile.cache",)
    a = setup_memo("x", {"v": 1}, lambda: compute(1), mods)
    b = setup_memo("x", {"v": 1}, lambda: compute(1), mods)
    assert a is b and calls == [1] and not a[0].flags.writeable
    with pytest.raises(ValueError):
        a[0][0] = 5.0  # no slide can change what the next one reads
    c = setup_memo("x", {"v": 2}, lambda: compute(2), mods)  # another part: computed
    d = setup_memo("y", {"v": 1}, lambda: compute(3), mods)  # another kind: computed
    assert calls == [1, 2, 3] and c[0][0] == 2.0 and d[0][0] == 3.0
    assert len(fresh_memo) == 3


def test_a_value_kept_on_disk_is_read_by_the_next_process_and_never_trusted_blindly(
    fresh_memo, tmp_path
):
    from sim_tactile.cache import SETUP_EXT, ArtefactCache
    from sim_tactile.errors import CacheWarning

    own = ArtefactCache(tmp_path)
    calls = []

    def compute():
        calls.append(1)
        return (np.linspace(0.0, 1.0, 7), np.eye(2, dtype=np.float32))

    mods = ("sim_tactile.cache",)
    a = setup_memo("x", {"v": 1}, compute, mods, own)
    forget_process_memos()  # a fresh process: read, not computed
    b = setup_memo("x", {"v": 1}, compute, mods, own)
    assert calls == [1] and all(x.tobytes() == y.tobytes() for x, y in zip(a, b, strict=True))
    assert b[1].dtype == np.float32 and not b[0].flags.writeable
    (entry,) = tmp_path.rglob(f"*.{SETUP_EXT}.d")
    key = entry.name.split(".", 1)[0]
    own.discard(key, SETUP_EXT)
    own.put(key, SETUP_EXT, b"no npz")  # its checksum holds, its bytes are no arrays
    forget_process_memos()
    with pytest.warns(CacheWarning, match="cannot be read as set-up arrays"):
        c = setup_memo("x", {"v": 1}, compute, mods, own)
    assert calls == [1, 1] and c[0].tobytes() == a[0].tobytes()
    with pytest.raises(TypeError, match="tuple of arrays"):
        setup_memo("y", {}, lambda: (np.zeros(2), "label"), mods, own)


def test_array_digest_tells_dtype_shape_and_bytes_apart():
    a = np.arange(6, dtype=np.float64)
    assert array_digest(a) == array_digest(a.copy())
    assert array_digest(a) != array_digest(a.reshape(2, 3))
    assert array_digest(a) != array_digest(a.astype(np.float32))
    b = a.copy()
    b[3] = np.nextafter(b[3], 10.0)  # one rounding
    assert array_digest(a) != array_digest(b)


@pytest.mark.parametrize(
    ("plate", "sensor", "kw"),
    [
        # a small dense skin (its compliance and inverse kept), mirror-halved held step
        ("finger7/ridges-4", "grid3x3", dict(pitch_m=0.5e-3)),
        # a rough plate on the roughness fingertip's layered skin
        ("roughness8/ra-50", "pvdf2", {}),
    ],
)
def test_slides_are_equal_bit_for_bit_with_their_set_up_computed_or_kept(
    plate, sensor, kw, fresh_memo, tmp_path
):
    """Computed, kept in the process, read from the disk cache (the taxel weights and the
    compiled models as another process reads them), computed again with an empty cache."""
    from sim_tactile.cache import SETUP_EXT, ArtefactCache

    proto = Protocol(duration_s=0.25)
    own = ArtefactCache(tmp_path / "own")

    def run(c):
        return simulate(plate, sensor, protocol=proto, ideal=True, cache=c, **kw).recording

    first = run(own)
    assert len(fresh_memo) >= 2  # the weights and the skin were kept
    assert len(model_module.SCENES) == 1  # and the compiled models
    kinds = {p.name.split(".", 1)[1] for p in own.root.rglob("*.d")}
    assert {SETUP_EXT, *model_module.MODEL_EXTS} <= {k.removesuffix(".d") for k in kinds}
    again = run(own)
    forgotten = forget_process_memos()  # then read from the disk
    assert len(fresh_memo) == 0 and len(model_module.SCENES) == 0
    assert {"set-up arrays", "compiled scene models"} <= set(forgotten)
    read = run(own)
    forget_process_memos()  # and computed anew
    anew = run(ArtefactCache(tmp_path / "empty"))
    assert first.data.max() > 0
    for r in (again, read, anew):
        assert r.data.tobytes() == first.data.tobytes()
        assert r.meta["normal_force_n"] == first.meta["normal_force_n"]


def test_stored_models_that_mujoco_cannot_read_are_compiled_again(fresh_memo, tmp_path):
    """An entry whose checksum holds but whose bytes are no MuJoCo model (another MuJoCo's,
    say): a warning names it, and the slide is the one its compiled models make."""
    from sim_tactile.cache import ArtefactCache
    from sim_tactile.errors import CacheWarning

    own = ArtefactCache(tmp_path / "own")
    kw = dict(protocol=Protocol(duration_s=0.25), ideal=True, pitch_m=0.5e-3, cache=own)
    first = simulate("finger7/ridges-4", "grid3x3", **kw).recording
    (entry,) = own.root.rglob("*.col.mjb.d")
    key = entry.name.split(".", 1)[0]
    own.discard(key, "col.mjb")
    own.put(key, "col.mjb", b"not a model")
    forget_process_memos()
    with pytest.warns(CacheWarning, match="cannot be read as MuJoCo models"):
        again = simulate("finger7/ridges-4", "grid3x3", **kw).recording
    assert again.data.tobytes() == first.data.tobytes()
    assert own.get(key, "col.mjb").read_bytes() != b"not a model"  # stored again, whole


def test_a_softer_skin_is_never_served_the_kept_weights(fresh_memo):
    from dataclasses import replace

    from sim_tactile.sensors import get_sensor

    s = get_sensor("grid3x3")
    soft = replace(s, finger=replace(s.finger, young_pa=s.finger.young_pa / 2))
    kw = dict(protocol=Protocol(duration_s=0.25), ideal=True, pitch_m=0.5e-3)
    a = simulate("finger7/ridges-4", s, **kw).recording
    n = len(fresh_memo)
    b = simulate("finger7/ridges-4", soft, **kw).recording
    assert len(fresh_memo) > n  # its own skin kept beside the first
    assert a.data.tobytes() != b.data.tobytes()


def test_a_slide_places_a_copy_of_the_kept_models_never_them(fresh_memo, cache):
    """Each scene takes copies of the kept models and places its bone and time step there;
    another margin or pad is another entry."""
    from sim_tactile.plates import get_plate
    from sim_tactile.scene.model import build_scene
    from sim_tactile.scene.nodes import skin_grid
    from sim_tactile.sensors import Finger, get_layout

    f = Finger()
    grid = skin_grid(f, 1e-3)
    kw = dict(z_damping=1.0, cache=cache)
    args = (get_plate("finger7/ridges-4"), f, grid, get_layout("grid3x3"))
    a = build_scene(*args, dt_s=1e-3, x0_m=-0.02, z0_m=1e-3, y0_m=2e-4, **kw)
    b = build_scene(*args, dt_s=2e-3, x0_m=-0.01, z0_m=2e-3, **kw)
    (kept,) = model_module.SCENES.values()
    bone = kept[0].body("bone").id
    assert a.m_col is not kept[0] and b.m_dyn is not kept[1]
    assert kept[0].body_pos[bone].tolist() == [0.0, 0.0, 0.0]  # the kept model untouched
    assert a.m_col.body_pos[bone].tolist() == [-0.02, 2e-4, 1e-3] and a.m_dyn.opt.timestep == 1e-3
    assert b.m_dyn.body_pos[bone].tolist() == [-0.01, 0.0, 2e-3] and b.m_col.opt.timestep == 2e-3
    build_scene(*args, dt_s=1e-3, x0_m=0.0, z0_m=1e-3, node_margin_m=1e-4, **kw)
    softer = (args[0], Finger(young_pa=0.2e6), grid, args[3])
    build_scene(*softer, dt_s=1e-3, x0_m=0.0, z0_m=1e-3, **kw)
    assert len(model_module.SCENES) == 3


@pytest.mark.parametrize(
    ("plate", "sensor", "kw"),
    [
        ("finger7/ridges-4", "grid3x3", dict(pitch_m=0.5e-3)),  # a dense skin
        ("textures20/boxes-4.5mm", "icub60", {}),  # a spectral one, on a primitive collider
    ],
)
def test_a_slide_on_the_models_a_finished_slide_gave_back_is_the_slide_on_fresh_copies(
    plate, sensor, kw, cache
):
    """A finished slide gives its placed models and MjData back (:data:`SPARE`); the next
    slide of the scene places them again, at its own start, offset and time step, and
    resets the data: bit for bit the slide on fresh copies."""
    second = Protocol(duration_s=0.2, offset_y_m=4e-4, speed_m_s=0.05)

    def run(p):
        return simulate(plate, sensor, protocol=p, ideal=True, cache=cache, **kw).recording

    run(Protocol(duration_s=0.2))
    (spare,) = model_module.SPARE.values()
    reused = run(second)
    (again,) = model_module.SPARE.values()
    assert again[0] is spare[0] and again[2] is spare[2]  # placed again, not copied
    forget_process_memos()
    assert not model_module.SPARE
    fresh = run(second)
    assert fresh.data.max() > 0
    assert reused.data.tobytes() == fresh.data.tobytes()
    assert reused.meta["normal_force_n"] == fresh.meta["normal_force_n"]


def test_a_tabled_slide_gives_its_runner_back_and_the_next_one_is_the_same(cache):
    """A slide read off its phase table that leaves it (its runner pressed for the steps off
    the table) gives its runner's models back too; the next slide of the scene, placed on
    them, is bit for bit the slide on fresh copies."""
    from dataclasses import replace

    from _scenes import ridges_on_shared_tables

    from sim_tactile.sim.slide import run

    first = ridges_on_shared_tables()
    assert first.table_plan() is not None
    second = replace(first, seed=5)
    rec = run(first, cache).recording
    assert "phase table" in rec.meta["skin_problem"] and "the rest:" in rec.meta["skin_problem"]
    (spare,) = model_module.SPARE.values()
    reused = run(second, cache).recording
    assert model_module.SPARE[next(iter(model_module.SPARE))][0] is spare[0]  # placed again
    forget_process_memos()
    fresh = run(second, cache).recording
    assert reused.data.tobytes() == fresh.data.tobytes()
    assert reused.meta["normal_force_n"] == fresh.meta["normal_force_n"]


def test_one_call_forgets_every_memo_of_the_process():
    """Whatever the package keeps in the process (the set-up arrays, the compiled models,
    the measured-errors table, roughness profiles, a height map's scales, ...) is empty after
    :func:`forget_process_memos`."""
    from sim_tactile.cache import _MEMOS
    from sim_tactile.plates import get_plate, surface_of
    from sim_tactile.sim.plan import measured_errors

    setup_memo("x", {"v": 1}, lambda: (np.zeros(3),), ("sim_tactile.cache",))
    measured_errors._table()
    assert surface_of(get_plate("roughness8/ra-50")).profile is not None
    assert len(cache_module.SETUP) == 1 and measured_errors._table.cache_info().currsize == 1
    names = forget_process_memos()
    assert set(names) == set(_MEMOS) and "measured-errors table" in names
    assert len(cache_module.SETUP) == 0 and measured_errors._table.cache_info().currsize == 0


def test_the_package_keeps_no_memo_outside_the_registry():
    """A functools cache or a module-level memo dict outside sim_tactile.cache's registry
    would outlive forget_process_memos (hashing and toml_text sit below cache.py: it
    forgets theirs by name)."""
    import re
    from pathlib import Path

    import sim_tactile

    root = Path(sim_tactile.__file__).parent
    below = {"cache.py", "hashing.py", "toml_text.py"}
    pattern = re.compile(r"^\s*@(functools\.)?(lru_cache|cache)\b", re.M)
    found = [
        p.relative_to(root).as_posix()
        for p in root.rglob("*.py")
        if p.name not in below and pattern.search(p.read_text())
    ]
    assert found == []


def test_a_value_kept_outside_a_slide_is_the_slides_own_bit_for_bit():
    """A slide computes on one BLAS thread; a script or a test that makes the same set-up
    array first, on BLAS's own threads, must not leave another value under the same key
    (the layered compliance table of finger7-v2's skin differed in its last bits; on one
    core the two agree either way)."""
    from sim_tactile.hashing import blas_controller, one_blas_thread
    from sim_tactile.scene.nodes import skin_grid
    from sim_tactile.sensors import resolve_sensor
    from sim_tactile.sim.skin.models import SpectralSkin
    from sim_tactile.tasks import get_task

    job = get_task("finger7-v2").get_data.jobs(seed=0)[0]
    finger = job.finger or resolve_sensor(job.sensor).finger
    assert finger.stack is not None  # a layered skin: its table sums through BLAS
    grid = skin_grid(finger, 0.25e-3)
    with blas_controller().limit(limits=2, user_api="blas"):
        outside = SpectralSkin.of(grid, finger).solver.table
    forget_process_memos()
    with one_blas_thread():
        inside = SpectralSkin.of(grid, finger).solver.table
    assert outside is not inside  # computed twice
    assert np.array_equal(outside, inside)
