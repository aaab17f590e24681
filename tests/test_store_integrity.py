"""A store verifies everything it serves: a changed index array, slide, checksum, metadata
file or attribute is refused by every reader with one StoreError naming what is damaged (or
written again by ``--resume``), crafted metadata never reaches a path outside the output
folder, and every fault is one line with nothing left behind (damage, full disk, read-only
folders). The stores are made with a fake worker (no physics): :mod:`_stores`."""

from __future__ import annotations

import builtins
import errno
import importlib
import io
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
import zarr
from _stores import (
    TINY,
    assert_same,
    chunk_file,
    flip_bit,
    make_store,
    quiet_generate,
    read_back,
    sample_chunk,
    write_config,
)

from sim_tactile import datasets
from sim_tactile.cli import main
from sim_tactile.datasets.integrity import INDEX_DTYPES, chunk_files, sealed, values_digest
from sim_tactile.errors import ConfigError, StoreError

INDEX = tuple(INDEX_DTYPES)
export_mod = importlib.import_module("sim_tactile.datasets.export")  # (the name is a function)


@pytest.fixture(scope="module")
def ref(tmp_path_factory) -> Path:
    return make_store(tmp_path_factory.mktemp("ref"))


@pytest.fixture(scope="module")
def ref_back(ref) -> dict:
    return read_back(ref)


@pytest.fixture
def store(ref, tmp_path) -> Path:
    """A copy of the reference store, and the configuration file that made it."""
    out = tmp_path / "s.zarr"
    shutil.copytree(ref, out)
    write_config(tmp_path)
    return out


def _resume(store: Path) -> dict:
    return quiet_generate(store.parent / "tiny.json", store, resume=True)


def _files(folder: Path) -> dict:
    return {p: p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _attrs_doc(path: Path) -> dict:
    return json.loads((path / "zarr.json").read_text())


def _craft(path: Path, seal: bool = True, **changes) -> None:
    """Change a group's attributes (``None``: remove the key), re-sealed as a forger would."""
    doc = _attrs_doc(path)
    attrs = doc["attributes"]
    for k, v in changes.items():
        attrs.pop(k) if v is None else attrs.__setitem__(k, v)
    doc["attributes"] = sealed(attrs) if seal else attrs
    (path / "zarr.json").write_text(json.dumps(doc))


def _one_line(err: pytest.ExceptionInfo) -> str:
    msg = str(err.value)
    assert "\n" not in msg and "Traceback" not in msg
    return msg


@pytest.mark.parametrize("name", INDEX)
def test_other_values_in_an_index_array_are_refused_then_written_again(store, ref_back, name):
    g = zarr.open_group(str(store), mode="r+")
    a = g[name]
    x = a[...]
    a[...] = x - 1 if name == "lengths" else x[::-1]  # valid chunks, other values
    with pytest.raises(StoreError, match=f"'{name}': its values do not match.*--resume") as e:
        datasets.open(store)
    _one_line(e)
    with pytest.raises(StoreError, match=name):
        datasets.export(store, store.parent / "npy")
    assert not (store.parent / "npy").exists()
    res = _resume(store)
    assert res["repaired"] == [name] and res["written"] == 0
    assert_same(read_back(store), ref_back)


def test_a_flipped_bit_in_a_slide_names_the_slide_and_resume_writes_it(store, ref_back):
    chunk = sample_chunk(store, 4)
    flip_bit(chunk, 8 * (chunk.stat().st_size - 3))
    st = datasets.open(store)
    np.testing.assert_array_equal(st[3], ref_back["slides"][3])
    for read in (lambda: st[4], lambda: list(st.batches(2)), st.to_tactile, lambda: list(st)):
        with pytest.raises(StoreError, match=r"slide 4 of .*verify\(\).*--resume") as e:
            read()
        _one_line(e)
    assert [i for i, _ in st.verify()] == [4]
    with pytest.raises(StoreError, match="slide 4"):
        datasets.export(store, store.parent / "npy")
    assert not (store.parent / "npy").exists()
    res = _resume(store)
    assert [c["slide"] for c in res["corrupt"]] == [4] and res["written"] == 1
    assert_same(read_back(store), ref_back)


def test_a_damaged_checksum_chunk_is_found_and_written_again(store, ref_back):
    (store / "checksum" / "c" / "2").write_bytes(b"\x01\x02\x03")  # truncated
    flip_bit(store / "checksum" / "c" / "5", 3)
    st = datasets.open(store)
    (two, why2), (five, why5) = st.verify()
    assert (two, five) == (2, 5) and why2.startswith("its checksum chunk cannot be read (")
    assert why5 == "checksum mismatch (the chunk was altered, truncated or moved)"
    with pytest.raises(StoreError, match="slide 2 of .*checksum"):
        st[2]
    with pytest.raises(StoreError, match="slide 2"):
        st.to_tactile()
    res = _resume(store)
    assert sorted(c["slide"] for c in res["corrupt"]) == [2, 5]
    assert_same(read_back(store), ref_back)


def test_a_slide_moved_with_its_checksum_is_found(store):
    for src, dst in (
        (sample_chunk(store, 3), sample_chunk(store, 4)),
        (chunk_file(store, "checksum", 3), chunk_file(store, "checksum", 4)),
    ):
        shutil.copy(src, dst)
    with pytest.raises(StoreError, match="slide 4 .*moved"):
        datasets.open(store)[4]


def _truncate(p: Path) -> None:
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])


def _rename_class(p: Path) -> None:
    (p / "zarr.json").write_text((p / "zarr.json").read_text().replace('"flat"', '"flap"'))


def _fill(p: Path) -> None:
    doc = json.loads((p / "data" / "zarr.json").read_text())
    doc["fill_value"] = 0.0
    (p / "data" / "zarr.json").write_text(json.dumps(doc, indent=2))


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        (_rename_class, "attributes .* do not match their digest"),
        (lambda p: _truncate(p / "zarr.json"), "zarr.json cannot be read"),
        (lambda p: (p / "zarr.json").write_text("{"), "zarr.json cannot be read"),
        (_fill, "data/zarr.json does not match its digest"),
        (lambda p: _truncate(p / "labels" / "zarr.json"), "labels/zarr.json does not match"),
        (lambda p: (p / "checksum" / "zarr.json").unlink(), "checksum/zarr.json is missing"),
        (lambda p: shutil.rmtree(p / "slide"), "slide/zarr.json is missing"),
    ],
)
def test_damaged_metadata_is_refused_by_readers_and_resume(store, damage, message):
    damage(store)
    before = _files(store)
    with pytest.raises(StoreError, match=message) as e:
        datasets.open(store)
    _one_line(e)
    with pytest.raises(StoreError, match=message):
        _resume(store)
    assert _files(store) == before  # nothing written into a store that cannot be trusted


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"n_slides": "6"}, "n_slides = '6' is not valid"),
        ({"n_slides": 10**12}, r"n_slides = 1000000000000 is not valid \(an integer in"),
        ({"n_slides": 7}, r"'data' is \(6, 20, 9\) float32, the attributes say \(7, 20, 9\)"),
        ({"n_time": 10**12}, "n_time = .* is not valid"),
        ({"n_time": 2 * 10**7}, r"n_time = 20000000 is not valid \(n_time x channels <="),
        ({"class_names": None}, "class_names = None is not valid"),
        ({"class_names": "flat"}, "class_names = 'flat' is not valid"),
        ({"channel_names": ["a"]}, "taxel_positions|'data' is"),
        ({"rate_hz": -1.0}, "rate_hz = -1.0 is not valid"),
        ({"config_hash": "0123456789abcdef"}, r"config_hash = .* \(the hash of its config\)"),
        ({"config": [1]}, r"config = \[1\] is not valid \(dict expected\)"),
        ({"taxel_positions": [[1.0]]}, "taxel_positions = .* is not valid"),
        ({"integrity": None}, "integrity = None is not valid"),
        ({"integrity": {"files": {}, "values": {}}}, "a digest of every array"),
        ({"complete": "yes"}, "complete = 'yes' is not valid"),
        ({"runs": {"a": 1}}, "runs = .* is not valid"),
        ({"format": None}, "not a sim_tactile data set"),
        ({"format_version": 1}, "made by an older version of sim_tactile .*generate it again"),
        ({"format_version": 99}, "store format 99; .*newer"),
    ],
)
def test_crafted_attributes_are_refused(store, changes, message):
    _craft(store, **changes)
    with pytest.raises(StoreError, match=message) as e:
        datasets.open(store)
    _one_line(e)


def test_crafted_file_digests_never_name_a_path_outside_the_store(store):
    integ = _attrs_doc(store)["attributes"]["integrity"]
    for rel in ("../escape/zarr.json", "/etc/hostname"):
        _craft(store, integrity={**integ, "files": {**integ["files"], rel: "0"}})
        with pytest.raises(StoreError, match="integrity.files .*relative names"):
            datasets.open(store)


def _suite(tmp_path: Path, store: Path, parts: list) -> Path:
    """A suite's store holding ``store`` as the part ``p1``, whose ``parts`` claim ``parts``."""
    suite = tmp_path / "suite.zarr"
    suite.mkdir()
    shutil.copytree(store, suite / "p1")
    attrs = {"format": "sim_tactile.slides", "format_version": 2, "suite": "x", "parts": parts}
    attrs["config_hash"] = "0123456789abcdef"
    doc = {"zarr_format": 3, "node_type": "group", "attributes": sealed(attrs)}
    (suite / "zarr.json").write_text(json.dumps(doc))
    return suite


@pytest.mark.parametrize("bad", ["ABS", "../escape", "a/b", "..", "", 3, "p1\\..\\x"])
def test_a_suite_whose_parts_leave_the_store_is_refused(store, tmp_path, bad):
    target = tmp_path / "elsewhere"
    bad = str(target) if bad == "ABS" else bad
    suite = _suite(tmp_path, store, ["p1", bad])
    out = tmp_path / "npy"
    for call in (
        lambda: datasets.export(suite, out),
        lambda: datasets.open(suite, part="p1"),
        lambda: datasets.parts_of(suite),
    ):
        with pytest.raises(StoreError, match="parts = .* plain folder names"):
            call()
    assert not target.exists() and not out.exists()
    assert not (tmp_path / "escape").exists()


def test_a_plain_suite_exports_each_part(store, tmp_path, ref_back):
    suite = _suite(tmp_path, store, ["p1"])
    (tmp_path / "npy").mkdir()  # an empty folder is taken
    doc = datasets.export(suite, tmp_path / "npy")
    assert doc["parts"]["p1"]["out"] == str(tmp_path / "npy" / "p1") and doc["slides"] == 6
    np.testing.assert_array_equal(np.load(tmp_path / "npy" / "p1" / "data.npy"), ref_back["data"])
    meta = json.loads((tmp_path / "npy" / "p1" / "meta.json").read_text())
    assert "integrity" not in meta and meta["config_hash"] == ref_back["meta"]["config_hash"]


def test_a_plate_map_is_checked_against_its_digest(tmp_path):
    from sim_tactile.datasets.export import spec_from_tactile
    from sim_tactile.datasets.lock import StoreLock
    from sim_tactile.datasets.store import create_store
    from sim_tactile.records import TactileDataset

    ds = TactileDataset(
        np.ones((2, 4, 2), np.float32), np.array([0, 1]), 10.0, ("a", "b"), ("x", "y")
    )
    spec = spec_from_tactile(ds, "maps")
    spec.plate_maps = {"ab12": np.arange(12.0).reshape(3, 4)}
    out = tmp_path / "m.zarr"
    with StoreLock(out):
        create_store(out, {"": spec}, {})
    st = datasets.open(out)
    assert st.verify() == [(0, "not written"), (1, "not written")]
    zarr.open_group(str(out), mode="r+")["plate_maps"]["ab12"][0, 0] = 5.0
    with pytest.raises(StoreError, match="plate map ab12 does not match its digest"):
        datasets.open(out).verify()


# ---------------------------------------------------------------- export: nothing left behind
def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def test_a_failed_export_leaves_nothing_behind(store, tmp_path, monkeypatch):
    out = tmp_path / "new" / "deeper" / "npy"
    flip_bit(sample_chunk(store, 5), 200)
    with pytest.raises(StoreError, match="slide 5"):
        datasets.export(store, out)
    assert not (tmp_path / "new").exists() and _leftovers(tmp_path) == []
    with pytest.raises(ConfigError, match="--format 'hdf5' is not valid; valid: numpy"):
        datasets.export(store, out, format="hdf5")
    assert not (tmp_path / "new").exists()
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("mine")
    with pytest.raises(StoreError, match="not an empty folder"):
        datasets.export(store, tmp_path / "full")
    assert [p.name for p in (tmp_path / "full").iterdir()] == ["x"]


@pytest.mark.parametrize(
    ("code", "message"),
    [(errno.ENOSPC, "no space left on device writing {out}"), (errno.EROFS, "{out} is read-only")],
)
def test_a_full_or_read_only_disk_is_one_line_and_leaves_nothing(
    ref, tmp_path, monkeypatch, code, message
):
    out = tmp_path / "npy"

    def refuse(*a, **k):
        raise OSError(code, os.strerror(code))

    for name in ("open", "np"):  # the streamed data.npy, then the small arrays
        with monkeypatch.context() as mp:
            if name == "open":
                mp.setattr(export_mod, "open", refuse, raising=False)
            else:
                mp.setattr(export_mod.np, "save", refuse)
            with pytest.raises(StoreError) as e:
                datasets.export(ref, out)
        assert _one_line(e) == message.format(out=out) + (
            " (cannot write there)" if code == errno.EROFS else ""
        )
        assert not out.exists() and _leftovers(tmp_path) == []


def _refuse_writes_under(monkeypatch, root: Path, code: int = errno.EROFS) -> None:
    """Every write, rename, removal or folder made under ``root`` fails with ``code`` (a
    read-only file system, simulated: the tests may run as root)."""
    root_s = str(root)

    def under(p) -> bool:
        return str(os.fspath(p)).startswith(root_s) if isinstance(p, str | os.PathLike) else False

    def refuse(p):
        raise OSError(code, os.strerror(code), str(p))

    real_open, real_os_open = io.open, os.open

    def guarded_open(file, mode="r", *a, **k):
        if under(file) and any(c in mode for c in "wax+"):
            refuse(file)
        return real_open(file, mode, *a, **k)

    def guarded_os_open(path, flags, *a, **k):
        if under(path) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT):
            refuse(path)
        return real_os_open(path, flags, *a, **k)

    monkeypatch.setattr(builtins, "open", guarded_open)
    monkeypatch.setattr(io, "open", guarded_open)
    monkeypatch.setattr(os, "open", guarded_os_open)
    for name in ("mkdir", "rename", "replace", "unlink", "rmdir", "link"):
        real = getattr(os, name)

        def guarded(p, *a, _real=real, **k):
            if under(p):
                refuse(p)
            return _real(p, *a, **k)

        monkeypatch.setattr(os, name, guarded)


def test_a_complete_read_only_store_reads_and_is_not_written(store, ref_back, monkeypatch):
    _refuse_writes_under(monkeypatch, store.parent)
    assert_same(read_back(store), ref_back)
    with pytest.raises(StoreError) as e:
        _resume(store)
    assert _one_line(e) == f"{store} is read-only (cannot write there)"


def test_writing_a_store_on_a_full_disk_keeps_what_was_written(
    store, ref_back, tmp_path, monkeypatch
):
    from sim_tactile.datasets.chunks import ChunkFile

    out = tmp_path / "full.zarr"
    calls = {"n": 0}
    real, real_chunk = zarr.Array.__setitem__, ChunkFile.write

    def counted(write):
        def call(self, key, value):
            calls["n"] += 1
            if calls["n"] > 5 + 2 * 3:  # the 5 index arrays, and data + checksum of 3 slides
                raise OSError(errno.ENOSPC, "No space left on device")
            return write(self, key, value)

        return call

    with monkeypatch.context() as mp:  # through Zarr, or the slides' own chunk files
        mp.setattr(zarr.Array, "__setitem__", counted(real))
        mp.setattr(ChunkFile, "write", counted(real_chunk))
        with pytest.raises(StoreError) as e:
            quiet_generate(tmp_path / "tiny.json", out)
    msg = _one_line(e)
    assert msg.startswith(f"no space left on device writing {out}; ") and "--resume" in msg
    st = datasets.open(out)
    assert st.missing() == 3 and st.meta["runs"][-1]["written"] == 3
    res = quiet_generate(tmp_path / "tiny.json", out, resume=True)
    assert res["reused"] == 3 and res["written"] == 3
    assert_same(read_back(out), ref_back)
    # a full disk while the store is made: nothing is left

    def full(*a):
        raise OSError(errno.ENOSPC, "No space left on device")

    with monkeypatch.context() as mp:
        mp.setattr(zarr.Array, "__setitem__", full)
        with pytest.raises(
            StoreError, match=f"no space left on device writing {tmp_path / 'new.zarr'}"
        ):
            quiet_generate(tmp_path / "tiny.json", tmp_path / "new.zarr")
    assert not (tmp_path / "new.zarr").exists() and ".creating" not in str(_leftovers(tmp_path))
    deep = tmp_path / "a" / "b" / "new.zarr"  # and no folder it made for it
    with monkeypatch.context() as mp:
        mp.setattr(zarr.Array, "__setitem__", full)
        with pytest.raises(StoreError, match=f"no space left on device writing {deep}"):
            quiet_generate(tmp_path / "tiny.json", deep)
    assert not (tmp_path / "a").exists() and _leftovers(tmp_path) == []


def test_run_and_export_on_a_damaged_store_say_one_line_and_leave_no_folder(
    store, tmp_path, capsys
):
    flip_bit(store / "labels" / "c" / "0", 8 * 12 + 1)
    cfg = tmp_path / "tiny.json"
    for argv in (
        ["run", str(cfg), "--store", str(store), "--out", str(tmp_path / "run" / "out")],
        ["export", str(store), "--out", str(tmp_path / "npy")],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and err.startswith("sim-tactile: error: ") and "labels" in err
    assert main(["export", str(store), "--out", str(tmp_path / "x"), "--format", "hdf5"]) == 2
    assert "--format = 'hdf5' is not valid; valid: numpy, parquet" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr", "tiny.json"]


def test_a_store_whose_index_disagrees_with_its_configuration_is_refused(store, tmp_path):
    """A store consistent in itself (digests re-sealed) whose labels are not the ones its
    configuration gives: ``run --store`` and ``--resume`` derive them again and refuse."""
    g = zarr.open_group(str(store), mode="r+")
    labels = g["labels"][...]
    labels[[0, 5]] = labels[[5, 0]]
    g["labels"][...] = labels
    integ = _attrs_doc(store)["attributes"]["integrity"]
    integ["values"]["labels"] = values_digest(labels)
    integ["files"].update(chunk_files(store, "labels"))
    _craft(store, integrity=integ)
    assert datasets.open(store).labels.tolist() == [1, 0, 0, 1, 1, 0]  # reads: self-consistent
    from sim_tactile.tasks.config_task import config_task
    from sim_tactile.tasks.registry import DataRequest
    from sim_tactile.tasks.runner import task_data

    spec, seed = config_task(tmp_path / "tiny.json")
    with pytest.raises(StoreError, match=r"labels of slide 0 is 1, its configuration gives 0"):
        task_data(spec, DataRequest(None, False, seed, lambda m: None, store))
    with pytest.raises(StoreError, match=r"labels of slide 0 is 1, its configuration gives 0"):
        _resume(store)
    assert TINY["slides_per_plate"] == 3


@pytest.mark.parametrize(
    ("code", "message"), [(errno.ENOSPC, "no space left on device writing"), (errno.EROFS, "")]
)
def test_run_on_a_full_or_read_only_disk_is_one_line_and_leaves_no_folder(
    store, tmp_path, monkeypatch, code, message
):
    from sim_tactile.tasks import runner

    out = tmp_path / "run" / "out"

    def refuse(spec, ds, folder, **kw):
        folder.mkdir(parents=True)
        raise OSError(code, os.strerror(code), str(folder / "report.json"))

    monkeypatch.setattr(runner, "evaluate_task", refuse)
    with pytest.raises(StoreError) as e:
        runner.run_task(
            str(tmp_path / "tiny.json"), out, store=store, seed=None, log=lambda m: None
        )
    want = f"no space left on device writing {out}" if message else f"{out} is read-only"
    assert _one_line(e).startswith(want)
    assert not (tmp_path / "run").exists()
    # an input that cannot be read is not the output's fault: it passes unchanged
    monkeypatch.setattr(
        runner,
        "evaluate_task",
        lambda *a, **k: (_ for _ in ()).throw(PermissionError(13, "no", "/x")),
    )
    with pytest.raises(PermissionError):
        runner.run_task(
            str(tmp_path / "tiny.json"), out, store=store, seed=None, log=lambda m: None
        )
