"""Spikes as Tonic events: the layouts' addresses (grids keep x and y, the rest put the
channel on x, several trains per channel go to polarity), every encoder's output, the exact
round trip, ToFrame's counts against the package's own encoder, PadTensors batches, and the
errors (a store of raw streams without an encoder, a layout of another size)."""

from __future__ import annotations

import numpy as np
import pytest
from _fake_task import tones_fixture

from sim_tactile import datasets, tasks
from sim_tactile.encoders import IzhikevichEncoder, LIFEncoder, ThresholdEncoder
from sim_tactile.errors import ConfigError
from sim_tactile.formats.events import EVENT_DTYPE, TactileEvents, codec_for
from sim_tactile.formats.layout import dataset_events, layout_events, train_map
from sim_tactile.records import SpikeTrains, TactileDataset
from sim_tactile.sensors.layouts import get_layout

tonic = pytest.importorskip("tonic", reason="the tonic extra is not installed")


@pytest.fixture(scope="module")
def tones(tmp_path_factory, cache_dir):
    """The tones task and its quick store (tests/_fake_task.py)."""
    yield from tones_fixture(tmp_path_factory, cache_dir)


#: Spike times that are not on the microsecond grid come back within half a microsecond.
HALF_US = 0.5e-6 + 1e-12


def _data(n_ch: int, meta: dict, n: int = 4, t: int = 60, seed: int = 0) -> TactileDataset:
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.normal(size=(n, t, n_ch)), axis=1).astype(np.float32)
    names = [f"c{i}" for i in range(n_ch)]
    return TactileDataset(x, np.arange(n) % 2, 100.0, names, ("a", "b"), meta=meta)


@pytest.mark.parametrize(
    ("name", "size", "grid"),
    [
        ("grid3x3", (3, 3, 1), True),
        ("icub60", (10, 6, 1), True),
        ("multilayer3x3x2", (3, 3, 2), True),
        ("biotac19", (19, 1, 1), False),
        ("pvdf2", (2, 1, 1), False),
    ],
)
def test_layouts_take_a_grid_or_the_channel_as_x(name, size, grid):
    lay = layout_events(get_layout(name))
    assert lay.sensor_size() == size and lay.grid == grid
    # every channel has its own address
    addr = lay.layer * lay.width * lay.height + lay.y * lay.width + lay.x
    assert np.unique(addr).size == lay.n_channels
    np.testing.assert_array_equal(
        lay.channel_at(lay.x, lay.y, lay.layer), np.arange(lay.n_channels)
    )


def test_the_grids_keep_their_rows_and_columns():
    g = layout_events(get_layout("grid3x3"))  # row-major r0c0, r0c1, ...
    np.testing.assert_array_equal(g.x, [0, 1, 2] * 3)
    np.testing.assert_array_equal(g.y, [0, 0, 0, 1, 1, 1, 2, 2, 2])
    ml = get_layout("multilayer3x3x2")
    m = layout_events(ml)
    np.testing.assert_array_equal(m.layer, ml.layer)  # top layer 0, bottom 1
    # the same place in both layers has the same (x, y)
    np.testing.assert_array_equal(m.x[:9], m.x[9:])
    np.testing.assert_array_equal(m.y[:9], m.y[9:])
    # a column runs along the slide (+x): x grows with the taxel's x position
    assert np.all(np.diff(ml.positions[np.argsort(m.x[:9]), 0]) >= 0)


def test_threshold_trains_go_to_polarity_and_come_back_exactly():
    ds = _data(9, {"grid_shape": [3, 3]})
    ev = TactileEvents(ds, encoder=ThresholdEncoder(rate_hz=100.0, n_thresholds=2))
    assert ev.sensor_size == (3, 3, 5)  # 2K + 1 = 5 trains per taxel
    enc = ev.encode.encoder
    for i in range(len(ev)):
        events, target = ev[i]
        assert events.dtype == EVENT_DTYPE and target == ds.labels[i]
        assert np.all(np.diff(events["t"]) >= 0)
        trains = enc.transform(ds.data[i : i + 1])[0]
        back = ev.codec.to_spike_trains(events, t_end_s=trains.t_end)
        assert back.channel_names == trains.channel_names
        for a, b in zip(trains.times, back.times, strict=True):
            np.testing.assert_array_equal(a, b)  # bit for bit
    # the polarity of t0's trains: up0, up1, down0, down1, max
    first = ev.codec
    assert [first._p[k] for k in range(5)] == [0, 1, 2, 3, 4]


@pytest.mark.parametrize(
    "encoder",
    [
        IzhikevichEncoder(rate_hz=100.0, preset="RS", gain=15.0, normalize="minmax"),
        LIFEncoder(rate_hz=100.0, gain=3.0, normalize="minmax"),
    ],
)
def test_neuron_encoders_round_trip_within_half_a_microsecond(encoder):
    ds = _data(19, {"sensor": "biotac19"})
    ev = TactileEvents(ds, encoder=encoder)
    assert ev.sensor_size == (19, 1, 1)  # no grid: the electrode is x (SHD's layout)
    total = 0
    for i in range(len(ev)):
        events, _ = ev[i]
        trains = ev.spike_trains(i)
        back = ev.codec.to_spike_trains(events, t_end_s=trains.t_end)
        for a, b in zip(trains.times, back.times, strict=True):
            assert a.size == b.size
            assert np.all(np.abs(a - b) <= HALF_US)
        again = ev.codec.to_events(back)  # and events -> trains -> events is exact
        np.testing.assert_array_equal(again, events)
        total += len(events)
    assert total > 0


class _TwoNeurons:
    """A user's encoder: two trains per channel, named '<channel>:on' / '<channel>:off'."""

    def fit(self, X, y=None):
        self.fitted_ = True
        return self

    def transform(self, X):
        out = []
        for x in np.asarray(X):
            times, names = [], []
            for c in range(x.shape[1]):
                d = np.diff(x[:, c])
                times += [np.flatnonzero(d > 0.5) / 100.0, np.flatnonzero(d < -0.5) / 100.0]
                names += [f"c{c}:on", f"c{c}:off"]
            out.append(SpikeTrains(tuple(times), 0.0, len(x) / 100.0, tuple(names)))
        return out


def test_a_users_encoder_takes_its_names_to_polarity():
    ds = _data(2, {"sensor": "pvdf2"})
    ev = TactileEvents(ds, encoder=_TwoNeurons())
    assert ev.sensor_size == (2, 1, 2)
    events, _ = ev[0]
    trains = ev.spike_trains(0)
    # 'c1:off' is channel 1, second kind: x = 1, p = 1
    off = trains.times[3]
    sel = (events["x"] == 1) & (events["p"] == 1)
    np.testing.assert_array_equal(events["t"][sel], np.rint(off * 1e6).astype(np.int64))


def test_train_maps_follow_the_names_or_the_order():
    tm = train_map(["a:up", "a:dn", "b:up", "b:dn"], ["a", "b"])
    np.testing.assert_array_equal(tm.channel, [0, 0, 1, 1])
    np.testing.assert_array_equal(tm.kind, [0, 1, 0, 1])
    tm = train_map([f"x{i}" for i in range(4)], ["a", "b"], order="train")
    np.testing.assert_array_equal(tm.channel, [0, 1, 0, 1])
    with pytest.raises(ConfigError, match="5 spike trains for 2 input channels"):
        train_map([f"x{i}" for i in range(5)], ["a", "b"])
    with pytest.raises(ConfigError, match="order"):
        train_map([f"x{i}" for i in range(4)], ["a", "b"], order="diagonal")


def test_toframe_counts_equal_the_task_encoders_counts_channel_by_channel(tones):
    from sklearn.pipeline import Pipeline

    td = tasks.load(tones.task, quick=True, store=tones.store)
    ev = TactileEvents(td, split="test")  # the task's own encoding (threshold, K = 2)
    ctx = tones.spec.context(td.dataset, True)
    own = Pipeline(tones.spec.encoder(ctx)).fit(td.X).transform(td.X)
    _, test = next(td.splits())
    np.testing.assert_array_equal(ev.indices, test)
    window_us = int(td.X.shape[1] / td.rate_hz * 1e6)
    to_frame = tonic.transforms.ToFrame(
        sensor_size=ev.sensor_size, time_window=window_us, start_time=0, end_time=window_us
    )
    checked = 0
    for i, k in enumerate(test):
        events, target = ev[i]
        assert target == td.y[k]
        frames = to_frame(events)  # (frames, P, H, W)
        counts = frames.sum(axis=0)
        trains = own[k]
        lay, codec = ev.layout, ev.codec
        for m, name in enumerate(trains.channel_names):
            c, kind = codec.tmap.channel[m], codec.tmap.kind[m]
            got = counts[lay.layer[c] * codec.tmap.per_channel + kind, lay.y[c], lay.x[c]]
            assert got == trains.times[m].size, name
            checked += int(got)
    assert checked > 100  # the tones make spikes on every taxel


def test_a_dataloader_with_padtensors_batches_the_events(tones):
    torch = pytest.importorskip("torch")
    td = tasks.load(tones.task, quick=True, store=tones.store)
    frame = tonic.transforms.ToFrame(sensor_size=(3, 3, 5), time_window=10_000)
    ev = TactileEvents(td, split="train", transform=frame)
    loader = torch.utils.data.DataLoader(
        ev, batch_size=4, collate_fn=tonic.collation.PadTensors(batch_first=True)
    )
    x, y = next(iter(loader))
    assert x.shape[0] == 4 and tuple(x.shape[2:]) == (5, 3, 3)
    np.testing.assert_array_equal(y.numpy(), ev.targets()[:4])
    lengths = [ev[i][0].shape[0] for i in range(4)]
    assert x.shape[1] == max(lengths)  # padded to the longest


def test_a_store_of_raw_streams_without_an_encoder_is_refused(tmp_path):
    st = datasets.from_tactile(_data(9, {"grid_shape": [3, 3]}), tmp_path / "raw.zarr")
    with pytest.raises(ConfigError, match="holds raw sensor streams"):
        TactileEvents(st)
    with pytest.raises(ConfigError, match="no task split"):
        TactileEvents(st, encoder=ThresholdEncoder(rate_hz=100.0), split="train")
    # with an encoder the store reads lazily, slide by slide
    ev = TactileEvents(tmp_path / "raw.zarr", encoder=ThresholdEncoder(rate_hz=100.0))
    assert len(ev) == 4 and ev.sensor_size == (3, 3, 5)
    assert dataset_events({}, 7).sensor_size() == (7, 1, 1)


def test_codecs_refuse_foreign_trains_and_events():
    ds = _data(9, {"grid_shape": [3, 3]})
    ev = TactileEvents(ds, encoder=ThresholdEncoder(rate_hz=100.0))
    other = SpikeTrains.from_lists([[0.1]] * 9, 0.0, 1.0)
    with pytest.raises(ConfigError, match="not this codec's"):
        ev.codec.to_events(other)
    bad = np.zeros(1, EVENT_DTYPE)
    bad["x"] = 3
    with pytest.raises(ConfigError, match="outside the sensor"):
        ev.codec.to_spike_trains(bad, t_end_s=1.0)
    with pytest.raises(ConfigError, match="grid_shape"):
        codec_for(other, [f"c{i}" for i in range(9)], dataset_events({"grid_shape": [2, 2]}, 9))


def test_the_real_recordings_give_events(dataset_dir):
    bio = datasets.load_biotac(dataset_dir, slides=2, materials=2)
    ev = TactileEvents(bio, encoder=ThresholdEncoder(rate_hz=100.0))
    assert ev.sensor_size == (19, 1, 5)  # electrodes on x, the 2K + 1 trains on p
    events, target = ev[3]
    assert len(events) > 0 and target == 1
    icub = datasets.load_icub(dataset_dir)  # 6 patches x 10 taxels: its grid, as STMNIST's
    ev = TactileEvents(icub.subset(np.arange(4)), encoder=ThresholdEncoder(rate_hz=50.0))
    assert ev.sensor_size == (10, 6, 5) and ev.layout.grid


def test_a_missing_extra_names_its_install_command(monkeypatch):
    import sys

    from sim_tactile.errors import MissingDependencyError

    monkeypatch.setitem(sys.modules, "tonic", None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'sim-tactile\[tonic\]'"):
        TactileEvents(_data(9, {}), encoder=ThresholdEncoder(rate_hz=100.0))
