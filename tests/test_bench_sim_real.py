"""The sim-to-real statistics, on streams whose answers are known, and the command on the
real data set (skipped without it)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import _find_dataset as find_dataset

from sim_tactile.bench.sim_real import separability, slide_stats
from sim_tactile.cli import main

#: The real data set (conftest: $SIM_TACTILE_DATASETS, ../shared, /work/shared).
DATA = find_dataset()


def test_the_statistics_of_known_streams():
    rng = np.random.default_rng(0)
    n, T, C = 20, 2000, 4
    white = 2.0 * rng.standard_normal((n, T, C))
    s = slide_stats(white + 5.0, 100.0)
    np.testing.assert_allclose(np.median(s["mean"]), 5.0, atol=0.05)
    np.testing.assert_allclose(np.median(s["noise"]), 2.0, rtol=0.03)
    np.testing.assert_allclose(np.median(s["temporal_std"]), 2.0, rtol=0.03)
    assert abs(np.median(s["spectral_slope"])) < 0.15  # white: flat
    assert abs(np.median(s["channel_correlation"])) < 0.05
    brown = np.cumsum(rng.standard_normal((n, T, C)), axis=1)
    assert np.median(slide_stats(brown, 100.0)["spectral_slope"]) == pytest.approx(-2.0, abs=0.3)
    common = np.repeat(rng.standard_normal((n, T, 1)), C, axis=2)
    assert np.median(slide_stats(common, 100.0)["channel_correlation"]) == pytest.approx(1.0)
    assert slide_stats(white, 100.0)["max"].min() > 6.0


def test_separability_grows_with_the_distance_between_classes():
    rng = np.random.default_rng(1)
    y = np.repeat(np.arange(3), 30)
    base = rng.standard_normal((90, 10, 5))
    near = separability(base + 0.1 * y[:, None, None], y)
    far = separability(base + 3.0 * y[:, None, None], y)
    assert far > 10 * near > 0


@pytest.mark.slow
@pytest.mark.skipif(not DATA.is_dir(), reason=f"the real data set is not at {DATA}")
def test_sim_real_on_the_biotac_data(tmp_path, capsys):
    assert (
        main(
            [
                "bench",
                "sim-real",
                "--data",
                str(DATA),
                "--sensors",
                "biotac19",
                "--slides",
                "2",
                "--out",
                str(tmp_path),
                "--json",
            ]
        )
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    s = doc["sensors"]["biotac19"]
    assert s["n_real"] == 40 and s["n_simulated"] == 40
    for col in ("real", "simulated"):
        assert s["columns"][col]["noise"]["median"] > 0
    # the uncalibrated preset's peaks sit far below the real ones (the 10x)
    assert s["columns"]["simulated"]["max"]["median"] < 0.5 * s["columns"]["real"]["max"]["median"]
    assert (tmp_path / "sim_real.png").read_bytes()[:4] == b"\x89PNG"
