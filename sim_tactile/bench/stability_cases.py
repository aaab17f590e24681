"""The hard cases of ``sim-tactile bench stability``, each a small function returning a
:class:`~.stability.Measured` or raising (:func:`~.stability.run_case` classifies the outcome).
"""

from __future__ import annotations

import math

import numpy as np

from .stability import Case, Measured, short


# ---------------------------------------------------------------- slides
def _slide(plate="finger7/ridges-4", *, force_n=1.0, force_tol=0.05, expect_warning=None, **kw):
    """Simulate (ideal loads) and measure. ``force_tol``: allowed relative deviation of the
    slide's mean normal force from the command (None: not checked, only reported)."""
    from ..sim.plan.protocol import Protocol
    from ..sim.slide import simulate

    proto_kw = {
        k: kw.pop(k)
        for k in list(kw)
        if k in ("speed_m_s", "duration_s", "press_s", "force_control")
    }
    proto = Protocol(force_n=force_n, **proto_kw)
    res = simulate(plate, "grid3x3", protocol=proto, ideal=True, **kw)
    rec = res.recording
    d = np.asarray(rec.data, float)
    f = np.asarray(rec.meta["normal_force_n"], float)
    rtf = rec.meta["sim_s"] / rec.meta["slide_wall_s"]
    mean_f = float(f.mean())
    off = float(np.mean(f <= 0))
    fid = res.fidelity
    detail = (
        f"RTF {rtf:.3g} ({fid.level}, node pitch {fid.pitch_m * 1e3:.3g} mm, dt "
        f"{fid.dt_s * 1e3:.3g} ms); over {rec.meta['sim_s']:.3g} s the normal force averaged "
        f"{mean_f:.4g} N of {force_n:g} N commanded ({mean_f / force_n - 1:+.1%}), peak "
        f"{f.max():.3g} N, pad off the plate in {off:.1%} of samples; peak taxel load "
        f"{d.max():.3g} N"
    )
    if res.warnings:
        detail += "; simulation warnings: " + " | ".join(short(w, 120) for w in res.warnings)
    checks = {
        "loads are not negative": bool(d.min() >= -1e-9),
        "the pad touched the plate": bool(d.max() > 0),
        "normal force is not negative": bool(f.min() >= 0),
        "the press settled at the command before the slide": not any(
            "did not settle" in w for w in res.warnings
        ),
        "real-time factor is positive": bool(rtf > 0),
    }
    if proto.force_control == "quasi-static":
        checks["the force is held at every sample (to 1e-9)"] = bool(
            np.allclose(f, force_n, rtol=1e-9, atol=0.0)
        )
    if force_tol is not None:
        checks[f"mean normal force within {force_tol:.0%} of the command"] = bool(
            abs(mean_f - force_n) <= force_tol * force_n
        )
    if expect_warning:
        checks[f"warns that {expect_warning}"] = any(expect_warning in w for w in res.warnings)
    values = {
        "rtf": rtf,
        "mean_force_n": mean_f,
        "peak_force_n": float(f.max()),
        "off_plate_fraction": off,
        "peak_load_n": float(d.max()),
        "loads": d,
        "forces": f,
    }
    return Measured(detail, values, checks)


#: What the fast slides check of the mean force, under each force control.
_FAST_NOTE = (
    "under the default quasi-static force control the force is held at any speed (checked "
    "to 0.1%); the dynamic loop skims the ridge tops at these speeds (its fast_slide_200_dynamic "
    "row reports, not checks, its mean force)"
)


def fast_slide_200() -> Measured:
    return _slide(speed_m_s=0.2, force_tol=1e-3)


def fast_slide_400() -> Measured:
    return _slide(speed_m_s=0.4, force_tol=1e-3)


def fast_slide_200_dynamic() -> Measured:
    return _slide(speed_m_s=0.2, force_tol=None, force_control="dynamic")


def high_force_5n() -> Measured:
    return _slide(force_n=5.0)


def high_force_20n() -> Measured:
    return _slide(force_n=20.0, duration_s=0.3)


def sharp_edges() -> Measured:
    from ..sensors import Finger

    return _slide(finger=Finger(edge_radius_m=0.0))


def features_below_node_pitch() -> Measured:
    from ..plates import Bumps, Plate

    plate = Plate(
        texture=Bumps(
            rows=30, cols=30, shape="box", size_m=0.3e-3, height_m=0.3e-3, spacing_m=1.2e-3
        )
    )
    return _slide(plate, duration_s=0.08, press_s=0.05, expect_warning="smeared")


def too_coarse_time_step() -> Measured:
    return _slide(dt_s=0.01, duration_s=0.3, force_control="dynamic")


def coarse_step_held_force() -> Measured:
    return _slide(dt_s=0.01, duration_s=0.3, expect_warning="too coarse")


def skin_pressed_to_bottom() -> Measured:
    from ..sensors import Finger

    return _slide(finger=Finger(thickness_m=0.3e-3), force_n=5.0, duration_s=0.3)


def static_press_beyond_skin() -> Measured:
    from ..sensors import Finger
    from ..sim.static_press import press

    finger = Finger(shape="sphere", radius_m=8e-3, size_m=(8e-3, 8e-3), thickness_m=0.5e-3)
    r = press(finger, 5.0, readout_pitch_m=0.5e-3)
    return Measured(
        f"total force {r.total_force_n:.4g} N, contact radius {r.contact_radius_m * 1e3:.3g} mm",
        {"total_force_n": r.total_force_n, "pressure_pa": r.pressure_pa},
        {
            "total force is the command": abs(r.total_force_n - 5.0) < 0.01,
            "pressure is not negative": bool(r.pressure_pa.min() >= 0),
        },
    )


# ---------------------------------------------------------------- neurons and encoders
def _trains_measured(trains: list[np.ndarray], duration_s: float, what: str) -> Measured:
    counts = [int(t.size) for t in trains]
    lo = min((float(t[0]) for t in trains if t.size), default=0.0)
    hi = max((float(t[-1]) for t in trains if t.size), default=0.0)
    return Measured(
        f"{what}: {sum(counts)} spikes in {duration_s:g} s, times in [{lo:.3g}, {hi:.3g}] s",
        {"spike_times": trains, "spikes": float(sum(counts))},
        {
            "spike times sorted": all(bool(np.all(np.diff(t) >= 0)) for t in trains),
            "spike times inside the input's span": bool(lo >= 0 and hi <= duration_s + 1e-9),
        },
    )


def izhikevich_huge_current() -> Measured:
    from ..encoders import simulate_izhikevich

    trains = simulate_izhikevich(np.full(100, 1e6), 100.0, "RS")
    return _trains_measured(trains, 1.0, "RS neuron, I = 1e6 for 1 s (rk4, dt 0.1 ms)")


def izhikevich_strongly_negative() -> Measured:
    from ..encoders import simulate_izhikevich

    trains = simulate_izhikevich(np.full(100, -200.0), 100.0, "RS", scheme="euler", dt_s=1e-3)
    return _trains_measured(trains, 1.0, "RS neuron, I = -200 for 1 s (Euler, dt 1 ms)")


def lif_huge_current() -> Measured:
    from ..encoders import simulate_lif

    trains = simulate_lif(np.full(100, 1e9), 100.0)
    return _trains_measured(trains, 1.0, "LIF neuron, input 1e9 for 1 s")


def neuron_nan_input() -> Measured:
    from ..encoders import simulate_izhikevich

    x = np.ones(100)
    x[10] = np.nan
    trains = simulate_izhikevich(x, 100.0, "RS")
    return _trains_measured(trains, 1.0, "RS neuron with a NaN sample")


def _dead_and_noisy() -> tuple[np.ndarray, float]:
    """Three slides (time x 9 taxels) of an L0 slide over ridges-4, taxel 0 dead (all zero)
    and taxel 1 buried in noise of 5x the largest load (negative values included)."""
    from ..sim.plan.protocol import Protocol
    from ..sim.slide import simulate

    rec = simulate(
        "finger7/ridges-4",
        "grid3x3",
        protocol=Protocol(duration_s=0.6),
        fidelity="L0",
        ideal=True,
    ).recording
    rng = np.random.default_rng(7)
    x = np.repeat(np.asarray(rec.data, float)[None], 3, axis=0)
    x[:, :, 0] = 0.0
    x[:, :, 1] += 5.0 * x.max() * rng.standard_normal(x[:, :, 1].shape)
    return x, float(rec.meta["rate_hz"])


def dead_and_noisy_taxels() -> Measured:
    from ..encoders import IzhikevichEncoder, ThresholdEncoder
    from ..spikes import distances, spike_features

    x, rate = _dead_and_noisy()
    izh = IzhikevichEncoder(rate_hz=rate, preset="SA", gain=15.0, normalize="minmax")
    thr = ThresholdEncoder(rate_hz=rate, n_thresholds=2)
    s_izh = izh.fit_transform(x)
    s_thr = thr.fit_transform(x)
    f_izh = spike_features(s_izh)
    f_thr = spike_features(s_thr)
    vp = distances.pairwise([s.times[1] for s in s_izh], "victor_purpura", q=24.0)
    vr = distances.pairwise([s.times[0] for s in s_izh], "van_rossum", tau=0.01)
    counts = [int(t.size) for t in s_izh[0].times]
    return Measured(
        f"Izhikevich (SA, gain 15, min-max) spike counts per taxel {counts} (dead taxel 0: "
        f"{counts[0]}, noisy taxel 1: {counts[1]}); {f_izh.shape[1]} + {f_thr.shape[1]} "
        f"features per slide (Izhikevich + threshold K = 2), all finite; VP of the noisy taxel "
        f"across slides up to {vp.max():.3g}",
        {
            "izh_features": f_izh,
            "thr_features": f_thr,
            "vp": vp,
            "vr": vr,
            "largest_feature": float(max(f_izh.max(), f_thr.max())),
            "spikes_noisy_taxel": float(counts[1]),
            "largest_vp": float(vp.max()),
        },
        {
            "features are not negative": bool(f_izh.min() >= 0 and f_thr.min() >= 0),
            "the dead taxel does not fire": counts[0] == 0,
            "distances are not negative": bool(vp.min() >= 0 and vr.min() >= 0),
        },
    )


def dead_taxel_rate_calibration() -> Measured:
    """Paper 003's encoder sets each taxel's gain from its largest training value: a dead
    taxel has none."""
    from ..encoders import IzhikevichEncoder

    x, rate = _dead_and_noisy()
    enc = IzhikevichEncoder(rate_hz=rate, preset="RS", max_rate_hz=100.0, normalize="minmax")
    trains = enc.fit_transform(x)
    f = np.concatenate([np.concatenate([t for t in s.times]) for s in trains])
    return Measured(f"{f.size} spikes", {"spike_times": f, "spikes": float(f.size)}, {})


def empty_spike_trains() -> Measured:
    from ..spikes import distances as D

    e = np.empty(0)
    one = np.array([0.5])
    three = np.array([0.1, 0.2, 0.3])
    got = {
        "vp(empty, empty)": (D.victor_purpura(e, e, 10.0), 0.0),
        "vp(empty, 3 spikes)": (D.victor_purpura(e, three, 10.0), 3.0),
        "vr(empty, empty)": (D.van_rossum(e, e, 0.01), 0.0),
        "vr(empty, 1 spike)": (D.van_rossum(e, one, 0.01), 1 / math.sqrt(2)),
        "isi(empty, empty)": (D.isi_distance(e, e, 0.0, 1.0), 0.0),
        "isi(empty, 1 spike)": (D.isi_distance(e, one, 0.0, 1.0), None),
        "spike(empty, empty)": (D.spike_distance(e, e, 0.0, 1.0), 0.0),
        "spike(empty, 3 spikes)": (D.spike_distance(e, three, 0.0, 1.0), None),
        "es(empty, empty)": (D.event_sync_distance(e, e), 0.0),
        "es(empty, 1 spike)": (D.event_sync_distance(e, one), 1.0),
    }
    mats = {}
    params = {
        "victor_purpura": {"q": 10.0},
        "van_rossum": {"tau": 0.01},
        "isi_distance": {"t_start": 0.0, "t_end": 1.0},
        "spike_distance": {"t_start": 0.0, "t_end": 1.0},
        "event_sync_distance": {},
    }
    for metric, p in params.items():
        mats[metric] = D.pairwise([e, one, e, three], metric, **p)
    checks = {
        f"{k} = {want:.4g}": abs(val - want) < 1e-9
        for k, (val, want) in got.items()
        if want is not None
    }
    checks.update(
        {
            f"{k} in [0, 1]": 0.0 <= val <= 1.0
            for k, (val, want) in got.items()
            if k[:3] in ("isi", "spi")
        }
    )
    for metric, m in mats.items():
        checks[f"pairwise {metric}: symmetric, zero diagonal, not negative"] = bool(
            np.allclose(m, m.T) and np.all(np.diag(m) == 0) and m.min() >= 0
        )
    values = {k: v for k, (v, _) in got.items()}
    values.update({f"pairwise_{k}": m for k, m in mats.items()})
    detail = ", ".join(f"{k} = {v:.4g}" for k, (v, _) in got.items())
    return Measured(detail + "; pairwise matrices with empty trains finite", values, checks)


# ---------------------------------------------------------------- the registry
CASES: tuple[Case, ...] = (
    Case(
        "fast_slide_200mm_s",
        fast_slide_200,
        "ok",
        f"finger7/ridges-4 crossed at 200 mm/s, 1 N; {_FAST_NOTE}",
    ),
    Case(
        "fast_slide_400mm_s",
        fast_slide_400,
        "ok",
        f"finger7/ridges-4 crossed at 400 mm/s, 1 N; {_FAST_NOTE}",
    ),
    Case(
        "fast_slide_200_dynamic",
        fast_slide_200_dynamic,
        "ok",
        "finger7/ridges-4 at 200 mm/s under the dynamic force loop: its damping (critical at the "
        "flat pad's stiffness) lets the pad sink back after a ridge at only F/c (about 19 mm/s "
        "at 1 N), so it skims the ridge tops; the mean force is reported, not checked",
    ),
    Case("high_force_5n", high_force_5n, "ok", "finger7/ridges-4 crossed under 5 N"),
    Case(
        "high_force_20n",
        high_force_20n,
        "error",
        "20 N on the 4 mm skin (E 0.3 MPa) over 2.5 mm ridges: beyond what the skin carries. "
        "It stops as a bottomed skin once the pad is 2.5 mm below the base surface: past half "
        "the plate's 5 mm base box the collider reads a node's depth from the bottom face, so "
        "that depth, not the skin's 4 mm, is the limit",
    ),
    Case("sharp_edges", sharp_edges, "ok", "a pad without edge roll-off over sharp box ridges"),
    Case(
        "features_below_node_pitch",
        features_below_node_pitch,
        "ok",
        "30 x 30 bumps of 0.3 mm, below two node pitches: a result with a warning",
    ),
    Case(
        "too_coarse_time_step",
        too_coarse_time_step,
        "error",
        "dt = 10 ms under the dynamic force loop, beyond the skin-bone coupling's stability limit",
    ),
    Case(
        "coarse_step_held_force",
        coarse_step_held_force,
        "ok",
        "dt = 10 ms under quasi-static force control: no coupling limit; a result with a "
        "warning that a feature takes too few steps",
    ),
    Case(
        "skin_pressed_to_bottom",
        skin_pressed_to_bottom,
        "error",
        "a 0.3 mm skin under 5 N",
    ),
    Case(
        "static_press_beyond_skin",
        static_press_beyond_skin,
        "error",
        "a static press of 5 N on a sphere with a 0.5 mm skin",
    ),
    Case(
        "izhikevich_huge_current",
        izhikevich_huge_current,
        "either",
        "I = 1e6 into an RS neuron: a warning and capped spikes, or an overflow error",
    ),
    Case(
        "izhikevich_strongly_negative",
        izhikevich_strongly_negative,
        "either",
        "I = -200 under Euler at 1 ms, below the step's stable input: a warning",
    ),
    Case("lif_huge_current", lif_huge_current, "either", "input 1e9 into a LIF neuron"),
    Case("neuron_nan_input", neuron_nan_input, "error", "a NaN sample into a neuron"),
    Case(
        "dead_and_noisy_taxels",
        dead_and_noisy_taxels,
        "ok",
        "a dead taxel and a noisy one through Izhikevich and threshold encoding and features",
    ),
    Case(
        "dead_taxel_rate_calibration",
        dead_taxel_rate_calibration,
        "error",
        "paper 003's max-rate gain calibration with a dead taxel",
    ),
    Case("empty_spike_trains", empty_spike_trains, "ok", "empty trains into every distance"),
)


def case_names() -> list[str]:
    return [c.name for c in CASES]
