"""``sim-tactile simulate`` (one slide) and ``press`` (a static press)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import ConfigError
from ..sim.fidelity import FIDELITIES, PRESS_LEVELS
from ..sim.protocol import FORCE_CONTROLS
from ._common import add_command, emit, log


def cmd_simulate(args: argparse.Namespace) -> int:
    from ..sim.plots import plot_heatmap, plot_traces
    from ..sim.protocol import Protocol
    from ..sim.simulate import simulate

    out = Path(args.out)
    if out.suffix != ".npz":
        raise ConfigError(f"--out {args.out!r} must end in .npz")
    proto = Protocol(
        speed_m_s=args.speed,
        force_n=args.force,
        duration_s=args.duration,
        rate_hz=args.rate,
        force_control=args.force_control,
    )
    res = simulate(
        args.plate,
        args.sensor,
        protocol=proto,
        fidelity=args.fidelity,
        seed=args.seed,
        ideal=args.ideal,
    )
    for w in res.warnings:
        log(f"warning: {w}")
    log(f"fidelity: {res.fidelity.reason}")
    rec = res.recording
    log(f"skin problem solved: {rec.meta['skin_problem']}")
    rec.save(out)
    figs = [
        str(plot_traces(rec, out.with_suffix(".traces.png"))),
        str(plot_heatmap(rec, out.with_suffix(".heatmap.png"))),
    ]
    payload = {
        "out": str(out),
        "n_taxels": rec.n_taxels,
        "n_samples": int(rec.data.shape[0]),
        "rate_hz": rec.rate_hz,
        "sim_s": res.sim_s,
        "wall_s": round(res.wall_s, 4),
        "fidelity": res.fidelity.level,
        "dt_s": res.fidelity.dt_s,
        "warnings": res.warnings,
        "node_pitch_m": res.fidelity.pitch_m,
        "skin_problem": rec.meta["skin_problem"],
        "transducer": rec.meta["transducer"],
        "figures": figs,
    }
    emit(args, payload, lambda: "\n".join(f"{k}: {v}" for k, v in payload.items()))
    return 0


def cmd_press(args: argparse.Namespace) -> int:
    from ..sensors import Finger
    from ..sim.press import hertz, press, sphere_pad_size_m

    r = args.radius
    kw = {"young_pa": args.young, "poisson": args.poisson, "thickness_m": args.thickness}
    if args.finger == "sphere":
        size = sphere_pad_size_m(r, args.force, args.young / (1 - args.poisson**2))
        finger = Finger(shape="sphere", radius_m=r, size_m=(size, size), **kw)
    else:
        finger = Finger(shape="flat", size_m=(args.size, args.size), **kw)
    res = press(
        finger, args.force, readout_pitch_m=args.pitch, plate=args.plate, fidelity=args.fidelity
    )
    payload = res.to_json()
    if args.finger == "sphere":
        payload["hertz"] = hertz(r, finger.e_star_pa, args.force)
    emit(
        args,
        payload,
        lambda: (
            f"total force {res.total_force_n:.4g} N, contact radius "
            f"{res.contact_radius_m * 1e3:.4g} mm, peak {res.peak_pressure_pa / 1e3:.4g} kPa"
        ),
    )
    return 0


def add_parsers(sub) -> None:
    sm = add_command(
        sub, "simulate", cmd_simulate, "press a finger on a plate, slide it, record the taxels"
    )
    sm.add_argument("--plate", required=True, help="preset plate name")
    sm.add_argument(
        "--sensor",
        default="grid3x3",
        help="sensor: grid3x3, multilayer3x3x2, biotac19, icub60, pvdf2, or a bare layout "
        "dense-<pitch>mm",
    )
    sm.add_argument("--speed", type=float, default=0.06, help="slide speed [m/s]")
    sm.add_argument("--force", type=float, default=1.0, help="normal force [N]")
    sm.add_argument(
        "--duration",
        type=float,
        default=None,
        help="slide duration [s] (default: cross the texture)",
    )
    sm.add_argument(
        "--rate", type=float, default=None, help="sample rate [Hz] (default: the sensor's)"
    )
    sm.add_argument("--fidelity", default="auto", choices=FIDELITIES)
    sm.add_argument(
        "--force-control",
        default="quasi-static",
        choices=FORCE_CONTROLS,
        help="hold the force exactly each step (quasi-static, default) or a damped bone mass",
    )
    sm.add_argument("--seed", type=int, default=0)
    sm.add_argument("--ideal", action="store_true", help="record the noise-free normal load [N]")
    sm.add_argument("--out", required=True, help="output .npz")

    pr = add_command(
        sub, "press", cmd_press, "static indentation of a pad on a plate, read by a dense grid"
    )
    pr.add_argument("--finger", default="sphere", choices=["sphere", "flat"])
    pr.add_argument("--radius", type=float, default=8e-3, help="sphere radius [m]")
    pr.add_argument("--size", type=float, default=12e-3, help="flat pad side [m]")
    pr.add_argument("--young", type=float, default=0.3e6, help="Young's modulus [Pa]")
    pr.add_argument("--poisson", type=float, default=0.5)
    pr.add_argument("--thickness", type=float, default=5e-3, help="skin thickness [m]")
    pr.add_argument("--force", type=float, default=1.0, help="normal force [N]")
    pr.add_argument(
        "--pitch", type=float, default=0.25e-3, help="taxel pitch of the dense grid [m]"
    )
    pr.add_argument("--plate", default="finger7/flat")
    pr.add_argument("--fidelity", default="L1", choices=PRESS_LEVELS)
