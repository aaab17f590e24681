"""export --format parquet: load_dataset gives the task's splits with tasks.load's labels and
shapes; mlcroissant validates the metadata and reads the records; the card says how the set
was made; bad input (an unknown format, a used folder, a corrupt slide, a missing extra)
writes nothing."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from _fake_task import tones_fixture
from _stores import TINY, make_store

from sim_tactile import datasets, tasks
from sim_tactile.errors import MissingDependencyError, StoreError

hf = pytest.importorskip("datasets", reason="the hub extra is not installed")
mlc = pytest.importorskip("mlcroissant", reason="the hub extra is not installed")
from sim_tactile.formats.hub import export_parquet  # noqa: E402


@pytest.fixture(scope="module")
def tones(tmp_path_factory, cache_dir):
    """The tones task and its quick store (tests/_fake_task.py)."""
    yield from tones_fixture(tmp_path_factory, cache_dir)


@pytest.fixture(scope="module")
def exported(tones, tmp_path_factory):
    out = tmp_path_factory.mktemp("hub") / "tones-hub"
    return out, export_parquet(tones.store, out, rows_per_shard=5)


def test_load_dataset_gives_the_tasks_splits(tones, exported):
    out, res = exported
    assert res["configs"] == {"default": {"train": 24, "test": 12}} and res["slides"] == 36
    td = tasks.load(tones.task, quick=True, store=tones.store)
    tr, te = next(td.splits())
    for loaded in (
        hf.load_dataset("parquet", data_dir=str(out / "data" / "default")),
        hf.load_dataset(str(out)),  # the card's configs
    ):
        for side, idx in (("train", tr), ("test", te)):
            d = loaded[side].with_format("numpy")
            assert d.features["label"].names == list(td.class_names)
            np.testing.assert_array_equal(d["index"], idx)
            np.testing.assert_array_equal(d["label"], td.y[idx])
            x = np.stack(list(d["data"]))
            assert x.shape == (len(idx), *td.X.shape[1:])
            np.testing.assert_array_equal(x, td.X[idx])
    assert len(list((out / "data" / "default").glob("train-*-of-00005.parquet"))) == 5


def test_croissant_validates_and_reads_the_records(tones, exported):
    out, _ = exported
    ds = mlc.Dataset(jsonld=str(out / "croissant.json"))
    recs = list(ds.records(record_set="default-test"))
    st = datasets.open(tones.store)
    _, te = next(tasks.load(tones.task, quick=True, store=tones.store).splits())
    assert [int(r["default-test/index"]) for r in recs] == te.tolist()
    assert [int(r["default-test/label"]) for r in recs] == st.labels[te].tolist()
    doc = json.loads((out / "croissant.json").read_text())
    assert doc["@type"] == "sc:Dataset" and len(doc["recordSet"]) == 2


def test_the_card_says_what_the_set_is_and_how_it_was_made(exported):
    out, _ = exported
    text = (out / "README.md").read_text()
    header = text.split("---")[1]
    import yaml

    meta = yaml.safe_load(header)
    assert meta["license"] == "cc-by-4.0"
    assert meta["configs"][0]["data_files"][1] == {
        "split": "test",
        "path": "data/default/test-*.parquet",
    }
    for words in (
        "Sensor: `grid3x3`",
        "finger7/ridges-2",
        "Fidelity",
        "error",
        "speed_m_s 0.06",
        "sim_tactile 0.1.0",
        "## License",
        "## Citation",
        "split of task",
    ):
        assert words in text, words


def test_bad_input_writes_nothing(tones, tmp_path, cli, monkeypatch):
    used = tmp_path / "used"
    used.mkdir()
    (used / "keep.txt").write_text("mine")
    with pytest.raises(StoreError, match="not an empty folder"):
        export_parquet(tones.store, used)
    assert [p.name for p in used.iterdir()] == ["keep.txt"]
    p = cli(
        ["export", tones.store, "--out", tmp_path / "x", "--format", "hdf5", "--json"], check=False
    )
    assert p.returncode != 0 and "--format = 'hdf5' is not valid; valid: numpy, parquet" in p.stderr
    assert not (tmp_path / "x").exists()
    # a missing extra: the install command, and nothing written
    monkeypatch.setitem(sys.modules, "mlcroissant", None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'sim-tactile\[hub\]'"):
        export_parquet(tones.store, tmp_path / "y")
    assert not (tmp_path / "y").exists()


def test_a_corrupt_slide_stops_the_export_and_leaves_nothing(tones, tmp_path):
    import shutil

    import zarr

    copy = tmp_path / "bad.zarr"
    shutil.copytree(tones.store, copy)
    g = zarr.open_group(str(copy), mode="r+")
    x = g["data"][30]
    g["data"][30] = x + 1.0  # no longer its checksum
    with pytest.raises(StoreError, match="slide 30"):
        export_parquet(copy, tmp_path / "out")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.zarr"]


@pytest.mark.slow
def test_the_command_line_writes_parquet(tones, tmp_path, cli):
    # a store of no task (the console script does not know the tests' task): one split
    st = datasets.open(tones.store)
    datasets.from_tactile(st.to_tactile(), tmp_path / "plain.zarr")
    p = cli(
        [
            "export",
            tmp_path / "plain.zarr",
            "--out",
            tmp_path / "h",
            "--format",
            "parquet",
            "--json",
        ]
    )
    doc = json.loads(p.stdout)
    assert doc["format"] == "parquet" and doc["configs"] == {"default": {"train": 36}}
    assert (tmp_path / "h" / "croissant.json").is_file()
    card = (tmp_path / "h" / "README.md").read_text()
    assert "license: other" in card  # a recorded (not simulated) set keeps its own license


def _rows(loaded) -> tuple[np.ndarray, np.ndarray]:
    d = loaded["train"].with_format("numpy")
    return np.asarray(d["index"]), np.stack(list(d["data"]))


def _card_loads(folder: Path):
    """The export at ``folder`` loaded exactly as its card says: the card's Python block,
    its ``folder`` set to the folder's path."""
    code = (folder / "README.md").read_text().split("```python\n")[1].split("```")[0]
    assert 'folder = "."' in code and "load_dataset(" in code
    ns: dict = {}
    exec(code.replace('folder = "."', f"folder = {str(folder)!r}"), ns)  # our own card
    return ns["ds"]


def test_exports_in_folders_of_one_name_each_load_their_own_rows(tmp_path, monkeypatch):
    """Two stores of the same size (other seeds) and a bigger one, exported into folders
    named ``hub`` (and one ``hub`` reused after deleting it), loaded through one Hugging
    Face cache: by folder (``load_dataset(folder)``, whose cache is keyed by the folder's
    name and the card's YAML) and the way the card says, each gives its own rows. Before
    the card named its content, the second folder served the first one's rows."""
    monkeypatch.setattr(hf.config, "HF_DATASETS_CACHE", str(tmp_path / "hf-cache"))
    stores = [
        make_store(tmp_path, "a.zarr", TINY),
        make_store(tmp_path, "b.zarr", TINY | {"seed": 8}),
        make_store(tmp_path, "c.zarr", TINY | {"slides_per_plate": 5}),
    ]
    for load in (lambda folder: hf.load_dataset(str(folder)), _card_loads):
        base = tmp_path / load.__name__.strip("<>_")
        folders = [base / "a" / "hub", base / "b" / "hub", base / "a" / "hub"]
        for store, folder in zip(stores, folders, strict=True):
            if folder.exists():
                shutil.rmtree(folder)  # the same path reused for another export
            export_parquet(store, folder)
            st = datasets.open(store)
            index, data = _rows(load(folder))
            np.testing.assert_array_equal(index, np.arange(len(st)))
            np.testing.assert_array_equal(data, np.stack([st[k] for k in range(len(st))]))
    text = (folders[0] / "README.md").read_text()
    assert "content sha256" in text and "configuration hash" in text
