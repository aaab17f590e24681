"""The simulate and press commands, through the real console script."""

from __future__ import annotations

import json

import numpy as np
import pytest

#: The contact radius a 0.2 mm node grid resolves against Hertz's (as in test_sim_press).
HERTZ_RADIUS_RTOL = 0.05


@pytest.mark.slow
def test_simulate_json_and_npz(cli, tmp_path):
    out = tmp_path / "r.npz"
    res = cli(
        [
            "simulate",
            "--plate",
            "finger7/ridges-2",
            "--sensor",
            "grid3x3",
            "--speed",
            "0.06",
            "--force",
            "1",
            "--duration",
            "0.3",
            "--ideal",
            "--dt",
            "0.0005",
            "--out",
            str(out),
            "--json",
        ],
    )
    doc = json.loads(res.stdout)
    assert doc["dt_s"] <= 0.0005  # the step forced
    assert {
        "out",
        "n_taxels",
        "n_samples",
        "rate_hz",
        "sim_s",
        "wall_s",
        "fidelity",
        "dt_s",
        "warnings",
    } <= set(doc)
    assert doc["n_taxels"] == 9 and doc["n_samples"] == 30 and doc["rate_hz"] == 100.0
    # it says which problem it solved: ridges across the slide reduce to columns and a half
    assert "mirror-halved solve" in doc["skin_problem"], doc["skin_problem"]
    with np.load(out, allow_pickle=False) as z:
        assert z["data"].shape == (30, 9) and z["data"].dtype == np.float32
        assert z["times"].shape == (30,) and z["taxels"].shape == (9, 3)
    for f in doc["figures"]:
        assert open(f, "rb").read(4) == b"\x89PNG"


@pytest.mark.slow
def test_press_json(cli):
    res = cli(
        [
            "press",
            "--finger",
            "sphere",
            "--radius",
            "0.008",
            "--young",
            "3e5",
            "--force",
            "1",
            "--pitch",
            "0.0005",
            "--json",
        ],
    )
    doc = json.loads(res.stdout)
    assert len(doc["taxels"]) == len(doc["pressure_pa"]) > 100
    # the held force is exact; the contact is Hertz's within the press test's tolerance
    assert doc["total_force_n"] == pytest.approx(1.0, rel=1e-9)
    assert doc["contact_radius_m"] == pytest.approx(
        doc["hertz"]["contact_radius_m"], rel=HERTZ_RADIUS_RTOL
    )


def test_simulate_bad_sensor_is_one_line(cli, tmp_path):
    res = cli(
        [
            "simulate",
            "--plate",
            "finger7/flat",
            "--sensor",
            "nope",
            "--out",
            str(tmp_path / "x.npz"),
            "--json",
        ],
        check=False,
    )
    assert res.returncode != 0 and res.stdout == ""
    assert len(res.stderr.strip().splitlines()) == 1 and "nope" in res.stderr


@pytest.mark.parametrize(
    ("flag", "value", "name"), [("--dt", "-1", "dt_s"), ("--node-pitch", "0.1", "pitch_m")]
)
def test_simulate_forced_step_or_pitch_out_of_range_is_one_line(cli, tmp_path, flag, value, name):
    res = cli(
        ["simulate", "--plate", "finger7/flat", flag, value, "--out", str(tmp_path / "x.npz")],
        check=False,
    )
    assert res.returncode != 0 and not (tmp_path / "x.npz").exists()
    line = res.stderr.strip()
    assert (
        len(line.splitlines()) == 1 and f"{name} = {float(value):g}" in line and "valid: [" in line
    )


@pytest.mark.slow
def test_simulate_force_control_flag(cli, tmp_path):
    args = ["simulate", "--plate", "finger7/ridges-4", "--sensor", "grid3x3", "--speed", "0.06"]
    # L1 at the grid that resolves the ridges (auto refines ridges-4 to 2193 nodes)
    args += ["--force", "1", "--duration", "0.4", "--ideal", "--json", "--fidelity", "L1"]
    forces = {}
    for fc in ("quasi-static", "dynamic"):
        out = tmp_path / f"{fc}.npz"
        cli([*args, "--force-control", fc, "--out", str(out)])
        with np.load(out, allow_pickle=False) as z:
            meta = json.loads(str(z["meta_json"]))
        assert meta["protocol"]["force_control"] == fc
        forces[fc] = np.asarray(meta["normal_force_n"])
    np.testing.assert_allclose(forces["quasi-static"], 1.0, rtol=1e-9)
    assert np.ptp(forces["dynamic"]) > 1e-3  # the damped bone's force moves


@pytest.mark.slow
def test_press_a_layered_skin_and_read_the_stress_at_depth(cli):
    layers = '[{"thickness_m": 0.001, "young_pa": 6e5, "poisson": 0.45}, {"thickness_m": 0.003, "young_pa": 3e5}]'
    common = ["press", "--force", "1", "--pitch", "0.0005", "--json"]
    layered = json.loads(
        cli([*common, "--layers", layers, "--backing", "rigid", "--depth", "0.001"]).stdout
    )
    assert layered["skin"]["backing"] == "rigid" and len(layered["skin"]["layers"]) == 2
    assert layered["depth_m"] == 0.001 and "pressure_pa" not in layered
    stress = np.array(layered["stress_pa"])
    # the stress at depth carries the load: its integral over the plane is the force. The grid
    # covers the pad only, and around the contact the bonded layers are in slight tension
    # (the integral over the grid is 1.027 here, 0.995 on the half-space)
    assert stress.sum() * 0.0005**2 == pytest.approx(1.0, rel=0.05)
    assert layered["total_force_n"] == pytest.approx(1.0, rel=1e-9)
    # a layer on a rigid base is stiffer than the half-space: smaller approach and contact
    half = json.loads(cli(common).stdout)
    assert layered["approach_m"] < half["approach_m"]
    assert layered["contact_area_m2"] < half["contact_area_m2"]


@pytest.mark.parametrize(
    ("args", "names"),
    [
        (["--layers", '[{"thick": 1}]', "--backing", "rigid"], "--layers[0]"),
        (["--layers", "[1,", "--backing", "rigid"], "--layers"),
        (["--backing", "halfspace", "--backing-young", "1"], "stack.backing_young_pa"),
        (["--depth", "0.01"], "depth_m"),
        (["--node-pitch", "0.01"], "node_pitch_m"),
        (
            ["--layers", '[{"thickness_m": 0.001, "young_pa": 3e5, "poisson": 0.7}]'],
            "layer.poisson",
        ),
    ],
)
def test_press_bad_skin_is_one_line_naming_the_parameter(cli, args, names):
    res = cli(["press", *args, "--json"], check=False)
    assert res.returncode == 2 and res.stdout == ""
    assert len(res.stderr.strip().splitlines()) == 1 and names in res.stderr


@pytest.mark.slow
def test_press_with_friction_loads_the_trailing_side_at_depth(cli):
    """A flat pad at 1 N with mu 0.5, read 1 mm deep: the side the pad slides away from
    reads more (the tractions' Cerruti stress), mirrored when the slide reverses; the force
    and, on the incompressible half-space, the contact are unchanged."""
    common = ["press", "--finger", "flat", "--force", "1", "--pitch", "0.001", "--depth", "0.001"]

    def sides(extra):
        doc = json.loads(cli([*common, *extra, "--json"]).stdout)
        s, x = np.array(doc["stress_pa"]), np.array(doc["taxels"])[:, 0]
        return doc, s[x > 2.5e-3].mean(), s[x < -2.5e-3].mean()

    plain, ahead0, behind0 = sides([])
    fwd, ahead, behind = sides(["--friction", "0.5", "--slide-dir", "x"])
    back, ahead_r, behind_r = sides(["--friction", "0.5", "--slide-dir=-x"])
    assert ahead0 == pytest.approx(behind0, rel=1e-9)
    assert behind > behind0 * 1.05 and ahead < ahead0 * 0.95
    assert ahead_r == pytest.approx(behind, rel=1e-9) and behind_r == pytest.approx(ahead, rel=1e-9)
    assert fwd["approach_m"] == pytest.approx(plain["approach_m"], rel=1e-9)
    assert fwd["contact_area_m2"] == plain["contact_area_m2"]


@pytest.mark.slow
def test_press_with_friction_on_a_layer_moves_the_contact_pressure(cli):
    """On 4 mm of silicone bonded to a bone, sliding friction (mu 0.5) couples into the
    normal problem: at the surface the trailing side's pressure rises and the leading
    side's falls, the pad sinks deeper, and reversing the slide mirrors it (0.5 mm nodes)."""
    common = [
        "press", "--finger", "flat", "--force", "1", "--backing", "rigid", "--thickness",
        "0.004", "--pitch", "0.001", "--node-pitch", "0.0005", "--json",
    ]  # fmt: skip

    def sides(extra):
        doc = json.loads(cli([*common, *extra]).stdout)
        p, x = np.array(doc["pressure_pa"]), np.array(doc["taxels"])[:, 0]
        return doc, p[x < -2.5e-3].mean(), p[x > 2.5e-3].mean()

    plain, trail0, lead0 = sides([])
    fwd, trail, lead = sides(["--friction", "0.5", "--slide-dir", "x"])
    back, trail_r, lead_r = sides(["--friction", "0.5", "--slide-dir=-x"])
    assert trail0 == pytest.approx(lead0, rel=1e-6)
    assert trail > 1.08 * trail0 and lead < 0.92 * lead0
    assert trail_r == pytest.approx(lead, rel=1e-6) and lead_r == pytest.approx(trail, rel=1e-6)
    assert fwd["approach_m"] > 1.02 * plain["approach_m"]
