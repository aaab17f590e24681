"""Simulation warnings reach the user: each distinct warning once, with the number of slides
it touched, whether the slides were simulated now or read from the cache."""

from __future__ import annotations

from sim_tactile.cache import ArtefactCache
from sim_tactile.plates import get_plate
from sim_tactile.sensors import get_sensor
from sim_tactile.sim.protocol import Protocol
from sim_tactile.slides import SlideJob, run_slides

ALIAS = "the taxel array aliases the texture"


def test_run_slides_prints_each_warning_once_with_its_count(tmp_path):
    cache = ArtefactCache(tmp_path)
    proto = Protocol(duration_s=0.1, rate_hz=100.0, start="texture")
    sensor = get_sensor("grid3x3")
    jobs = [
        SlideJob(get_plate("textures20/cylinders-3.0mm"), sensor, proto, seed=s, fidelity="L0")
        for s in (1, 2)
    ] + [SlideJob(get_plate("finger7/flat"), sensor, proto, seed=3, fidelity="L0")]
    for attempt in ("simulated", "cached"):
        lines: list[str] = []
        _, stats = run_slides(jobs, cache=cache, workers=1, log=lines.append)
        alias = [x for x in lines if ALIAS in x]
        assert len(alias) == 1, (attempt, lines)
        assert alias[0].startswith("warning: ") and alias[0].endswith("(2 of 3 slides)")
        assert any(ALIAS in w and w.endswith("(x2)") for w in stats["sim_warnings"]), attempt
    assert stats["slides_cached"] == 3


def test_generate_prints_each_warning_once_and_returns_them(tmp_path, monkeypatch):
    from sim_tactile.generate import generate

    monkeypatch.setenv("SIM_TACTILE_CACHE", str(tmp_path / "cache"))
    cfg = tmp_path / "alias.toml"
    cfg.write_text(
        'plates = ["textures20/cylinders-3.0mm", "finger7/flat"]\nsensor = "grid3x3"\n'
        'slides_per_plate = 2\nfidelity = "L0"\n[protocol]\nduration_s = 0.1\n'
        'start = "texture"\n'
    )
    lines: list[str] = []
    res = generate(str(cfg), tmp_path / "a.zarr", workers=1, progress=False, log=lines.append)
    alias = [x for x in lines if ALIAS in x]
    assert len(alias) == 1 and alias[0].endswith("(2 of 4 slides)"), lines
    (warns,) = res["warnings"].values()
    assert any(ALIAS in w and w.endswith("(x2)") for w in warns)
