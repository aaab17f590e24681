"""sim-tactile generate: a tiny data set (2 plates x 3 slides of 0.2 s, about 0.15 s a slide)
written with 1 and 2 workers and with Ray is identical; interrupted runs (Ctrl-C, a killed
process, a killed worker) resume to the same data set; corrupted chunks are found and
written again; other configurations and existing stores are refused; loading, export and
the tasks' ``--store``."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from _stores import sample_chunk
from conftest import EXE  # noqa: E402  (the console script, for processes killed mid-run)

from sim_tactile import datasets
from sim_tactile.cache import default_root
from sim_tactile.datasets import from_tactile
from sim_tactile.errors import ConfigError, StoreError
from sim_tactile.generate import generate
from sim_tactile.records import Recording
from sim_tactile.slides import SlideOutcome, SlideWorker

ARRAYS = ("data", "checksum", "lengths", "labels", "slide", "seed", "params")

TINY = {
    "name": "tiny",
    "seed": 7,
    "plates": ["finger7/flat", "finger7/ridges-2"],
    "sensor": "grid3x3",
    "slides_per_plate": 3,
    "protocol": {"duration_s": 0.2},
    "randomise": {"speed_jitter": 0.05, "force_jitter": 0.1, "offset_jitter_m": 0.5e-3},
}
TINY_TOML = """
name = "tiny"
seed = 7
plates = ["finger7/flat", "finger7/ridges-2"]
sensor = "grid3x3"
slides_per_plate = 3

[protocol]
duration_s = 0.2

[randomise]
speed_jitter = 0.05
force_jitter = 0.1
offset_jitter_m = 0.5e-3
"""


@pytest.fixture(autouse=True)
def _shared_cache(cache_dir, monkeypatch):
    monkeypatch.setenv("SIM_TACTILE_CACHE", str(cache_dir))


def _write(path: Path, cfg: dict) -> Path:
    path.write_text(json.dumps(cfg))
    return path


def _arrays(path: Path, part: str | None = None) -> dict:
    import zarr

    g = zarr.open_group(str(path), mode="r")
    g = g[part] if part else g
    return {k: g[k][:] for k in ARRAYS}


def assert_same_store(a: Path, b: Path) -> None:
    x, y = _arrays(a), _arrays(b)
    for k in ARRAYS:
        np.testing.assert_array_equal(x[k], y[k], err_msg=k)
    sa, sb = datasets.open(a), datasets.open(b)
    assert sa.config_hash == sb.config_hash and sa.complete and sb.complete


def _quiet(*a, **k):
    return generate(*a, progress=False, log=lambda m: None, **k)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, cache_dir):
    """The tiny configuration (TOML) and its data set written with one worker."""
    d = tmp_path_factory.mktemp("gen")
    cfg = d / "tiny.toml"
    cfg.write_text(TINY_TOML)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SIM_TACTILE_CACHE", str(cache_dir))
        res = _quiet(str(cfg), d / "ref.zarr", workers=1)
    assert res["trials"] == 6 and res["written"] == 6 and not res["resumed"]
    return cfg, d / "ref.zarr"


def test_one_and_two_workers_write_the_same_data_set(tiny, tmp_path):
    cfg, ref = tiny
    res = _quiet(str(cfg), tmp_path / "w2.zarr", workers=2)
    assert set(res) >= {"out", "trials", "resumed", "wall_s"} and res["workers"] == 2
    assert_same_store(ref, tmp_path / "w2.zarr")
    # a JSON file with the same content is the same configuration
    res = _quiet(str(_write(tmp_path / "tiny.json", TINY)), tmp_path / "j.zarr", workers=2)
    assert res["config_hash"] == datasets.open(ref).config_hash


def test_generate_says_which_slides_came_from_the_slide_cache(tiny, tmp_path, cache_dir):
    """Slides a run left in the slide cache are read, not simulated, and generate says so
    (it said "6 simulated now" for slides it read in a fraction of a second)."""
    from sim_tactile.cli.data import generate_line

    cfg, ref = tiny
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SIM_TACTILE_CACHE", str(cache_dir))
        filler = SlideWorker(str(cache_dir), write=True)  # as `run` fills the cache
        first = _quiet(str(cfg), tmp_path / "a.zarr", workers=1, _worker=filler)
        again = _quiet(str(cfg), tmp_path / "b.zarr", workers=1)
    assert first["simulated"] + first["cached"] == first["written"] == 6
    assert (again["simulated"], again["cached"], again["written"]) == (0, 6, 6)
    assert "(0 simulated now, 6 from the slide cache, 0 kept)" in generate_line(again)
    assert_same_store(ref, tmp_path / "b.zarr")


@pytest.mark.slow
def test_ray_backend_writes_the_same_data_set(tiny, tmp_path, cli_env):
    pytest.importorskip("ray", reason="the ray extra is not installed")
    cfg, ref = tiny
    out = tmp_path / "ray.zarr"
    p = subprocess.run(
        [EXE, "generate", str(cfg), "--out", str(out), "--backend", "ray", "--workers", "2"]
        + ["--json"],
        env={**cli_env, "RAY_AUTH_MODE": "disabled"},
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert p.returncode == 0, p.stderr[-2000:]
    doc = json.loads(p.stdout)
    assert doc["backend"] == "ray" and doc["trials"] == 6 and doc["written"] == 6
    assert "%|" not in p.stderr  # no progress bar under --json
    assert_same_store(ref, out)
    runs = datasets.open(out).meta["runs"]
    assert runs[-1]["backend"] == "ray" and runs[-1]["ray"]


def _count_done(out: Path) -> int:
    """Slides whose checksum chunk is written: its file named by the slide's index (not a
    ``<index>.<hex>.partial`` file that a kill left half written)."""
    c = out / "checksum" / "c"
    return sum(1 for f in c.iterdir() if f.name.isdigit()) if c.is_dir() else 0


def _start(args: list[str], env: dict) -> subprocess.Popen:
    return subprocess.Popen(
        [EXE, "generate", *args],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def _wait_for(out: Path, n: int, proc: subprocess.Popen, timeout: float = 60.0) -> int:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout and proc.poll() is None:
        k = _count_done(out)
        if k >= n:
            return k
        time.sleep(0.01)
    raise AssertionError(f"the run did not reach {n} slides: {proc.poll()}, {_count_done(out)}")


def _slide(job):
    """What generate's own worker does: the slide through the cache, never writing it."""
    return SlideWorker(str(default_root()), write=False)(job)


def _interrupt_on(seed: int):
    def fn(job):
        if job.seed == seed:
            raise KeyboardInterrupt  # Ctrl-C while this slide runs
        return _slide(job)

    return fn


@pytest.mark.slow
def test_interrupted_and_killed_runs_resume_to_the_same_data_set(tmp_path, cli_env):
    cfg = _write(tmp_path / "twelve.json", {**TINY, "slides_per_plate": 6})
    ref = tmp_path / "ref.zarr"
    _quiet(str(cfg), ref, workers=1)
    seeds = datasets.open(ref).seeds
    out = tmp_path / "cut.zarr"
    # Ctrl-C during the fourth slide (one worker: the slide runs in this process)
    lines: list[str] = []
    with pytest.raises(KeyboardInterrupt):
        generate(
            str(cfg),
            out,
            workers=1,
            progress=False,
            log=lines.append,
            _worker=_interrupt_on(int(seeds[3])),
        )
    assert any("interrupted: 3 of 12 slides" in m and "--resume" in m for m in lines), lines
    assert _count_done(out) == 3
    # kill -9 of the whole process group (parent and workers) while resuming
    p = _start([str(cfg), "--out", str(out), "--workers", "2", "--resume"], cli_env)
    _wait_for(out, 5, p)
    os.killpg(p.pid, signal.SIGKILL)
    p.communicate(timeout=30)
    killed = _count_done(out)
    assert 5 <= killed < 12, killed
    # resume to the end
    stale = out / "checksum" / "c" / "7.0123abcd.partial"  # as a kill mid-chunk leaves
    stale.write_bytes(b"\x00\x01")
    res = _quiet(str(cfg), out, workers=2, resume=True)
    assert res["resumed"] and res["reused"] == killed and res["written"] == 12 - killed
    assert not list(out.rglob("*.partial"))  # the resume removed what the kill left
    assert_same_store(ref, out)
    runs = datasets.open(out).meta["runs"]
    assert runs[0]["interrupted"] is True and runs[-1]["interrupted"] is False


_DIE_SEED: list[int] = []


def _die_on_last(job):
    if job.seed in _DIE_SEED:
        os._exit(9)  # a worker killed half-way through the run
    return _slide(job)


@pytest.mark.slow
def test_a_killed_worker_stops_the_run_and_resume_completes_it(tiny, tmp_path):
    cfg, ref = tiny
    out = tmp_path / "w.zarr"
    _DIE_SEED[:] = [int(datasets.open(ref).seeds[-1])]
    with pytest.raises(StoreError, match="worker process died.*--resume"):
        _quiet(str(cfg), out, workers=2, _worker=_die_on_last)
    assert 0 < int((datasets.open(out).checksums() != 0).sum()) < 6
    res = _quiet(str(cfg), out, workers=2, resume=True)
    assert res["resumed"] and res["written"] + res["reused"] == 6
    assert_same_store(ref, out)


def test_corrupted_chunks_are_found_and_written_again(tiny, tmp_path):
    cfg, ref = tiny
    out = tmp_path / "bad.zarr"
    shutil.copytree(ref, out)
    truncated = sample_chunk(out, 1)
    truncated.write_bytes(truncated.read_bytes()[:20])
    # a valid chunk with other samples (slide 3's): decodes, fails the checksum
    sample_chunk(out, 4).write_bytes(sample_chunk(out, 3).read_bytes())
    sample_chunk(out, 5).unlink()  # lost: reads as NaN fill
    st = datasets.open(out)
    with pytest.raises(StoreError, match="slide 1 .*(unreadable|checksum)"):
        st[1]
    assert [i for i, _ in st.verify()] == [1, 4, 5]
    np.testing.assert_array_equal(st[0], datasets.open(ref)[0])
    lines: list[str] = []
    res = generate(str(cfg), out, workers=1, resume=True, progress=False, log=lines.append)
    assert res["regenerated"] == 3 and res["written"] == 3 and res["reused"] == 3
    assert [c["slide"] for c in res["corrupt"]] == [1, 4, 5]
    assert any("slide 4: checksum mismatch" in line for line in lines), lines
    assert_same_store(ref, out)
    assert datasets.open(out).verify() == []


def test_a_flipped_label_is_refused_by_readers_and_run_and_resume_writes_it_again(tiny, tmp_path):
    """The issue users met: one bit of ``labels/c/0`` relabelled a slide, ``verify()`` was
    clean, ``--resume`` reused everything and ``run --store`` scored the wrong labels."""
    from sim_tactile.tasks.config_task import config_task
    from sim_tactile.tasks.registry import DataRequest
    from sim_tactile.tasks.runner import task_data

    cfg, ref = tiny
    out = tmp_path / "flip.zarr"
    shutil.copytree(ref, out)
    chunk = out / "labels" / "c" / "0"
    b = bytearray(chunk.read_bytes())
    b[-1] ^= 0x01  # in the last value: decodes, as another label
    chunk.write_bytes(bytes(b))
    with pytest.raises(StoreError, match="'labels'.*--resume"):
        datasets.open(out)
    spec, seed = config_task(cfg)
    with pytest.raises(StoreError, match="'labels'"):
        task_data(spec, DataRequest(None, False, seed, lambda m: None, out))
    lines: list[str] = []
    res = generate(str(cfg), out, workers=1, resume=True, progress=False, log=lines.append)
    assert res["repaired"] == ["labels"] and res["written"] == 0 and res["reused"] == 6
    assert any("'labels' was damaged" in line for line in lines), lines
    assert_same_store(ref, out)
    assert datasets.open(out).verify() == []


def test_existing_stores_and_other_configurations_are_refused(tiny, tmp_path):
    cfg, ref = tiny
    before = {p: p.stat().st_mtime_ns for p in ref.rglob("*") if p.is_file()}
    with pytest.raises(StoreError, match="already exists .*6 written.*--resume"):
        _quiet(str(cfg), ref, workers=1)
    other = _write(tmp_path / "other.json", {**TINY, "slides_per_plate": 4})
    with pytest.raises(StoreError, match="another configuration.*slides_per_plate: 3 in the"):
        _quiet(str(other), ref, workers=1, resume=True)
    with pytest.raises(StoreError, match="another configuration.*seed"):
        _quiet(str(cfg), ref, workers=1, resume=True, seed=8)
    assert before == {p: p.stat().st_mtime_ns for p in ref.rglob("*") if p.is_file()}
    (tmp_path / "notastore").mkdir()
    with pytest.raises(StoreError, match="not a data set"):
        _quiet(str(cfg), tmp_path / "notastore", resume=True)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            {"protocol": {"speed_m_s": 2.0}},
            r"protocol.speed_m_s = 2 m/s is out of range; valid: \[0, 1\]",
        ),
        ({"protocol": {"force_n": "one"}}, "protocol.force_n must be a number"),
        ({"protocol": {"speed_jitter": 0.1}}, r"speed_jitter.*put the jitters under \[randomise\]"),
        (
            {"randomise": {"force_jitter": 0.9}},
            r"randomise.force_jitter = 0.9 is out of range; valid: \[0, 0.5\]",
        ),
        (
            {"randomise": {"spin": 1}},
            r"unknown key\(s\) randomise.spin; valid: randomise.speed_jitter",
        ),
        ({"slides_per_plate": 1}, r"slides_per_plate = 1 is out of range; valid: \[2, 100000\]"),
        ({"slides_per_plate": 2.5}, "slides_per_plate must be an integer"),
        ({"seed": -1}, r"seed = -1 is out of range"),
        ({"plates": ["finger7/flat"]}, "at least 2 distinct plates"),
        (
            {"plates": ["finger7/flat", "finger7/nope"]},
            "plate 'finger7/nope' is not a preset; valid: ",
        ),
        ({"sensor": "grid9"}, "sensor = 'grid9' is not valid; valid: .*grid3x3"),
        ({"fidelity": "L7"}, "fidelity = 'L7' is not valid; valid: auto, L0"),
        (
            {"finger": {"young_pa": 10.0}},
            r"finger.young_pa = 10 Pa is out of range; valid: \[1000, 1e\+09\]",
        ),
        (
            {"finger": {"size_m": [0.004, 0.004], "edge_radius_m": 0.0}},
            "smaller than the grid3x3 layout",
        ),
        ({"finger": {"colour": "red"}}, r"unknown key\(s\) finger.colour; valid: finger.shape"),
        ({"colour": "red"}, "unknown key.*colour; valid: name"),
        ({"rig": {"pitch": 1}}, r"rig: unknown key\(s\) pitch; valid: node_pitch_m"),
        ({"rig": {"direction": "up"}}, "rig direction = 'up' is not valid; valid: both"),
        ({"rig": {}, "protocol": {}}, "probe rig needs protocol.duration_s"),
        ({"paper_stack": "yes"}, "paper_stack must be true or false"),
        (
            {"paper_stack": True, "finger": {"young_pa": 1e6}},
            "paper_stack = true and .finger. both set the skin",
        ),
    ],
)
def test_bad_configuration_values_are_named(tmp_path, change, message):
    path = _write(tmp_path / "bad.json", {**TINY, **change})
    with pytest.raises(ConfigError, match=f"configuration file .*bad.json: .*{message}"):
        _quiet(str(path), tmp_path / "x.zarr")
    assert not (tmp_path / "x.zarr").exists()


@pytest.mark.slow
def test_bad_files_and_names(tmp_path, cli_env):
    bad = tmp_path / "bad.toml"
    bad.write_text("plates = [\n")
    with pytest.raises(ConfigError, match="cannot be parsed"):
        _quiet(str(bad), tmp_path / "x.zarr")
    with pytest.raises(ConfigError, match="neither a task id .*finger7-v1.* nor a configuration"):
        _quiet("finger9-v1", tmp_path / "x.zarr")
    with pytest.raises(ConfigError, match="does not exist"):
        _quiet(str(tmp_path / "missing.toml"), tmp_path / "x.zarr")
    p = subprocess.run(
        [EXE, "generate", "finger9-v1", "--out", str(tmp_path / "x.zarr"), "--json"],
        env=cli_env,
        capture_output=True,
        text=True,
    )
    assert p.returncode == 2 and p.stdout == "" and "neither a task id" in p.stderr


def test_open_iterates_lazily_and_export_round_trips(tiny, tmp_path, cli_env):
    cfg, ref = tiny
    st = datasets.open(ref)
    assert len(st) == 6 and st.class_names == ("flat", "ridges-2") and st.units == "V"
    assert st.labels.tolist() == [0, 0, 0, 1, 1, 1] and st.slide_numbers.tolist() == [0, 1, 2] * 2
    assert st.channel_names[:2] == ("r0c0", "r0c1") and st.rate_hz == 100.0
    meta = st.meta
    assert meta["config"]["plates"] == TINY["plates"] and meta["config"]["seed"] == 7
    assert meta["versions"]["zarr"] and meta["code_version"] and meta["complete"]
    assert meta["dataset_meta"]["config_file"]["name"] == "tiny"
    pairs = list(st)
    assert len(pairs) == 6 and all(x.shape == (20, 9) and x.dtype == np.float32 for x, _ in pairs)
    rec = st.recording(4)
    assert rec.meta["class"] == "ridges-2" and rec.meta["slide"] == 1 and rec.taxels.shape == (9, 3)
    assert abs(rec.meta["params"]["speed_m_s"] - 0.06) < 0.02
    x, y = next(st.batches(4))
    assert x.shape == (4, 20, 9) and y.tolist() == [0, 0, 0, 1]
    ds = st.to_tactile()
    assert ds.data.shape == (6, 20, 9) and ds.meta["config_hash"] == st.config_hash
    # export, and back
    p = subprocess.run(
        [EXE, "export", str(ref), "--out", str(tmp_path / "npy"), "--json"],
        env=cli_env,
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stderr
    doc = json.loads(p.stdout)
    assert doc["slides"] == 6
    out = tmp_path / "npy"
    np.testing.assert_array_equal(np.load(out / "data.npy"), ds.data)
    np.testing.assert_array_equal(np.load(out / "labels.npy"), st.labels)
    np.testing.assert_array_equal(np.load(out / "seed.npy"), st.seeds)
    np.testing.assert_array_equal(np.load(out / "params.npy")[:, 0], st.params["speed_m_s"])
    meta = json.loads((out / "meta.json").read_text())
    assert meta["config_hash"] == st.config_hash and meta["class_names"] == ["flat", "ridges-2"]
    with pytest.raises(StoreError, match="not an empty folder"):
        datasets.export(ref, out)


def _round_trip(ds, path):
    st = from_tactile(ds, path, name="real")
    back = st.to_tactile()
    np.testing.assert_array_equal(back.data, ds.data)
    np.testing.assert_array_equal(back.labels, ds.labels)
    assert back.channel_names == ds.channel_names and back.class_names == ds.class_names
    assert st.verify() == [] and st.complete


def test_any_data_set_takes_the_store_form(tiny, tmp_path):
    _round_trip(datasets.open(tiny[1]).to_tactile(), tmp_path / "sim.zarr")


def test_real_recordings_take_the_same_form(tmp_path, dataset_dir):
    _round_trip(datasets.load_biotac(dataset_dir, slides=2, materials=2), tmp_path / "real.zarr")


@pytest.fixture
def tiny_task():
    """A registered task whose quick data is the tiny set (removed again afterwards)."""
    from sim_tactile.encoders.encodings import threshold_encoding
    from sim_tactile.sim.plan.protocol import Protocol
    from sim_tactile.slides import SlideSet
    from sim_tactile.tasks import Settings, TaskSpec, register
    from sim_tactile.tasks.registry import unregister

    spec = TaskSpec(
        id="generate-tiny-v1",
        title="two plates, tiny",
        get_data=SlideSet(
            plates=("finger7/flat", "finger7/ridges-2"),
            sensor="grid3x3",
            protocol=Protocol(duration_s=0.2, speed_jitter=0.05, force_jitter=0.1),
            slides=4,
            quick_slides=3,
        ),
        classifiers=("svm-raw",),
        split="2/1",
        quick=Settings(repeats=2, split="2/1"),
        encoder=threshold_encoding,
    )
    register(spec)
    yield spec
    unregister(spec.id)


@pytest.mark.slow
def test_tasks_read_their_data_from_a_store(tiny_task, tmp_path):
    from sim_tactile.tasks import DataRequest, run_task
    from sim_tactile.tasks.runner import task_data

    out = tmp_path / "task.zarr"
    res = _quiet("generate-tiny-v1", out, quick=True, workers=2, seed=3)
    assert res["trials"] == 6
    log: list[str] = []
    stored = task_data(tiny_task, DataRequest(None, True, 3, log.append, out))
    assert any("reading 6 slides" in line for line in log)
    # the same slides as the task's own simulation (the slide cache's path)
    direct = tiny_task.get_data(DataRequest(None, True, 3, log.append))
    np.testing.assert_array_equal(stored.data, direct.data)
    np.testing.assert_array_equal(stored.labels, direct.labels)
    assert stored.class_names == direct.class_names and stored.meta["window_s"] == 0.2
    with pytest.raises(StoreError, match="quick data, not generate-tiny-v1"):
        task_data(tiny_task, DataRequest(None, False, 3, log.append, out))
    with pytest.raises(StoreError, match="another configuration"):
        task_data(tiny_task, DataRequest(None, True, 4, log.append, out))
    rep = run_task(
        "generate-tiny-v1", tmp_path / "run", quick=True, seed=3, store=out, log=log.append
    )
    assert rep["results"][0]["classifier"] == "svm-raw"
    assert rep["timing"]["simulate_s"] == 0.0


def _fake_slide(job):
    """A constant of the slide's shape (no physics): for the store's layout of a suite."""
    taxels = job.sensor.layout.positions
    x = np.full((job.n_samples(), len(taxels)), job.seed % 97, np.float32)
    times = np.arange(len(x)) / job.protocol.rate_hz
    return SlideOutcome(Recording(x, times, taxels), (), 0.0, False)


@pytest.mark.slow
def test_a_suite_gets_one_group_per_part(tmp_path):
    out = tmp_path / "t20.zarr"
    res = _quiet("textures20-v1", out, quick=True, workers=1, _worker=_fake_slide)
    assert res["parts"] == ["textures20-biotac19-v1", "textures20-icub60-v1"]
    assert res["trials"] == 2 * 4 * 3
    with pytest.raises(StoreError, match="holds the parts of textures20-v1"):
        datasets.open(out)
    bio = datasets.open(out, part="textures20-biotac19-v1")
    icub = datasets.open(out / "textures20-icub60-v1")
    assert len(bio.channel_names) == 19 and len(icub.channel_names) == 60
    assert bio.class_names == ("flat", "grating-4.0mm", "boxes-4.5mm", "hemispheres-6.0mm")
    assert bio.meta["config"]["task"] == "textures20-biotac19-v1" and icub.complete
    doc = datasets.export(out, tmp_path / "npy")
    assert (
        doc["slides"] == 24 and (tmp_path / "npy" / "textures20-icub60-v1" / "data.npy").is_file()
    )
    with pytest.raises(StoreError, match="already exists"):
        _quiet("textures20-v1", out, quick=True, _worker=_fake_slide)
    res = _quiet("textures20-v1", out, quick=True, resume=True, _worker=_fake_slide)
    assert res["reused"] == 24 and res["written"] == 0
    # a part's damaged index array and slide: refused by readers, written again by --resume
    icub = out / "textures20-icub60-v1"
    labels = icub.joinpath("labels", "c", "0")
    labels.write_bytes(labels.read_bytes()[:-1])
    with pytest.raises(StoreError, match="textures20-icub60-v1'.*'labels'"):
        datasets.open(out, part="textures20-icub60-v1")
    sample_chunk(icub, 2).unlink()
    res = _quiet("textures20-v1", out, quick=True, resume=True, _worker=_fake_slide)
    assert res["repaired"] == ["textures20-icub60-v1/labels"] and res["written"] == 1
    assert [c["slide"] for c in res["corrupt"]] == [2]
    assert datasets.open(out, part="textures20-icub60-v1").verify() == []


@pytest.mark.slow
def test_a_configuration_on_the_probe_rig_writes_its_slides(tmp_path):
    """``[rig]`` and ``paper_stack``: the multilayer paper's rig from a user's file, whole
    windows of both plates written, each slide the rig's (its meta says so)."""
    cfg = {
        "name": "rig",
        "seed": 3,
        "plates": ["multilayer3/flat", "multilayer3/grating-9"],
        "sensor": "multilayer3x3x2",
        "slides_per_plate": 2,
        "paper_stack": True,
        "protocol": {"speed_m_s": 0.065, "force_n": 5.0, "duration_s": 1.2},
        "rig": {"direction": "+x"},
    }
    out = tmp_path / "rig.zarr"
    _quiet(str(_write(tmp_path / "rig.json", cfg)), out)
    ds = datasets.open_store(out).to_tactile()
    assert ds.data.shape == (4, 120, 18) and list(ds.labels) == [0, 0, 1, 1]
    flat, grating = ds.data[:2], ds.data[2:]
    assert np.ptp(grating[:, :, 4]) > np.ptp(flat[:, :, 4])  # the ridges pass the centre
