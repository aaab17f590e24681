"""NeuroBench's figures: computed by hand for the SRM network (which NeuroBench cannot hook),
equal to neurobench's own Benchmark on an snnTorch model it accepts; the encoders' spikes per
second of input; and both in the report of a task with an SNN row."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _fake_task import tones_fixture

from sim_tactile.errors import ConfigError
from sim_tactile.learn.neurobench import encoder_rate, layer_metrics, neuromorphic_figures
from sim_tactile.records import SpikeTrains

torch = pytest.importorskip("torch", reason="the learn extra (torch) is not installed")


@pytest.fixture(scope="module")
def tones(tmp_path_factory, cache_dir):
    """The tones task and its quick store (tests/_fake_task.py)."""
    yield from tones_fixture(tmp_path_factory, cache_dir)


def _snntorch_net(w1, w2):
    snn = pytest.importorskip("snntorch", reason="the neurobench extra is not installed")
    nn = torch.nn

    class Net(nn.Module):
        def __init__(self):
            super().__init__()
            self.fc1 = nn.Linear(w1.shape[1], w1.shape[0], bias=False)
            self.lif1 = snn.Leaky(beta=0.8, threshold=1.0, init_hidden=True)
            self.fc2 = nn.Linear(w2.shape[1], w2.shape[0], bias=False)
            self.lif2 = snn.Leaky(beta=0.8, threshold=1.0, init_hidden=True, output=True)
            with torch.no_grad():
                self.fc1.weight.copy_(torch.from_numpy(w1))
                self.fc2.weight.copy_(torch.from_numpy(w2))

        def forward(self, x):
            return self.lif2(self.fc2(self.lif1(self.fc1(x))))

    return Net()


@pytest.mark.slow  # importing neurobench (snnTorch, Tonic) takes about 6 s
def test_the_hand_made_figures_equal_neurobenchs_on_an_snntorch_model():
    nb = pytest.importorskip("neurobench", reason="neurobench is not installed")
    from neurobench.benchmarks import Benchmark
    from neurobench.metrics.static import ConnectionSparsity, Footprint, ParameterCount
    from neurobench.metrics.workload import ActivationSparsity, SynapticOperations
    from neurobench.models import SNNTorchModel

    rng = np.random.default_rng(3)
    w1 = rng.normal(0, 1.5, (12, 20)).astype(np.float32)
    w1[rng.random(w1.shape) < 0.3] = 0.0  # some connections cut
    w2 = rng.normal(0, 1.5, (4, 12)).astype(np.float32)
    x = (rng.random((10, 30, 20)) < 0.2).astype(np.float32)
    y = rng.integers(0, 4, 10)
    net = _snntorch_net(w1, w2)
    buffers = sum(b.numel() * b.element_size() for b in net.buffers())  # before any state
    loader = torch.utils.data.DataLoader(
        torch.utils.data.TensorDataset(torch.from_numpy(x), torch.from_numpy(y)), batch_size=4
    )
    bench = Benchmark(
        SNNTorchModel(net),
        loader,
        [],
        [],
        [[Footprint, ParameterCount, ConnectionSparsity], [ActivationSparsity, SynapticOperations]],
    )
    theirs = bench.run(quiet=True)
    assert nb is not None
    # the same network by hand: its layers' inputs and spikes, step by step
    import snntorch.utils

    snntorch.utils.reset(net)
    hidden, out = [], []
    with torch.no_grad():
        xt = torch.from_numpy(x)
        for n in range(x.shape[1]):
            h = net.lif1(net.fc1(xt[:, n]))
            o, _ = net.lif2(net.fc2(h))
            hidden.append(h.numpy())
            out.append(o.numpy())
    hidden, out = np.stack(hidden, 1), np.stack(out, 1)
    ours = layer_metrics([w1, w2], [x, hidden], [hidden, out], buffer_bytes=buffers)
    assert ours["footprint_bytes"] == theirs["Footprint"]
    assert ours["parameter_count"] == theirs["ParameterCount"]
    assert ours["connection_sparsity"] == pytest.approx(theirs["ConnectionSparsity"], abs=5e-5)
    assert ours["activation_sparsity"] == pytest.approx(theirs["ActivationSparsity"], rel=1e-12)
    ops = theirs["SynapticOperations"]
    assert ours["synaptic_operations"]["effective_acs"] == pytest.approx(ops["Effective_ACs"])
    assert ours["synaptic_operations"]["effective_macs"] == ops["Effective_MACs"] == 0
    assert ours["synaptic_operations"]["dense"] == pytest.approx(ops["Dense"])
    assert 0 < ours["synaptic_operations"]["effective_acs"] < ours["synaptic_operations"]["dense"]


def test_non_spiking_inputs_count_as_macs():
    w = np.array([[1.0, 0.0], [2.0, 3.0]], np.float32)
    x = np.array([[[0.5, 0.0], [0.0, 1.0]]], np.float32)  # one sample, two steps
    m = layer_metrics([w], [x], [np.zeros((1, 2, 2))])
    # step 0: input 0 fans out to 2 weights; step 1: input 1 to 1 weight
    assert m["synaptic_operations"] == {"effective_acs": 0.0, "effective_macs": 3.0, "dense": 8.0}
    assert m["connection_sparsity"] == 0.25 and m["activation_sparsity"] == 1.0
    with pytest.raises(ConfigError, match="weight matrices"):
        layer_metrics([w, w], [x], [])


def test_encoder_rate_counts_spikes_per_second_of_input():
    a = SpikeTrains.from_lists([[0.1, 0.2], [0.3]], 0.0, 0.5)
    b = SpikeTrains.from_lists([[], [0.1, 0.2, 0.4]], 0.0, 0.5)
    r = encoder_rate([a, b])
    assert r["spikes_per_s"] == 6 / 1.0 and r["spikes_per_s_per_channel"] == 3.0


@pytest.mark.slow  # a whole run with its figures: about 10 s
def test_the_report_of_a_task_with_an_snn_row_carries_the_figures(tones, tmp_path):
    from sim_tactile import tasks

    rep = tasks.run_task(tones.task, tmp_path, quick=True, store=tones.store, log=lambda m: None)
    rows = {r["classifier"]: r for r in rep["results"]}
    snn = rows["snn"]["neuromorphic"]
    assert set(snn) >= {
        "encoder",
        "footprint_bytes",
        "parameter_count",
        "connection_sparsity",
        "activation_sparsity",
        "synaptic_operations",
        "spikes_per_sample",
    }
    # 45 encoded inputs -> 16 hidden -> 3 classes, 50 steps; the alpha kernel is a buffer
    assert snn["parameter_count"] == 45 * 16 + 16 * 3
    assert snn["synaptic_operations"]["dense"] == 50 * (45 * 16 + 16 * 3)
    assert snn["footprint_bytes"] > 4 * snn["parameter_count"]
    assert 0 < snn["activation_sparsity"] < 1 and snn["synaptic_operations"]["effective_macs"] == 0
    # the threshold encoding's spikes per second of input: the same for both spike rows
    assert rows["svm-spike"]["neuromorphic"]["encoder"] == snn["encoder"]
    assert snn["encoder"]["spikes_per_s"] > 0 and "neuromorphic" not in rows["svm-raw"]
    assert json.loads((tmp_path / "report.json").read_text())["results"][0]["neuromorphic"]
    md = (tmp_path / "report.md").read_text()
    assert "## Neuromorphic figures" in md and "| snn |" in md


def test_a_model_without_spikes_has_no_figures():
    from sklearn.dummy import DummyClassifier

    est = DummyClassifier().fit(np.zeros((2, 3)), [0, 1])
    assert neuromorphic_figures(est, np.zeros((2, 4, 3))) is None
