"""Loaders of the real BioTac / iCub data (skipped where the data set is absent) and the
TactileDataset record."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.datasets import load_biotac, load_icub
from sim_tactile.datasets.real import read_biotac_csv
from sim_tactile.errors import ConfigError
from sim_tactile.records import Recording, TactileDataset


def test_biotac_window_channels_and_labels(dataset_dir):
    ds = load_biotac(dataset_dir, slides=2, materials=3)
    assert ds.data.shape == (6, 400, 19) and ds.data.dtype == np.float32
    assert ds.rate_hz == 100.0 and ds.duration_s == pytest.approx(4.0)
    assert ds.channel_names[0] == "ele1" and ds.channel_names[-1] == "ele19"
    np.testing.assert_array_equal(ds.labels, [0, 0, 1, 1, 2, 2])
    assert ds.class_names == ("mat1", "mat2", "mat3")
    # the window is rows 100..499 of the electrode columns of mat1_1_bio.csv
    f = dataset_dir / "raw_data" / "mat1" / "mat1_1_bio.csv"
    header = f.read_text().splitlines()[0].split(",")
    rows = np.loadtxt(f, delimiter=",", skiprows=1, usecols=[header.index("ele1")])
    np.testing.assert_array_equal(ds.data[0, :, 0], rows[100:500])


def test_icub_all_slides(dataset_dir):
    ds = load_icub(dataset_dir)
    assert ds.data.shape == (1000, 75, 60)
    assert ds.rate_hz == 50.0 and ds.meta["grid_shape"] == [6, 10]
    np.testing.assert_array_equal(ds.class_counts(), np.full(20, 50))
    raw = np.load(dataset_dir / "compiled_data" / "icub_test.npy")
    np.testing.assert_array_equal(ds.data[0, :, 13], raw[0, 1, 3, :])  # patch 1, taxel 3
    assert ds.channel_names[13] == "p1t3"


def test_missing_path_names_the_path_and_the_option(tmp_path):
    for loader in (load_biotac, load_icub):
        with pytest.raises(ConfigError, match=r"nowhere.*--data PATH"):
            loader(tmp_path / "nowhere")
        with pytest.raises(ConfigError, match="--data PATH"):
            loader(None)
        with pytest.raises(ConfigError, match="has no"):
            loader(tmp_path)


def test_a_truncated_csv_is_reported(tmp_path):
    f = tmp_path / "short.csv"
    header = "timestamp," + ",".join(f"ele{k}" for k in range(1, 20))
    f.write_text(header + "\n" + "\n".join(",".join(["1"] * 20) for _ in range(30)) + "\n")
    assert read_biotac_csv(f, start=10, n_samples=20).shape == (20, 19)
    with pytest.raises(ConfigError, match="has 30 samples"):
        read_biotac_csv(f, start=10, n_samples=400)


def _ds(**kw):
    base = dict(
        data=np.zeros((4, 10, 2)),
        labels=np.array([0, 1, 0, 1]),
        rate_hz=100.0,
        channel_names=("a", "b"),
        class_names=("x", "y"),
    )
    return TactileDataset(**{**base, **kw})


@pytest.mark.parametrize(
    ("kw", "needle"),
    [
        ({"labels": np.array([0, 1, 0])}, "4 samples but labels of shape \\(3,\\)"),
        ({"labels": np.array([0, 1, 0, 2])}, "labels must lie in \\[0, 1\\]"),
        ({"data": np.full((4, 10, 2), np.nan)}, "must be finite"),
        ({"channel_names": ("a",)}, "2 channels but 1 channel names"),
        ({"rate_hz": 0.0}, "rate_hz"),
        ({"labels": np.array([0.0, 1.0, 0.0, 1.0])}, "integers"),
    ],
)
def test_dataset_rejects_inconsistent_input(kw, needle):
    with pytest.raises(ConfigError, match=needle):
        _ds(**kw)


def test_dataset_from_recordings_and_subset():
    recs = [
        Recording(
            np.full((10, 3), k, np.float32),
            np.arange(10) / 50.0,
            np.zeros((3, 3)),
            meta={"rate_hz": 50.0},
        )
        for k in range(4)
    ]
    ds = TactileDataset.from_recordings(recs, [0, 0, 1, 1], ("flat", "ridges"))
    assert ds.data.shape == (4, 10, 3) and ds.rate_hz == 50.0
    assert ds.taxel_positions.shape == (3, 3)
    sub = ds.subset(ds.labels == 1)
    assert sub.n_samples == 2 and float(sub.data[0, 0, 0]) == 2.0
    assert not ds.data.flags.writeable
