"""The bench commands: stability (every hard case ends in a measured result or a
named error, and the checker can fail) and speed-error (a tiny sweep)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from sim_tactile import cli
from sim_tactile.bench import physics, stability, stability_cases
from sim_tactile.bench.closed_forms import pulse_period
from sim_tactile.bench.pareto import pareto_front
from sim_tactile.bench.speed_error import run_speed_error
from sim_tactile.bench.sweep import Sweep
from sim_tactile.errors import ConfigError, PhysicsError
from sim_tactile.plates import get_plate
from sim_tactile.records import Recording
from sim_tactile.sensors import get_sensor

# ---------------------------------------------------------------- stability

#: Cases that must stop with a named error, and words of the cause their message must hold.
EXPECTED_ERRORS = {
    "too_coarse_time_step": ("PhysicsError", "time step too coarse"),
    "skin_pressed_to_bottom": ("PhysicsError", "pressed to the bottom"),
    "static_press_beyond_skin": ("PhysicsError", "pressed to the bottom"),
    "neuron_nan_input": ("ConfigError", "must be finite"),
    "dead_taxel_rate_calibration": ("ConfigError", "max_rate_hz"),
}


#: What a case must show beyond passing, where a name or a number says more than the outcome.
EXPECTED_DETAIL = {
    "features_below_node_pitch": ("smeared", "aliases the texture"),
    "izhikevich_huge_current": ("NeuronStepWarning",),
    "high_force_20n": ("half the plate's 5 mm base",),
    "coarse_step_held_force": ("too coarse",),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", stability_cases.CASES, ids=stability_cases.case_names())
def test_every_stability_case_ends_as_expected(case):
    """Each hard case, run once: a measured result whose numbers are finite and whose checks
    hold, or the named error it must stop with (never a crash or a silent wrong number)."""
    c = stability.run_case(case)
    assert c["outcome"] in stability.PASS, c["detail"]
    assert c["as_expected"], (c["expected"], c["outcome"], c["detail"])
    if case.name in EXPECTED_ERRORS:
        cls, cause = EXPECTED_ERRORS[case.name]
        assert c["outcome"] == "error" and c["detail"].startswith(cls), c["detail"]
        assert cause in c["detail"], c["detail"]
    if c["outcome"] == "ok":
        assert c["values"] and all(
            isinstance(v, float) and math.isfinite(v) for v in c["values"].values()
        ), c["values"]
        assert c["checks"] and all(c["checks"].values()), c["checks"]
    for words in EXPECTED_DETAIL.get(case.name, ()):
        assert words in c["detail"], (words, c["detail"])
    if case.name == "fast_slide_200_dynamic":  # the dynamic loop skims the ridge tops: said
        assert c["values"]["mean_force_n"] > 1.05
        assert "mean normal force over the slide" in c["detail"]
    if case.name.startswith("fast_slide_") and case.name.endswith("mm_s"):
        assert c["values"]["rtf"] > 0 and "RTF" in c["detail"]


@pytest.mark.slow
def test_bench_stability_cli(cli):
    """The command on two cheap cases: the JSON document, and the named error of one."""
    res = cli(["bench", "stability", "--cases", "empty_spike_trains,neuron_nan_input", "--json"])
    cases = {c["name"]: c for c in json.loads(res.stdout)["cases"]}
    assert cases["empty_spike_trains"]["outcome"] == "ok"
    assert cases["neuron_nan_input"]["outcome"] == "error"
    assert "must be finite" in cases["neuron_nan_input"]["detail"]
    bad = cli(["bench", "stability", "--cases", "nope", "--json"], check=False)
    assert bad.returncode != 0 and "nope" in bad.stderr and bad.stdout == ""


def _nan_case() -> stability.Measured:
    return stability.Measured("a number that is not one", {"rtf": float("nan")}, {})


def _bad_check() -> stability.Measured:
    return stability.Measured("negative load", {"load": -1.0}, {"load is not negative": False})


def _inf_in_train() -> stability.Measured:
    return stability.Measured("trains", {"trains": [np.array([0.1]), np.array([np.inf])]}, {})


def _not_a_number() -> stability.Measured:
    return stability.Measured("text", {"rtf": "fast"}, {})


def _crash() -> stability.Measured:
    raise TypeError("unexpected")


def _named() -> stability.Measured:
    raise PhysicsError("the skin load is not finite (NaN or infinity)")


def test_the_checker_fails_nan_failed_checks_and_crashes():
    out = {
        name: stability.run_case(stability.Case(name, f))
        for name, f in (
            ("nan", _nan_case),
            ("bad_check", _bad_check),
            ("inf_in_train", _inf_in_train),
            ("not_a_number", _not_a_number),
            ("crash", _crash),
            ("named", _named),
        )
    }
    assert out["nan"]["outcome"] == "wrong" and "rtf is not finite" in out["nan"]["detail"]
    assert (
        out["bad_check"]["outcome"] == "wrong"
        and "load is not negative" in (out["bad_check"]["detail"])
    )
    assert out["inf_in_train"]["outcome"] == "wrong"
    assert out["not_a_number"]["outcome"] == "wrong"
    assert out["crash"]["outcome"] == "crash" and "TypeError" in out["crash"]["detail"]
    assert out["named"]["outcome"] == "error" and out["named"]["detail"].startswith("PhysicsError")
    doc = stability.run_stability(
        [stability.Case("nan", _nan_case), stability.Case("named", _named)]
    )
    assert doc["failures"] == 1 and doc["failed"] == ["nan"]


def test_bench_stability_exits_nonzero_on_a_wrong_number(monkeypatch, capsys):
    monkeypatch.setattr(stability_cases, "CASES", (stability.Case("nan", _nan_case),))
    monkeypatch.setattr(stability_cases, "case_names", lambda: ["nan"])
    assert cli.main(["bench", "stability", "--json"]) == 1
    captured = capsys.readouterr()
    doc = json.loads(captured.out)  # still valid JSON: NaN is written as null
    assert doc["cases"][0]["outcome"] == "wrong"
    assert "nan" in captured.err.strip().splitlines()[-1]


def test_bench_without_a_name_is_a_one_line_error(cli):
    res = cli(["bench"], check=False)
    assert res.returncode != 0 and res.stdout == ""
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "speed-error" in lines[0] and "stability" in lines[0]


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--scenes", "nope"], "--scenes 'nope'"),
        (["--levels", "L3"], "L0, L1, L2"),
        (["--duration", "-1"], "--duration = -1 s is out of range"),
    ],
)
def test_bench_speed_error_bad_input_names_the_option(args, needle, tmp_path, capsys):
    rc = cli.main(["bench", "speed-error", "--out", str(tmp_path), *args, "--json"])
    captured = capsys.readouterr()
    assert rc != 0 and captured.out == ""
    assert needle in captured.err


# ---------------------------------------------------------------- speed-error
def test_pareto_front():
    err = [0.0, 0.1, 0.2, 0.15, 0.5]
    cost = [10.0, 1.0, 0.5, 2.0, 0.5]
    assert pareto_front(err, cost) == [2, 1, 0]


def test_pulse_period_of_a_known_pulse_train():
    plate = get_plate("finger7/ridges-4")
    rate, v, spacing = 100.0, 0.058, 9e-3
    t = (np.arange(110) + 0.5) / rate
    x_pad = -0.03 + v * t
    phase = 2 * np.pi * x_pad / spacing
    data = np.maximum(np.cos(phase), 0.0) ** 3 + 0.2 + 0.5 * t  # pulses on a drifting load
    rec = Recording(
        data[:, None],
        t,
        np.zeros((1, 3)),
        meta={"rate_hz": rate, "x_pad_m": x_pad.tolist()},
    )
    m = pulse_period(
        rec, 0, plate.area_length_m, spacing, 0.06, 16e-3
    )  # commanded 60 mm/s, runs at 58
    assert m["pad_speed_m_s"] == pytest.approx(v, rel=1e-9)
    assert m["period_s"] == pytest.approx(spacing / v, rel=2e-3)
    assert m["periods"] > 2


@pytest.mark.slow
def test_speed_error_tiny_sweep(tmp_path, cache):
    sweep = Sweep(
        scenes=("finger7",),
        levels=("L0", "L1"),
        dt_factors=(1.0,),
        pitch_factors=(1.0,),
        l2_dt_factors=(),
        l2_pitch_factors=(),
        physics=False,
    )
    doc = run_speed_error(sweep, tmp_path, cache=cache)
    rows = doc["rows"]
    assert [(r["fidelity"], r["setting"]) for r in rows] == [
        ("L2", "reference"),
        ("L0", "auto"),
        ("L1", "auto"),
        ("auto", "default"),  # ridges-4's default: the lattice anchored to its walls
    ]
    assert rows[3]["wall_m"] == 0.5e-3 and "anchored" in rows[3]["grid"]
    for r in rows:
        assert r["outcome"] == "ok", r
        assert r["rtf"] > 0 and math.isfinite(r["rtf"])
        assert math.isfinite(r["error_vs_reference"]) and r["error_vs_reference"] >= 0
        assert math.isfinite(r["error_vs_analytic"]) and r["error_vs_analytic"] < 0.05
        assert r["dt_s"] > 0 and r["pitch_m"] > 0 and r["scene"].startswith("finger7/ridges-4")
    assert rows[0]["error_vs_reference"] == 0.0
    assert rows[1]["error_vs_reference"] > rows[2]["error_vs_reference"] > 0  # L0 worse than L1
    png = tmp_path / "speed_error.png"
    assert doc["figures"] == [str(png)] and png.read_bytes()[:4] == b"\x89PNG"
    assert json.loads((tmp_path / "speed_error.json").read_text())["rows"][0]["fidelity"] == "L2"
    assert "| finger7/ridges-4" in (tmp_path / "speed_error.md").read_text()
    assert all("error_vs_physics" not in r for r in rows)  # physics=False: not measured


@pytest.mark.slow
def test_speed_error_reports_the_error_against_physics(tmp_path, cache):
    """The same tiny sweep against Tamaas at four pad offsets: every row has its error, the
    Winkler bed is farther off than the coupled half-space (measured 29% against 13.5%; at
    two offsets the walls sit where the Winkler bed happens to do well, 5.4% against 10.1%),
    and the document names its reference; without Tamaas every row says why."""
    sweep = Sweep(
        scenes=("finger7",),
        levels=("L0", "L1"),
        dt_factors=(1.0,),
        pitch_factors=(1.0,),
        l2_dt_factors=(),
        l2_pitch_factors=(),
        physics_offsets=4,
    )
    rows = run_speed_error(sweep, tmp_path, cache=cache)["rows"]
    if physics.tamaas_missing():
        assert all(r["error_vs_physics"] is None and "Tamaas" in r["physics_note"] for r in rows)
        return
    for r in rows:
        assert 0 < r["error_vs_physics"] <= r["physics_max"] * 3 + 1e-9, r
    assert rows[1]["error_vs_physics"] > rows[2]["error_vs_physics"]  # L0 against L1
    assert "The references against physics" in (tmp_path / "speed_error.md").read_text()


@pytest.mark.slow
def test_the_error_against_physics_falls_as_the_grid_resolves_the_ridges():
    """finger7's scene at four pad offsets: the coupled half-space on 1 x 2 mm nodes, 0.25 x
    2 mm (the grid that resolves the ridges) and 0.125 x 1 mm (auto's since aa8c226) against
    Tamaas: the error falls as the nodes shrink (measured 21.7%, 13.5%, 8.2%; at one offset
    the walls can sit where a coarse grid happens to be right: 0.2% at 1 x 2 mm)."""
    pytest.importorskip("tamaas")
    plate, sensor = get_plate("finger7/ridges-4"), get_sensor("grid3x3")
    ref = physics.reference(plate, sensor, 1.0, 4)
    assert 0 < ref.ref_change < 0.05
    errs = [
        ref.error(physics.configuration_loads(ref, plate, sensor, 1.0, "L1", px, py))[0]
        for px, py in ((1e-3, 2e-3), (0.25e-3, 2e-3), (0.125e-3, 1e-3))
    ]
    assert errs[0] > errs[1] > errs[2] and errs[2] < 0.10, errs


def test_sweep_rejects_bad_settings():
    with pytest.raises(ConfigError, match="scene = 'nope' is not valid"):
        Sweep(scenes=("nope",))
    with pytest.raises(ConfigError, match="finer than the L2 reference"):
        Sweep(l2_dt_factors=(0.5,))
    with pytest.raises(ConfigError, match="duration_s"):
        Sweep(duration_s=0.0)


def test_the_physics_reference_is_kept_by_its_content(tmp_path, monkeypatch):
    """A reference is read back from the cache only for the same scene and force: a stored
    one returns the same loads without solving, another force solves again."""
    pytest.importorskip("tamaas")
    plate, sensor = get_plate("finger7/ridges-4"), get_sensor("grid3x3")
    calls = []

    def fake(plate_, finger, force_n, offset, spacing):  # a uniform pressure under the pad
        calls.append(offset)
        x = physics.reference_axis(16, 1e-3)
        X, Y = np.meshgrid(x, x, indexing="ij")
        p = np.full(X.size, force_n * (1 + offset) / (X.size * 1e-6))
        return np.column_stack([X.ravel(), Y.ravel()]), p, 1e-3, None

    monkeypatch.setattr(physics, "tamaas_press", fake)
    first = physics.reference(plate, sensor, 1.0, 2, tmp_path)
    assert len(calls) == 4 and len(list(tmp_path.glob("physics-ref-*.npz"))) == 1
    again = physics.reference(plate, sensor, 1.0, 2, tmp_path)
    assert len(calls) == 4  # read back, not solved
    np.testing.assert_array_equal(again.loads, first.loads)
    assert again.offsets_m == first.offsets_m and again.ref_change == first.ref_change
    other = physics.reference(plate, sensor, 2.0, 2, tmp_path)
    assert len(calls) == 8 and len(list(tmp_path.glob("physics-ref-*.npz"))) == 2
    np.testing.assert_allclose(other.loads, 2 * first.loads)
