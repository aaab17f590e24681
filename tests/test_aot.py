"""Kernels compiled ahead of time (sim_tactile/_aot.py, sim_tactile/_jit.py).

An extension serves a call only where numba would have compiled the same signature for it:
its argument check is held to numba's own ``typeof`` on arrays of every layout, flag and
dtype, scalars and tuples. Then, in a kernel folder of the test's own, one module is built
ahead of time and called from fresh processes: the same values as numba's, bit for bit,
without importing numba; a JIT kernel that calls it from compiled code (numba then
imported) gives the same values too; a call whose arguments match no signature goes to numba
and gets numba's answer; a damaged extension is passed over with a warning.
"""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
import warnings

import numpy as np
import pytest
from numba import typeof
from numba.core.errors import NumbaError

from sim_tactile import _aot
from sim_tactile._jit import kernel_stamp
from sim_tactile.sim.collide.height import SurfaceProbe


def _samples() -> list:
    ro = np.zeros(4)
    ro.flags.writeable = False
    unaligned = np.frombuffer(np.zeros(17, np.uint8).tobytes()[1:9], dtype=np.float64)
    return [
        np.zeros(5),
        np.zeros((3, 4)),
        np.zeros((3, 4))[:, ::2],
        np.asfortranarray(np.zeros((3, 4))),
        np.zeros((1, 5)),
        np.zeros((2, 2))[0],
        np.zeros(0),
        np.zeros(5, np.int64),
        np.zeros(5, bool),
        np.zeros(5, np.float32),
        np.zeros(5, np.int32),
        ro,
        unaligned,
        1.5,
        3,
        True,
        np.float64(2.0),
        np.int64(4),
        np.bool_(True),
        np.float32(1.0),
        -(2**63),
        (np.zeros(3), 1.0),
        (1.0, 2.0),
        (1.0, 2),
        (np.zeros(2), np.zeros(2)),
        ((np.zeros(2), 3), True),
        SurfaceProbe(
            np.zeros((2, 3)), np.zeros(2), np.zeros(2), (1.0, np.zeros(3)), np.zeros(2, np.int64)
        ),
        SurfaceProbe(np.zeros((2, 3)), np.zeros(2), np.zeros(2), (1.0, 2.0), np.zeros(2, np.int64)),
        pickle.loads(pickle.dumps(np.zeros(3))),  # a dtype equal to float64's, not its object
        np.zeros(3, ">f8"),
    ]


def test_the_argument_check_is_numbas_typeof():
    """For every pair of samples: a signature built from one's numba type matches the other
    exactly where numba types the two alike."""
    samples = _samples()
    served = 0
    for x in samples:
        try:
            tx = typeof(x)
        except NumbaError:  # numba types no big-endian array: never compiled
            continue
        spec = _aot.spec_of(tx)
        if spec is None:  # a type no extension serves (a float32 scalar): numba's
            continue
        served += 1
        ok = _aot.matcher([spec, ["f"]])
        for y in samples:
            try:
                ty = typeof(y)
            except NumbaError:
                ty = None
            assert ok((y, 0.5)) == (ty == tx), (tx, ty)
        assert not ok((x,)) and not ok((x, 0.5, 0.5)) and not ok((x, 1))
    assert served == len(samples) - 2  # all but the float32 scalar and the big-endian array
    assert not _aot.matcher([["i"]])((2**63,))  # beyond int64: numba refuses it


def test_a_call_no_signature_serves_says_once_that_numba_serves_it():
    """A kernel built ahead of time, called with types it was not built for, goes to numba
    (whose start-up a command then pays) and warns once that a build would serve it; a kernel
    with no extension of its own says nothing."""
    from sim_tactile.errors import CacheWarning

    def f(x):
        return x

    made = []
    k = _aot.Kernel(f, lambda: made.append(1) or (lambda x: x + 1), [(lambda a: False, None)])
    with pytest.warns(CacheWarning, match=r"kernels build"):
        assert k(1) == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert k(2) == 3 and made == [1]  # once
        plain = _aot.Kernel(f, lambda: lambda x: x * 10, ())
        assert plain(3) == 30


def test_a_signatures_check_is_written_out_at_its_first_call(monkeypatch):
    """A loaded signature's check is written out when a call first asks it (a process calls
    few of the kernels it loads), then kept; it answers as :func:`~sim_tactile._aot.matcher`
    does, and a spec it does not know is refused at that call."""
    made = []
    real = _aot.matcher
    monkeypatch.setattr(_aot, "matcher", lambda specs: made.append(specs) or real(specs))
    specs = [["a", np.dtype(np.float64).str, 1, "C", True, True], ["f"]]
    lazy = _aot.LazyMatcher(specs)
    assert made == []
    x = np.zeros(3)
    assert lazy((x, 1.0)) and not lazy((x, 1)) and not lazy((x[::2], 1.0))
    assert made == [specs]  # written once
    bad = _aot.LazyMatcher([["x"]])
    with pytest.raises(ValueError, match="unknown argument spec"):
        bad((1.0,))


def test_a_spec_it_does_not_know_is_refused():
    with pytest.raises(ValueError, match="unknown argument spec"):
        _aot.matcher([["x"]])
    with pytest.raises(ValueError, match="not a class of the package"):
        _aot.matcher([["n", "collections:OrderedDict", []]])
    with pytest.raises(ValueError, match="unknown layout"):
        _aot.matcher([["a", "<f8", 1, "K", True, True]])


MODULE = "sim_tactile.sim.skin.clipped"
_CHILD = r"""
import json, sys, warnings
import numpy as np
warnings.simplefilter("always")
from sim_tactile.sim.skin import clipped
args = (1.0e-3, 2.0e-3, 0.5e-3, 0.7e-3)
out = {"kind": type(clipped.rect_entry).__name__, "value": clipped.rect_entry(*args).hex()}
out["numba_after_call"] = "numba" in sys.modules
from sim_tactile.sim.skin import anchored
cxb, wxb = np.linspace(0, 1e-3, 5), np.full(5, 2e-4)
cy, wy = np.linspace(-2e-3, 2e-3, 7), np.full(7, 6e-4)
C = anchored.lattice_compliance(cxb, wxb, 1.4e-3, 2, cy, wy, 1e5)
out["compliance"] = [float(v).hex() for v in C.ravel()[::7]]
out["int_args"] = clipped.rect_entry(1, 2, 1, 1).hex()  # ints: not the compiled signature
print(json.dumps(out))
"""


def _child(env: dict) -> dict:
    r = subprocess.run(
        [sys.executable, "-c", _CHILD], env=env, capture_output=True, text=True, check=False
    )
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1]), r.stderr


def _build(env: dict, *modules: str) -> str:
    r = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; from sim_tactile.cli import main; sys.exit(main())",
            "kernels",
            "build",
            "--json",
            "--modules",
            ",".join(modules),
        ],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout)


@pytest.mark.slow
def test_an_extension_serves_its_kernels_bit_for_bit_without_numba(tmp_path):
    env = {**os.environ, "SIM_TACTILE_KERNELS": str(tmp_path / "kernels"), "SIM_TACTILE_AOT": "0"}
    jit, _ = _child(env)  # numba compiles (or loads) every kernel into the test's folder
    assert jit["kind"] == "CPUDispatcher" and jit["numba_after_call"]

    env["SIM_TACTILE_AOT"] = "1"
    doc = _build(env, MODULE)
    (mod,) = doc["modules"]
    assert mod["module"] == MODULE and mod["built"] >= 2 and "rect_entry" in mod["kernels"]
    where = tmp_path / "kernels" / MODULE / kernel_stamp(MODULE) / f"aot-{_aot.cpu_key()}"
    index = json.loads((where / _aot.INDEX).read_text())
    assert index["stamp"] == kernel_stamp(MODULE) and (where / index["file"]).is_file()

    aot, err = _child(env)
    assert aot["kind"] == "Kernel"
    assert "was not compiled ahead of time" not in err  # every call served, or not built
    assert aot["numba_after_call"] is False  # served ahead of time: numba never loaded
    assert aot["value"] == jit["value"]  # bit for bit
    # anchored's kernel is numba's (not built), calling the extension's module's kernel
    assert aot["compliance"] == jit["compliance"]
    assert aot["int_args"] == jit["int_args"]  # no signature of ints: numba's answer

    # a damaged extension: passed over, with a warning, and numba serves the same numbers
    so = where / index["file"]
    so.write_bytes(so.read_bytes()[: so.stat().st_size // 2])
    damaged, stderr = _child(env)
    assert damaged["numba_after_call"] and damaged["value"] == jit["value"]
    assert "do not match their digest" in stderr


@pytest.mark.slow
def test_an_array_of_another_layout_or_dtype_goes_to_numba(tmp_path):
    """The extension's entry points check nothing: a strided array read as contiguous gives
    wrong numbers, a float32 one crashes. The check sends both to numba."""
    module = "sim_tactile.sim.skin.anchored"
    env = {**os.environ, "SIM_TACTILE_KERNELS": str(tmp_path / "kernels"), "SIM_TACTILE_AOT": "0"}
    child = r"""
import json, sys
import numpy as np
from sim_tactile.sim.skin import anchored
f = np.arange(40.0).reshape(8, 5)
cxr, wxr = np.linspace(-1e-3, 1e-3, 8), np.full(8, 3e-4)
tx, th = np.array([-5e-4, 5e-4]), np.array([5e-4, 5e-4])
oy = np.linspace(0.1, 1.0, 10).reshape(2, 5)
def read(f, oy):
    out = np.zeros(2)
    anchored.read_surface(0.0, cxr, wxr, 5, tx, th, oy, f, out)
    return [v.hex() for v in out]
import warnings
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    res = {"contig": read(f.ravel(), oy)}
    if sys.argv[1] == "all":
        res["strided"] = read((np.arange(80.0) / 2)[::2], oy)
        res["fortran"] = read(f.ravel(), np.asfortranarray(oy))
        res["f32"] = read(f.ravel().astype(np.float32), oy)
res["said"] = sum("was not compiled ahead of time" in str(w.message) for w in caught)
res["kind"] = type(anchored.read_surface).__name__
res["numba"] = "numba" in sys.modules
print(json.dumps(res))
"""

    def run(calls: str) -> dict:
        r = subprocess.run(
            [sys.executable, "-c", child, calls],
            env=env,
            capture_output=True,
            text=True,
            check=False,
        )
        assert r.returncode == 0, r.stderr[-3000:]
        return json.loads(r.stdout.strip().splitlines()[-1])

    plain = run("plain")  # numba compiles the contiguous float64 signature only
    env["SIM_TACTILE_AOT"] = "1"
    (mod,) = _build(env, module)["modules"]
    assert mod["built"] >= 1
    served = run("plain")
    assert served["kind"] == "Kernel" and not served["numba"] and served["said"] == 0
    assert served["contig"] == plain["contig"]
    aot = run("all")
    assert aot["numba"]  # the calls no signature serves loaded numba
    assert aot["said"] == 1  # and said so, once for the kernel
    env["SIM_TACTILE_AOT"] = "0"
    jit = run("all")
    for k in ("contig", "strided", "fortran", "f32"):
        assert aot[k] == jit[k], k
    assert jit["strided"] == jit["contig"] == jit["fortran"]  # whatever the layout


def test_a_module_pycc_cannot_compile_is_said_and_left_to_numba(tmp_path, monkeypatch):
    """A C compiler missing or failing fails the module's build, not the command: it says
    why, keeps nothing, and numba serves the module as before."""
    import numba.pycc
    from _kernels import compile_into

    from sim_tactile import _aot_build

    compile_into(tmp_path)  # numba caches clipped's kernels in the test's folder
    monkeypatch.setenv("SIM_TACTILE_KERNELS", str(tmp_path))

    class Failing(numba.pycc.CC):
        def compile(self):
            raise OSError("gcc: command not found")

    monkeypatch.setattr(numba.pycc, "CC", Failing)
    (done,) = _aot_build.build_ahead([MODULE])
    assert done["built"] == 0 and "gcc: command not found" in done["why"]
    stamp = tmp_path / MODULE / kernel_stamp(MODULE)
    assert not _aot.folder(stamp, _aot.cpu_key()).exists()
    assert [p.name for p in stamp.iterdir() if p.name.startswith(".aot")] == []
