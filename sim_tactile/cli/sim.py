"""``sim-tactile simulate`` (one slide) and ``press`` (a static press)."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from ..errors import ConfigError
from ..sim.plan.fidelity import FIDELITIES, PRESS_LEVELS
from ..sim.plan.options import DT_RANGE_S, PITCH_RANGE_M
from ..sim.plan.protocol import FORCE_CONTROLS, STARTS
from ._common import add_command, add_knob_args, add_plate_args, emit, log, options_of, plate_of


def cmd_simulate(args: argparse.Namespace) -> int:
    from ..sim.plan.protocol import Protocol
    from ..sim.plots import plot_heatmap, plot_traces
    from ..sim.slide import simulate

    out = Path(args.out)
    if out.suffix != ".npz":
        raise ConfigError(f"--out {args.out!r} must end in .npz")
    proto = Protocol(
        speed_m_s=args.speed,
        force_n=args.force,
        duration_s=args.duration,
        rate_hz=args.rate,
        force_control=args.force_control,
        start=args.start,
    )
    sensor = args.sensor
    if args.sensor_config is not None:
        from ..sensors import resolve_sensor
        from ..sensors.calibration import calibrated, load_calibration

        cal = load_calibration(args.sensor_config)
        sensor = calibrated(resolve_sensor(args.sensor or cal.sensor), cal)
    res = simulate(
        plate_of(args.plate, args.plate_frame),
        sensor or "grid3x3",
        protocol=proto,
        fidelity=args.fidelity,
        seed=args.seed,
        ideal=args.ideal,
        pitch_m=args.node_pitch,
        dt_s=args.dt,
        options=options_of(args),
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


#: press --slide-dir: the direction the pad would slide in, in its plane
SLIDE_DIRS = {"x": (1.0, 0.0), "-x": (-1.0, 0.0), "y": (0.0, 1.0), "-y": (0.0, -1.0)}


def _press_stack(args: argparse.Namespace):
    """The skin stack of ``press``'s options, or None for the half-space skin."""
    import json

    from ..sensors.stack import Layer, Stack

    if args.layers is None and args.backing == "none":
        return None
    if args.layers is not None:
        try:
            rows = json.loads(args.layers)
        except json.JSONDecodeError as e:
            raise ConfigError(
                f"--layers is not JSON ({e}); valid: a list of objects with "
                "thickness_m, young_pa and poisson, from the surface down"
            ) from e
        if not isinstance(rows, list) or not rows or not all(isinstance(r, dict) for r in rows):
            raise ConfigError(
                f"--layers = {args.layers!r}; valid: a non-empty JSON list of objects with "
                "thickness_m, young_pa and poisson, from the surface down"
            )
        allowed = {"thickness_m", "young_pa", "poisson"}
        for i, r in enumerate(rows):
            if set(r) - allowed or "thickness_m" not in r or "young_pa" not in r:
                raise ConfigError(
                    f"--layers[{i}] has keys {sorted(r)}; valid: thickness_m and young_pa "
                    "(required), poisson (default 0.5)"
                )
        layers = tuple(Layer(**r) for r in rows)
    else:
        layers = (Layer(args.thickness, args.young, args.poisson),)
    backing = "rigid" if args.backing == "none" else args.backing
    if backing == "halfspace":
        return Stack(layers, "halfspace", args.backing_young, args.backing_poisson)
    return Stack(layers, backing)


def cmd_press(args: argparse.Namespace) -> int:
    from ..sensors import Finger
    from ..sim.static_press import hertz, press, sphere_pad_size_m

    r = args.radius
    stack = _press_stack(args)
    top = stack.layers[0] if stack else None
    young = top.young_pa if top else args.young
    poisson = top.poisson if top else args.poisson
    kw = {"young_pa": young, "poisson": poisson}
    if args.finger == "sphere":
        size = sphere_pad_size_m(r, args.force, young / (1 - poisson**2))
        finger = Finger(shape="sphere", radius_m=r, size_m=(size, size), **kw)
    else:
        finger = Finger(shape="flat", size_m=(args.size, args.size), **kw)
    finger = finger.layered(stack) if stack else replace(finger, thickness_m=args.thickness)
    if args.friction is not None:
        finger = replace(finger, friction=args.friction, skin_tractions=True)
    res = press(
        finger,
        args.force,
        readout_pitch_m=args.pitch,
        node_pitch_m=args.node_pitch,
        plate=plate_of(args.plate, args.plate_frame),
        fidelity=args.fidelity,
        depth_m=args.depth,
        slide_dir=SLIDE_DIRS[args.slide_dir],
    )
    payload = res.to_json()
    payload["skin"] = stack.to_json() if stack else {"half_space": kw}
    if args.finger == "sphere":
        payload["hertz"] = hertz(r, finger.e_star_pa, args.force)
    where = "pressure" if args.depth == 0 else f"stress at {args.depth * 1e3:g} mm"
    emit(
        args,
        payload,
        lambda: (
            f"total force {res.total_force_n:.4g} N, contact radius "
            f"{res.contact_radius_m * 1e3:.4g} mm (area {res.contact_area_m2 * 1e6:.4g} mm^2), "
            f"peak pressure {res.peak_pressure_pa / 1e3:.4g} kPa, approach "
            f"{res.approach_m * 1e3:.4g} mm, largest {where} {res.pressure_pa.max() / 1e3:.4g} kPa"
        ),
    )
    return 0


def add_parsers(sub) -> None:
    _add_simulate(sub)
    _add_press(sub)


def _add_simulate(sub) -> None:
    sm = add_command(
        sub,
        "simulate",
        cmd_simulate,
        "Press a finger on a plate, slide it across, and record its taxels (one slide).",
        compiles=True,
    )
    add_plate_args(sm, required=True)
    sm.add_argument(
        "--sensor",
        default=None,
        help="The sensor: grid3x3 (the default), multilayer3x3x2, biotac19, icub60, pvdf2, a "
        "sensor file (.toml; copy one of assets/sensors), or a bare layout dense-<pitch>mm.",
    )
    sm.add_argument(
        "--sensor-config",
        default=None,
        help="A sensor calibration (.toml, from 'sim-tactile calibrate'); it names the sensor "
        "unless --sensor does.",
    )
    sm.add_argument("--speed", type=float, default=0.06, help="The slide speed [m/s].")
    sm.add_argument("--force", type=float, default=1.0, help="The normal force [N].")
    sm.add_argument(
        "--duration",
        type=float,
        default=None,
        help="The slide's duration [s] (default: the time to cross the texture).",
    )
    sm.add_argument(
        "--rate", type=float, default=None, help="The sample rate [Hz] (default: the sensor's)."
    )
    sm.add_argument(
        "--fidelity",
        default="auto",
        choices=FIDELITIES,
        help="The fidelity level: auto (the default) picks the node grid and step for the "
        "scene; L0, L1 and L2 force a level.",
    )
    sm.add_argument(
        "--force-control",
        default="quasi-static",
        choices=FORCE_CONTROLS,
        help="Hold the force exactly at each step (quasi-static, the default), or push a "
        "damped bone mass (dynamic).",
    )
    sm.add_argument(
        "--start",
        default="flat",
        choices=STARTS,
        help="Start on flat ground and cross the texture (flat, the default), or start on the "
        "texture and stay on it for --duration (texture; the textures20-long strips).",
    )
    sm.add_argument(
        "--seed", type=int, default=0, help="The seed of the slide's jitters and noise."
    )
    sm.add_argument(
        "--ideal",
        action="store_true",
        help="Record the noise-free normal load on each taxel [N] instead of the sensor's output.",
    )
    sm.add_argument(
        "--node-pitch",
        type=float,
        default=None,
        help="The skin's node pitch along the slide [m], in [{:g}, {:g}] (default: the "
        "fidelity's).".format(*PITCH_RANGE_M),
    )
    sm.add_argument(
        "--dt",
        type=float,
        default=None,
        help="The time step [s], at most this, in [{:g}, {:g}] (default: the fidelity's; a "
        "piezoelectric sensor on a rough plate needs about 8 steps a sample).".format(*DT_RANGE_S),
    )
    add_knob_args(sm)
    sm.add_argument("--out", required=True, help="The recording to write (.npz).")


def _add_press(sub) -> None:
    pr = add_command(
        sub,
        "press",
        cmd_press,
        "Press a pad statically on a plate and read the pressure with a dense grid of taxels.",
        compiles=True,
    )
    pr.add_argument(
        "--finger",
        default="sphere",
        choices=["sphere", "flat"],
        help="The pad's shape: a sphere (the default) or a flat square.",
    )
    pr.add_argument("--radius", type=float, default=8e-3, help="The sphere's radius [m].")
    pr.add_argument("--size", type=float, default=12e-3, help="The flat pad's side [m].")
    pr.add_argument("--young", type=float, default=0.3e6, help="The skin's Young's modulus [Pa].")
    pr.add_argument("--poisson", type=float, default=0.5, help="The skin's Poisson ratio.")
    pr.add_argument(
        "--thickness",
        type=float,
        default=5e-3,
        help="The skin's thickness [m]: how deep the half-space skin may be pressed, or the "
        "layer's thickness on a --backing.",
    )
    pr.add_argument(
        "--backing",
        default="none",
        choices=["none", "rigid", "halfspace"],
        help="The skin's backing: with none (the default) the skin is a half-space; with rigid "
        "or halfspace it is a layer (or --layers) bonded to that backing.",
    )
    pr.add_argument(
        "--layers",
        default=None,
        help='The skin\'s layers from the surface down, as JSON: [{"thickness_m": 0.001, '
        '"young_pa": 3e5, "poisson": 0.5}, ...]; they override --thickness, --young and '
        "--poisson.",
    )
    pr.add_argument(
        "--backing-young",
        type=float,
        default=3e6,
        help="The Young's modulus of a halfspace backing [Pa].",
    )
    pr.add_argument(
        "--backing-poisson",
        type=float,
        default=0.5,
        help="The Poisson ratio of a halfspace backing.",
    )
    pr.add_argument(
        "--friction",
        type=float,
        default=None,
        help="The skin carries sliding friction of this coefficient (q = mu p against "
        "--slide-dir), and buried taxels (--depth) read its stress.",
    )
    pr.add_argument(
        "--slide-dir",
        default="x",
        choices=list(SLIDE_DIRS),
        help="The direction the pad slides in, for --friction (write --slide-dir=-x for -x).",
    )
    pr.add_argument(
        "--depth",
        type=float,
        default=0.0,
        help="Read the vertical stress this far under the surface [m] (default 0: the pressure).",
    )
    pr.add_argument("--force", type=float, default=1.0, help="The normal force [N].")
    pr.add_argument(
        "--pitch", type=float, default=0.25e-3, help="The taxel pitch of the dense grid [m]."
    )
    pr.add_argument(
        "--node-pitch",
        type=float,
        default=None,
        help="The skin's node pitch [m] (default: the taxel pitch, at most 0.2 mm).",
    )
    add_plate_args(pr, default="finger7/flat")
    pr.add_argument(
        "--fidelity",
        default="L1",
        choices=PRESS_LEVELS,
        help="The skin model: L1 (coupled, the default) or L0 (a Winkler bed).",
    )
