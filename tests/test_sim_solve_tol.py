"""The spectral contact solve's tolerance (StepOptions.solve_tol): a looser one takes fewer
iterations and stays within its bound of the reference solve, it enters the slide's key and
meta only where it is set, and a bad one is refused with its range."""

from __future__ import annotations

import numpy as np
import pytest

from sim_tactile.errors import ConfigError
from sim_tactile.sim import StepOptions, simulate
from sim_tactile.sim.skin.contact import spectral
from sim_tactile.slides.config import config_slide_set
from sim_tactile.tasks import get_task

#: The taxel loads' relative L2 against the reference solve that a tolerance of 1e-4 stays
#: under (measured: 2e-6 on this slide, 5e-6 on an iCub slide; perf/bench_response.py)
REL_L2_AT_1E4 = 1e-4
#: The share of the reference's FFT products that a tolerance of 1e-4 stays under on this
#: slide (measured: 0.80 with its single-precision products, 0.78 with double ones).
PRODUCTS_AT_1E4 = 0.85


def _slide(tol, cache):
    kw = dict(ideal=True, pitch_m=0.8e-3, cache=cache, seed=1)
    # the per-step path: the knobs as given (auto would loosen a spectral skin's by itself)
    opts = StepOptions(skin_solver="spectral", solve_tol=tol, path="per-step")
    return simulate("finger7/bumps-3x3", "grid3x3", options=opts, **kw)


def test_a_looser_tolerance_takes_fewer_iterations_within_its_bound(cache, monkeypatch):
    applies = {"n": 0}
    real = spectral.Spectral.apply

    def counted(self, p):
        applies["n"] += 1
        return real(self, p)

    monkeypatch.setattr(spectral.Spectral, "apply", counted)
    ref = _slide(None, cache)
    n_ref, applies["n"] = applies["n"], 0
    loose = _slide(1e-4, cache)
    n_loose = applies["n"]
    assert "solve_tol" not in ref.recording.meta
    assert loose.recording.meta["solve_tol"] == 1e-4
    assert "to 0.0001" in loose.recording.meta["skin_problem"]
    a, b = loose.recording.data.astype(float), ref.recording.data.astype(float)
    assert b.max() > 0 and not np.array_equal(a, b)
    assert np.linalg.norm(a - b) / np.linalg.norm(b) < REL_L2_AT_1E4
    assert n_loose < PRODUCTS_AT_1E4 * n_ref, (n_loose, n_ref)


def test_the_tolerance_enters_a_slides_key_only_where_it_is_set():
    ss = get_task("finger7-v1").get_data
    job = ss.jobs(seed=0, quick=True)[0]
    from dataclasses import replace

    assert "solve_tol" not in job.describe()
    loose = replace(job, options=StepOptions(solve_tol=1e-4))
    assert loose.describe()["solve_tol"] == 1e-4
    assert loose.key() != job.key()
    loose_set = replace(ss, options=StepOptions(solve_tol=1e-4))
    assert loose_set.jobs(seed=0, quick=True)[0].key() == loose.key()
    assert loose_set.describe()["solve_tol"] == 1e-4
    # the keyword of one release ago builds the same slide
    assert replace(job, solve_tol=1e-4) == loose


@pytest.mark.parametrize("bad", [0.0, -1e-6, 1e-2, float("nan"), "tight"])
def test_a_bad_tolerance_names_its_range(bad):
    with pytest.raises(ConfigError, match=r"solve_tol.*valid: \[1e-12, 0.001\]"):
        StepOptions(solve_tol=bad)


def test_a_tolerance_is_kept_as_the_float_it_reads_as():
    assert StepOptions(solve_tol="1e-4").solve_tol == 1e-4
    ss = get_task("finger7-v1").get_data
    from dataclasses import replace

    assert type(replace(ss, options=StepOptions(solve_tol="1e-5")).options.solve_tol) is float


def test_a_configuration_file_takes_the_tolerance_and_refuses_a_bad_one():
    cfg = {
        "plates": ["finger7/flat", "finger7/ridges-4"],
        "sensor": "grid3x3",
        "slides_per_plate": 2,
        "solve_tol": 1e-5,
    }
    ss, _, _ = config_slide_set(cfg)
    assert ss.options.solve_tol == 1e-5
    assert all(j.options.solve_tol == 1e-5 for j in ss.jobs(seed=0))
    with pytest.raises(ConfigError, match=r"solve_tol = 0.1 is out of range"):
        config_slide_set({**cfg, "solve_tol": 0.1})
