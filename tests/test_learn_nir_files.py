"""NIR files are read as data and written whole: a file that is no NIR graph, is cut short,
or holds a graph no simulator could run (NaN weights, a negative time constant) is refused
with its path named; a write that fails leaves no file behind and the file that was there
as it was. Needs the nir extra only (no torch)."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.errors import ConfigError

nir = pytest.importorskip("nir", reason="the nir extra is not installed")
from sim_tactile.learn import nir as bridge  # noqa: E402


def _graph(weight=None, tau_mem=0.02, v_reset=0.0):
    """input (3) -> Linear -> CubaLIF (2) -> output: a graph as snn_to_nir makes them."""
    w = np.arange(6, dtype=np.float32).reshape(2, 3) / 6 if weight is None else weight
    one = np.ones(2)
    nodes = {
        "input": nir.Input(input_type={"input": np.array([3])}),
        "fc": nir.Linear(weight=w),
        "lif": nir.CubaLIF(
            tau_syn=0.02 * one,
            tau_mem=tau_mem * one,
            r=one.copy(),
            v_leak=0.0 * one,
            v_threshold=1.0 * one,
            v_reset=v_reset * one,
            w_in=one.copy(),
        ),
        "output": nir.Output(output_type={"output": np.array([2])}),
    }
    edges = [("input", "fc"), ("fc", "lif"), ("lif", "output")]
    return nir.NIRGraph(nodes=nodes, edges=edges)


def test_a_graph_round_trips_and_leaves_nothing_beside_it(tmp_path):
    path = bridge.write_nir(_graph(), tmp_path / "g.nir")
    back = bridge.read_nir(path)
    np.testing.assert_array_equal(back.nodes["fc"].weight, _graph().nodes["fc"].weight)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.nir"]


@pytest.mark.parametrize(
    "content",
    [b"this is not a NIR file\n", b"\x89HDF\r\n\x1a\n" + b"\0" * 40, b""],
    ids=["text", "hdf5-signature-only", "empty"],
)
def test_a_file_that_is_no_nir_graph_is_refused_by_its_path(tmp_path, content):
    path = tmp_path / "garbage.nir"
    path.write_bytes(content)
    with pytest.raises(ConfigError, match=r"NIR file '.*garbage\.nir' cannot be read") as e:
        bridge.read_nir(path)
    assert "\n" not in str(e.value)


def test_a_truncated_file_is_refused_by_its_path(tmp_path):
    path = bridge.write_nir(_graph(), tmp_path / "cut.nir")
    data = path.read_bytes()
    for keep in (len(data) // 2, 800):
        path.write_bytes(data[:keep])
        with pytest.raises(ConfigError, match=r"NIR file '.*cut\.nir' cannot be read"):
            bridge.read_nir(path)


def test_an_hdf5_file_without_a_graph_is_refused_by_its_path(tmp_path):
    import h5py

    path = tmp_path / "other.nir"
    with h5py.File(path, "w") as f:
        f.create_dataset("x", data=np.arange(3))
    with pytest.raises(ConfigError, match=r"other\.nir' cannot be read as a NIR graph"):
        bridge.read_nir(path)


@pytest.mark.parametrize(
    "graph, message",
    [
        (
            _graph(weight=np.array([[np.nan, 0, 0], [0, 1, 0]], np.float32)),
            r"node 'fc': weight has 1 values that are NaN or infinite; valid: finite",
        ),
        (
            _graph(weight=np.array([[np.inf, 0, 0], [0, 1, 0]], np.float32)),
            r"node 'fc': weight has 1 values that are NaN or infinite",
        ),
        (_graph(tau_mem=-0.01), r"node 'lif': tau_mem = -0.01 s; valid: > 0 s"),
        (_graph(tau_mem=0.0), r"node 'lif': tau_mem = 0 s; valid: > 0 s"),
        (_graph(v_reset=2.0), r"node 'lif': v_threshold is not above v_reset"),
    ],
    ids=["nan-weight", "inf-weight", "negative-tau", "zero-tau", "reset-above-threshold"],
)
def test_a_graph_no_simulator_could_run_is_refused_on_read_and_on_write(tmp_path, graph, message):
    path = tmp_path / "bad.nir"
    nir.write(str(path), graph)  # written by another tool, which did not check
    with pytest.raises(ConfigError, match=r"NIR file '.*bad\.nir': " + message):
        bridge.read_nir(path)
    with pytest.raises(ConfigError, match=message):
        bridge.write_nir(graph, tmp_path / "new.nir")
    assert not (tmp_path / "new.nir").exists()


def test_an_edge_to_no_node_is_refused(tmp_path):
    g = _graph()
    g.edges.append(("lif", "nowhere"))
    with pytest.raises(ConfigError, match=r"edge \('lif', 'nowhere'\) joins no two of its nodes"):
        bridge.write_nir(g, tmp_path / "g.nir")


def _failing_write(filename, graph, **kw):
    """nir.write that dies half way (a full disk, a kill): some bytes, then an error."""
    with open(filename, "wb") as fh:
        fh.write(b"\x89HDF\r\n\x1a\n partial")
    raise OSError(28, "No space left on device")


def test_a_failed_write_leaves_no_file_and_keeps_the_one_there(tmp_path, monkeypatch):
    old = bridge.write_nir(_graph(), tmp_path / "kept.nir")
    before = old.read_bytes()
    monkeypatch.setattr(nir, "write", _failing_write)
    with pytest.raises(OSError, match="No space left"):
        bridge.write_nir(_graph(weight=np.ones((2, 3), np.float32)), old)
    assert old.read_bytes() == before  # not clobbered
    with pytest.raises(OSError, match="No space left"):
        bridge.write_nir(_graph(), tmp_path / "new.nir")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.nir"]  # no file, no temporary
    monkeypatch.undo()
    np.testing.assert_array_equal(
        bridge.read_nir(old).nodes["fc"].weight, _graph().nodes["fc"].weight
    )


def test_a_folder_at_the_path_is_refused(tmp_path):
    (tmp_path / "d.nir").mkdir()
    with pytest.raises(ConfigError, match=r"d\.nir' is a folder"):
        bridge.write_nir(_graph(), tmp_path / "d.nir")
    with pytest.raises(ConfigError, match=r"d\.nir' is a folder"):
        bridge.read_nir(tmp_path / "d.nir")
