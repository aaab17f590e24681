"""The PyTorch Dataset: a DataLoader with two workers yields the task's samples, labels and
order (tasks.load's split), raw and encoded; a store is read lazily and every item depends
on its index alone."""

from __future__ import annotations

import numpy as np
import pytest
from _fake_task import tones_fixture

from sim_tactile import datasets, tasks
from sim_tactile.encoders import ThresholdEncoder
from sim_tactile.errors import ConfigError

torch = pytest.importorskip("torch", reason="the learn extra (torch) is not installed")
from sim_tactile.formats.torch_data import TactileTorchDataset  # noqa: E402


@pytest.fixture(scope="module")
def tones(tmp_path_factory, cache_dir):
    """The tones task and its quick store (tests/_fake_task.py)."""
    yield from tones_fixture(tmp_path_factory, cache_dir)


def _all(loader):
    xs, ys = zip(*loader, strict=True)
    return torch.cat(xs).numpy(), torch.cat(ys).numpy()


@pytest.mark.parametrize("side", ["train", "test"])
def test_two_workers_yield_the_tasks_samples_in_its_order(tones, side):
    td = tasks.load(tones.task, quick=True, store=tones.store, seed=0)
    tr, te = next(td.splits())
    want = tr if side == "train" else te
    ds = TactileTorchDataset(tones.store, split=side)
    np.testing.assert_array_equal(ds.indices, want)
    loader = torch.utils.data.DataLoader(ds, batch_size=5, num_workers=2)
    x, y = _all(loader)
    np.testing.assert_array_equal(x, td.X[want])
    np.testing.assert_array_equal(y, td.y[want])
    # a seeded shuffle gives the same order twice, with workers or without
    orders = []
    for workers in (0, 2):
        g = torch.Generator().manual_seed(7)
        dl = torch.utils.data.DataLoader(
            ds, batch_size=4, shuffle=True, generator=g, num_workers=workers
        )
        orders.append(_all(dl)[1])
    np.testing.assert_array_equal(orders[0], orders[1])


def test_encoded_items_are_the_tasks_spike_rasters(tones):
    from sklearn.pipeline import Pipeline

    from sim_tactile.learn.preprocess import SpikeRaster

    td = tasks.load(tones.task, quick=True, store=tones.store)
    ctx = tones.spec.context(td.dataset, True)
    own = Pipeline(tones.spec.encoder(ctx) + [("r", SpikeRaster(dt_s=0.01))]).fit_transform(td.X)
    ds = TactileTorchDataset(td, split="test", encoded=True)
    x, y = _all(torch.utils.data.DataLoader(ds, batch_size=3, num_workers=2))
    _, te = next(td.splits())
    assert x.shape == (len(te), 50, 45)  # 9 taxels x (2K + 1) trains
    np.testing.assert_array_equal(x, own[te])
    np.testing.assert_array_equal(y, td.y[te])


def test_transforms_apply_to_each_item_and_the_short_import_is_the_class(tones):
    """``transform`` and ``target_transform`` as torchvision and Tonic take them; a value
    that is not callable is refused by name; ``sim_tactile.formats.TactileTorchDataset`` is
    the class (and importing ``sim_tactile.formats`` alone does not import torch)."""
    import subprocess
    import sys

    import sim_tactile.formats as formats

    assert formats.TactileTorchDataset is TactileTorchDataset
    plain = TactileTorchDataset(tones.store, split="test")
    ds = formats.TactileTorchDataset(
        tones.store,
        split="test",
        transform=lambda x: x.mean(dim=0),
        target_transform=lambda y: plain.classes[y],
    )
    x, name = ds[0]
    x0, y0 = plain[0]
    assert x.shape == (x0.shape[1],) and torch.allclose(x, x0.mean(dim=0))
    assert name == plain.classes[y0]
    with pytest.raises(ConfigError, match="transform = 3 is not valid; valid: a callable"):
        TactileTorchDataset(tones.store, transform=3)
    code = "import sys, sim_tactile.formats; print('torch' in sys.modules)"
    assert subprocess.check_output([sys.executable, "-c", code], text=True).strip() == "False"


def test_any_store_reads_lazily_and_checks_its_slides(tmp_path, tones):
    st = datasets.open(tones.store)
    ds = TactileTorchDataset(st)  # every slide, in store order
    assert len(ds) == len(st)
    x, y = ds[5]
    np.testing.assert_array_equal(x.numpy(), st[5])
    assert y == int(st.labels[5]) and ds[-1][1] == int(st.labels[-1])
    with pytest.raises(IndexError, match="out of range"):
        ds[len(ds)]
    raw = datasets.from_tactile(st.to_tactile(), tmp_path / "copy.zarr")
    with pytest.raises(ConfigError, match="no task split"):
        TactileTorchDataset(raw, split="test")
    with pytest.raises(ConfigError, match="holds raw sensor streams"):
        TactileTorchDataset(raw, encoded=True)
    enc = TactileTorchDataset(raw, encoder=ThresholdEncoder(rate_hz=100.0), dt_s=0.02)
    assert tuple(enc[0][0].shape) == (25, 45)
    with pytest.raises(ConfigError, match="split"):
        TactileTorchDataset(raw, split="validation")
