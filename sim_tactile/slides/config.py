"""Configuration files of slide sets (TOML or JSON, read as data; no code is run).

::

    name = "my-set"              # optional, a label
    seed = 0                     # integer >= 0
    plates = ["finger7/flat", "finger7/ridges-2"]   # >= 2 plates (the classes): preset names
                                 # or plate files ("my-plate.toml", relative to this file),
                                 # parts and height maps ("knurl.py:make", "part.step?up=+y",
                                 # "scan.npy?pixel_m=1e-5", or a table {file = "part.stl",
                                 # units = "mm", rotate_deg = 90}: sim_tactile.plates.parts.user)
    sensor = "grid3x3"           # a sensor (its layout, rate, transducer and pad): a preset's
                                 # name or a sensor file ("my4x4.toml", relative to this file)
    slides_per_plate = 100       # [2, 100000]
    quick_slides_per_plate = 2   # optional: the slides per plate under --quick
    fidelity = "auto"            # auto, L0, L1, L2
    ideal = false                # record the noise-free normal loads [N]
    solve_every = 1              # the skin solved at every n-th step of a slide held at its
                                 # force, the loads between read off a line (1: every step;
                                 # its error per task scene: the manual's results)
    # solve_tol = 1e-4           # optional: the spectral contact solve's tolerance, in
                                 # [1e-12, 1e-3] (absent: 1e-10, the reference)
    # pitch_m = 0.25e-3          # optional: the skin's node pitch along the slide, in
                                 # [2e-5, 5e-3] m (absent: the fidelity's)
    # dt_s = 1.25e-4             # optional: every slide's time step at most this, in
                                 # [1e-6, 1e-2] s (absent: the fidelity's; a piezoelectric
                                 # sensor on a rough plate needs about 8 steps a sample)

    [protocol]                   # sim.protocol.Protocol: speed_m_s, force_n, duration_s,
    speed_m_s = 0.06             # rate_hz, press_s, settle_s, passes, return_stroke,
    force_n = 1.0                # offset_y_m, force_control, start ("flat" or "texture";
                                 # duration_s absent: cross the texture; rate_hz absent:
                                 # the sensor's)
    [randomise]                  # per-slide variation (one SD)
    speed_jitter = 0.05          # relative, [0, 0.5]
    force_jitter = 0.1           # relative, [0, 0.5]
    offset_jitter_m = 0.5e-3     # [0, 0.01] m

    [finger]                     # optional: change fields of the sensor's pad
    young_pa = 0.3e6

    paper_stack = false          # optional: the skin its paper describes (layers on their
                                 # backing, sensors.paper_stacks) instead of the half-space
    [evaluate]                   # optional: how `sim-tactile run FILE` scores the set
    classifiers = ["svm-raw", "svm-spike"]          # (sim_tactile.tasks.config_task)
    [rig]                        # optional: slides on the probe rig (sim.rig.ProbeRig:
    node_pitch_m = 0.25e-3       # node_pitch_m, probe_mass_kg, margin_m, direction,
                                 # pass_at); needs protocol.duration_s

:func:`config_slide_set` checks every value before anything runs; an error names the file,
the key, the value and what would be valid.
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import fields, replace
from pathlib import Path

from .. import _validate as v
from .._names import did_you_mean
from ..errors import ConfigError
from ..plates import get_plate, preset_names
from ..plates.parts.user import is_user_plate, parse_ref
from ..sensors import Finger, check_pad, get_sensor, sensor_names
from ..sensors.files import load_sensor_file
from ..sim.plan.fidelity import FIDELITIES
from ..sim.plan.options import DT_RANGE_S, KNOBS, PITCH_RANGE_M, StepOptions
from ..sim.plan.protocol import Protocol
from ..sim.plan.rig import ProbeRig
from ..toml_text import check_text_size
from .slide_set import SLIDES_RANGE, SlideSet

#: Most plates (classes) a configuration may name: each is loaded (a script runs, within its
#: time limit) before anything is simulated, and the evaluation's confusion matrices grow as
#: the square of the classes. The textures20 task has 20.
MAX_PLATES = 1000
#: Most slides a configuration may ask for (plates x slides_per_plate): a store indexes
#: every one, and a million 1 s slides take 11 hours of a core at the faster scenes' 25x
#: real time (the manual's throughput results; the slower scenes, days).
MAX_SLIDES = 1_000_000

#: The keys of a configuration file, and what each takes.
TOP_KEYS = {
    "name": "a label",
    "seed": "integer >= 0",
    "plates": "list of >= 2 preset plate names or plate files (.toml)",
    "sensor": "sensor name, or a sensor file (.toml)",
    "slides_per_plate": f"integer in [{SLIDES_RANGE[0]}, {SLIDES_RANGE[1]}]",
    "quick_slides_per_plate": "integer in [2, slides_per_plate]",
    "fidelity": ", ".join(FIDELITIES),
    "ideal": "true or false",
    # the public knobs of how a slide is computed, as sim.plan.options declares them
    **{k.name: k.valid() for k in KNOBS if k.public},
    "pitch_m": "the node pitch along the slide, a number in [{:g}, {:g}] m".format(*PITCH_RANGE_M),
    "dt_s": "every slide's time step at most this, a number in [{:g}, {:g}] s".format(*DT_RANGE_S),
    "protocol": "table",
    "randomise": "table",
    "finger": "table",
    "paper_stack": "true or false",
    "rig": "table (the probe rig)",
    "evaluate": "table: how 'sim-tactile run FILE' scores the set (classifiers, split, repeats)",
}
#: The keys of ``[randomise]``: the protocol's per-slide jitters.
RANDOMISE = ("speed_jitter", "force_jitter", "offset_jitter_m")


def is_config_path(target: str | Path) -> bool:
    """Whether ``target`` names a configuration file rather than a task id: by its suffix,
    ``.toml`` or ``.json`` (the rule a user predicts from the command line)."""
    return str(target).lower().endswith((".toml", ".json"))


def load_config(path: str | Path) -> dict:
    """Read a configuration file (TOML or JSON) as data; no code is run."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"configuration file {str(path)!r} does not exist")
    check_text_size(path, "configuration file")
    text = path.read_bytes()
    try:
        if path.suffix.lower() == ".json":
            cfg = json.loads(text)
        else:
            cfg = tomllib.loads(text.decode())
    except (ValueError, UnicodeDecodeError) as exc:
        raise ConfigError(f"configuration file {path}: cannot be parsed: {exc}") from None
    except RecursionError:
        raise ConfigError(f"configuration file {path}: its values nest too deeply") from None
    if not isinstance(cfg, dict):
        raise ConfigError(f"configuration file {path}: the top level must be a table / object")
    return cfg


def config_slide_set(
    cfg: dict, where: str = "configuration", base_dir: Path | None = None
) -> tuple[SlideSet, int, str]:
    """Validate a configuration (from :func:`load_config`) and build its slide set; returns
    ``(slide_set, seed, name)``. Every error names the parameter and its valid values. Files
    it names (a sensor file) are found relative to ``base_dir`` (the file's folder)."""
    try:
        return _slide_set(cfg, base_dir)
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _slide_set(cfg: dict, base_dir: Path | None) -> tuple[SlideSet, int, str]:
    v.known_keys("", cfg, TOP_KEYS, describe=lambda k: f"{k} ({TOP_KEYS[k]})")
    for key in ("plates", "sensor", "slides_per_plate"):
        if key not in cfg:
            raise ConfigError(f"{key} is missing ({TOP_KEYS[key]})")
    plates = cfg["plates"]
    if not isinstance(plates, list) or not all(isinstance(p, str | dict) for p in plates):
        raise ConfigError(
            f"plates must be a list of preset plate names, plate files, parts or height maps, "
            f"got {plates!r}"
        )
    if len(plates) > MAX_PLATES:
        raise ConfigError(f"plates names {len(plates)} plates; valid: at most {MAX_PLATES}")
    plates = [_plate(p, base_dir) for p in plates]
    if len(plates) < 2 or len(set(plates)) != len(plates):
        raise ConfigError(f"plates must name at least 2 distinct plates, got {plates}")
    sensor, spec = _sensor(cfg["sensor"], base_dir)
    name = cfg.get("name", "")
    if not isinstance(name, str):
        raise ConfigError(f"name must be a string, got {name!r}")
    seed = v.integer("seed", cfg.get("seed", 0), 0, 2**32 - 1)
    slides = v.integer("slides_per_plate", cfg["slides_per_plate"], *SLIDES_RANGE)
    if slides * len(plates) > MAX_SLIDES:
        raise ConfigError(
            f"slides_per_plate = {slides} over {len(plates)} plates is {slides * len(plates)} "
            f"slides; valid: at most {MAX_SLIDES} in all (slides_per_plate <= "
            f"{MAX_SLIDES // len(plates)})"
        )
    quick = v.integer("quick_slides_per_plate", cfg.get("quick_slides_per_plate", 2), 2, slides)
    fidelity = v.one_of("fidelity", cfg.get("fidelity", "auto"), FIDELITIES)
    ideal = cfg.get("ideal", False)
    if not isinstance(ideal, bool):
        raise ConfigError(f"ideal must be true or false, got {ideal!r}")
    paper_stack = cfg.get("paper_stack", False)
    if not isinstance(paper_stack, bool):
        raise ConfigError(f"paper_stack must be true or false, got {paper_stack!r}")
    base = spec if spec is not None else get_sensor(sensor)
    finger = _finger(_table(cfg, "finger"), base)
    if paper_stack:
        if spec is not None:
            raise ConfigError(
                "paper_stack = true takes a preset sensor's paper stack; a sensor file "
                "gives its own ([pad.stack])"
            )
        if finger is not None:
            raise ConfigError("paper_stack = true and [finger] both set the skin; give one")
        finger = base.with_paper_stack().finger
    rig = None
    if "rig" in cfg:
        try:
            rig = ProbeRig.from_json(_table(cfg, "rig"))
        except TypeError as exc:
            raise ConfigError(f"rig: {exc}") from None
    ss = SlideSet(
        plates=tuple(plates),
        sensor=sensor,
        protocol=_protocol(_table(cfg, "protocol"), _table(cfg, "randomise")),
        slides=slides,
        quick_slides=quick,
        fidelity=fidelity,
        ideal=ideal,
        finger=finger,
        rig=rig,
        sensor_spec=spec,
        pitch_m=_number(cfg, "pitch_m"),
        dt_s=_number(cfg, "dt_s"),
        options=StepOptions.from_table({k.name: cfg[k.name] for k in KNOBS if k.name in cfg}),
    )
    return ss, seed, name


def _number(cfg: dict, key: str) -> float | None:
    """The number ``cfg[key]`` (None where absent); its range is the slide set's to check."""
    if key not in cfg:
        return None
    x = cfg[key]
    if not _is_number(x):
        raise ConfigError(f"{key} must be a number ({TOP_KEYS[key]}), got {x!r}")
    return float(x)


def _beside(value: str, base_dir: Path | None) -> Path:
    """A file the configuration names: relative paths are relative to its folder."""
    path = Path(value)
    return base_dir / path if not path.is_absolute() and base_dir is not None else path


def _plate(value, base_dir: Path | None) -> str:
    """A preset plate's name, a plate file's absolute path (``.toml``, relative to the
    configuration file's folder), or the reference of a user's part or height map
    (:mod:`~sim_tactile.plates.parts.user`: a string, or a table with its ``file`` and options)
    with its path made absolute, checked (a script runs here, once)."""
    opts = {}
    if isinstance(value, dict):
        opts = dict(value)
        value = opts.pop("file", None)
        if not isinstance(value, str) or not is_user_plate(value):
            raise ConfigError(
                f"a plate table needs file = a part or height map (.step, .stp, .stl, .py, "
                f".npy, .png), got {value!r}"
            )
    if not isinstance(value, str):
        raise ConfigError(f"a plate must be a name, a file or a table, got {value!r}")
    if is_user_plate(value):
        src = parse_ref(value, **opts)
        value = replace(src, path=str(_beside(src.path, base_dir).resolve())).ref()
        get_plate(value)  # it must load
        return value
    if value.lower().endswith(".toml"):
        path = _beside(value, base_dir).resolve()
        get_plate(str(path))  # it must read
        return str(path)
    if value not in preset_names():
        raise ConfigError(
            f"plate {value!r} is not a preset{did_you_mean(value, preset_names())}; valid: "
            f"{', '.join(preset_names())}, a plate "
            "file (.toml), a part (.step, .stp, .stl, .py[:function]) or a height map (.npy, .png)"
        )
    return value


def _sensor(value, base_dir: Path | None):
    """``(name, definition)`` of the configuration's ``sensor``: a preset's name (definition
    None), or a sensor file (``.toml``, relative to the configuration file's folder)."""
    if isinstance(value, str) and value.lower().endswith(".toml"):
        spec = load_sensor_file(_beside(value, base_dir))
        return spec.name, spec
    return v.one_of("sensor", value, [*sensor_names(), "<a sensor file>.toml"]), None


def _table(cfg: dict, key: str) -> dict:
    t = cfg.get(key, {})
    if not isinstance(t, dict):
        raise ConfigError(f"{key} must be a table, got {t!r}")
    return t


def _is_number(x: object) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _protocol(proto_t: dict, rand_t: dict) -> Protocol:
    names = [f.name for f in fields(Protocol) if f.name not in RANDOMISE]
    if set(proto_t) & set(RANDOMISE):
        bad = ", ".join(sorted(set(proto_t) & set(RANDOMISE)))
        raise ConfigError(f"protocol.{bad}: put the jitters under [randomise]")
    v.known_keys("", proto_t, names, prefix="protocol.")
    v.known_keys("", rand_t, RANDOMISE, prefix="randomise.")
    for sect, t in (("protocol", proto_t), ("randomise", rand_t)):
        for k, val in t.items():
            if k in ("force_control", "start"):
                ok, kind = isinstance(val, str), "string"
            elif k == "return_stroke":
                ok, kind = isinstance(val, bool), "boolean"
            else:
                ok, kind = _is_number(val), "number"
            if not ok:
                raise ConfigError(f"{sect}.{k} must be a {kind}, got {val!r}")
    try:
        proto = Protocol(**proto_t, **rand_t)
    except ConfigError as exc:
        sect = "randomise" if str(exc).split(" ")[0] in RANDOMISE else "protocol"
        raise ConfigError(f"{sect}.{exc}") from None
    if proto.speed_m_s == 0 and proto.duration_s is None:
        raise ConfigError("protocol.speed_m_s = 0 needs a protocol.duration_s")
    return proto


def _finger(finger_t: dict, base) -> Finger | None:
    """The sensor ``base``'s pad with the fields of ``[finger]`` changed (None: no change)."""
    if not finger_t:
        return None
    v.known_keys("", finger_t, [f.name for f in fields(base.finger)], prefix="finger.")
    kw = {k: tuple(x) if isinstance(x, list) else x for k, x in finger_t.items()}
    try:
        f = replace(base.finger, **kw)
    except TypeError as exc:
        raise ConfigError(f"finger: {exc}") from None
    check_pad(base.layout, f)
    return f
