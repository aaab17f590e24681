"""Recordings of a fixed set of slides, bit for bit as the code at 7f597a3 made them.

``tests/data/golden_slides.npz`` holds, for one short slide of every task's sensor and plate
kind (each collider, skin reduction, fidelity level and force control), the recorded data,
the per-sample normal force and the pad's path. A refactor that keeps the arithmetic must
reproduce them exactly; a change that alters them on purpose regenerates the file with
``python tools/golden_slides.py`` (which defines the cases) and says why in its commit.
Bit for bit on the BLAS kernel the file was written with; on another CPU's kernel, to the
script's ``OTHER_KERNEL_RTOL`` (see its docstring for the measured difference).
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).parent
GOLDEN = HERE / "data" / "golden_slides.npz"
with np.load(GOLDEN, allow_pickle=False) as _z:
    CASES = json.loads(str(_z["cases_json"]))
    BLAS_CORE = str(_z["blas_core"])


def _script():
    """The regenerating script, the one definition of how a case becomes a slide."""
    path = HERE.parent / "tools" / "golden_slides.py"
    spec = importlib.util.spec_from_file_location("golden_slides", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("case", CASES, ids=[c["name"] for c in CASES])
def test_recordings_are_bit_identical_to_the_saved_ones(case, cache):
    job = _script().case_job(case)
    assert job.seed == case["seed"]  # the task's own seeding is part of what must not change
    rec = job.simulate(cache).recording
    with np.load(GOLDEN, allow_pickle=False) as z:
        want = {k: z[f"{case['name']}/{k}"] for k in ("data", "normal_force_n", "x_pad_m")}
    got = {
        "data": np.asarray(rec.data),
        "normal_force_n": np.asarray(rec.meta["normal_force_n"]),
        "x_pad_m": np.asarray(_script()._path(rec.meta)),
    }
    assert rec.meta["skin_problem"] == case["skin_problem"]
    script = _script()
    assert script.differences(got, {**want, "blas_core": BLAS_CORE}, script.blas_core()) == []


def test_the_comparison_is_bit_for_bit_on_the_files_kernel_only():
    """One rounding apart fails on the file's kernel and passes on another; a real change
    fails on both."""
    script = _script()
    want = {"f": np.array([1.0, 2.0]), "blas_core": "K"}
    ulp = {"f": np.nextafter(want["f"], 3.0)}
    moved = {"f": want["f"] * (1 + 1e-6)}
    assert script.differences(ulp, want, "K") and not script.differences(ulp, want, "other")
    assert script.differences(moved, want, "K") and script.differences(moved, want, "other")
