"""A data set travels: a folder of configuration, plate files and store, copied to another
place (a colleague's machine, a CI checkout), runs and resumes there. Its identity is its
content, never the paths of its files."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from sim_tactile import datasets
from sim_tactile.generate import generate
from sim_tactile.records import Recording
from sim_tactile.slides import SlideOutcome

SET = """
name = "mine"
seed = 3
plates = ["finger7/flat", "ridges.toml", {file = "waves.npy", pixel_m = 5e-5, name = "waves"}]
sensor = "grid3x3"
slides_per_plate = 4

[protocol]
duration_s = 0.2
"""


def _fake_slide(job):
    """A slide with the job's shape and a value of its own (no physics): the store's layout."""
    taxels = job.sensor.layout.positions
    x = np.full((job.n_samples(), len(taxels)), job.seed % 97, np.float32)
    x += np.linspace(0, 1, len(taxels), dtype=np.float32)[None, :] * (job.seed % 5)
    return SlideOutcome(Recording(x, np.arange(len(x)) / 100.0, taxels), (), 0.0, False)


class _StopAfter:
    """The fake slide, then Ctrl-C after ``n`` slides (an interrupted run)."""

    def __init__(self, n: int) -> None:
        self.n = n

    def __call__(self, job):
        self.n -= 1
        if self.n < 0:
            raise KeyboardInterrupt
        return _fake_slide(job)


def _folder(root, assets) -> None:
    root.mkdir()
    (root / "set.toml").write_text(SET)
    text = (assets / "plates" / "finger7" / "ridges-2.toml").read_text()
    (root / "ridges.toml").write_text(text.replace('name = "finger7/ridges-2"', 'name = "ridges"'))
    x = np.arange(401) * 5e-5
    z = 2e-4 * (1 + np.sin(2 * np.pi * x / 3e-3))[None, :] * np.ones((401, 1))
    np.save(root / "waves.npy", z)


def _gen(root, **kw):
    return generate(
        str(root / "set.toml"), root / "s.zarr", progress=False, log=lambda m: None, **kw
    )


@pytest.fixture
def assets():
    from pathlib import Path

    import sim_tactile.assets

    return Path(sim_tactile.assets.__path__[0])


@pytest.mark.slow
def test_a_copied_folder_resumes_and_runs_from_its_new_place(tmp_path, assets, cli, monkeypatch):
    monkeypatch.setenv("SIM_TACTILE_CACHE", str(tmp_path / "cache"))
    here = tmp_path / "here"
    _folder(here, assets)
    with pytest.raises(KeyboardInterrupt):
        _gen(here, workers=1, _worker=_StopAfter(5))
    there = tmp_path / "elsewhere" / "copy"
    shutil.copytree(here, there)
    shutil.rmtree(here)  # nothing of the old place is left to find
    res = _gen(there, workers=1, resume=True, _worker=_fake_slide)
    assert res["reused"] == 5 and res["written"] == 7
    # the same data as a folder that was never moved
    ref = tmp_path / "ref"
    _folder(ref, assets)
    _gen(ref, workers=1, _worker=_fake_slide)
    a, b = datasets.open(there / "s.zarr"), datasets.open(ref / "s.zarr")
    assert a.config_hash == b.config_hash
    np.testing.assert_array_equal(a.to_tactile().data, b.to_tactile().data)
    # and it is scored from its new place
    out = cli(
        [
            "run",
            there / "set.toml",
            "--store",
            there / "s.zarr",
            "--out",
            tmp_path / "run",
            "--classifiers",
            "svm-raw",
            "--repeats",
            "1",
            "--json",
        ],
        check=False,
    )
    assert out.returncode == 0, out.stderr[-2000:]


def test_a_refusal_lists_only_real_differences():
    """A list and a tuple of the same values are one value (the store holds JSON)."""
    from sim_tactile.generate import _diff

    stored = {"pad": {"size_m": [0.012, 0.012]}, "plates": ["a", "b"], "seed": 3}
    now = {"pad": {"size_m": (0.012, 0.012)}, "plates": ("a", "b"), "seed": 4}
    assert _diff(stored, now) == ["seed: 3 in the store, 4 now"]
