"""Sensors as files: a sensor's whole definition in TOML, read as data (no code runs).

::

    format = 1                  # optional; this reader reads format 1
    name = "my4x4"              # optional: the file's name without .toml
    base = "grid3x3"            # optional: start from a preset and change what follows
    rate_hz = 200.0             # the hardware's sampling rate [Hz]

    [layout.grid]               # a grid of square taxels centred on the pad (row-major)
    rows = 4
    cols = 4
    pitch_m = 2.5e-3
    size_m = 2.0e-3
    depth_m = 0.0               # optional: under the surface

    # or the taxels one by one, as columns (one entry per taxel, or one for all):
    # [layout]
    # x_m = [...]               # along the slide
    # y_m = [...]               # across it
    # depth_m = 0.0             # or [...]
    # size_m = 2.0e-3           # a square; [[sx, sy], ...] one per taxel; [[sx, sy]] for all
    # layer = 0                 # or [...]: the layer of each (one transducer per layer)
    # names = ["a", "b", ...]   # optional channel names
    # grid_shape = [rows, cols] # optional: the taxels form this grid in channel order
    # overlap = true            # optional: taxels of one layer may overlap (refused else)

    [pad]                       # sensors.pad.Finger: shape ("flat", "sphere", "ellipsoid"),
    shape = "flat"              # size_m, edge_radius_m, radius_m, radii_m, thickness_m,
    size_m = [0.012, 0.012]     # young_pa, poisson, bone_mass_kg, friction, skin_tractions

    [pad.stack]                 # optional: the skin's bonded layers, from the surface down
    backing = "rigid"           # or "halfspace" (with backing_young_pa, backing_poisson)
    [[pad.stack.layers]]
    thickness_m = 1e-3
    young_pa = 0.5e6
    poisson = 0.45

    [transducer]                # kind: piezoresistive, capacitive, impedance, piezoelectric,
    kind = "piezoresistive"     # or ideal (the loads in N); then the kind's parameters.
                                # [[transducer]] tables: one per layer, in layer order
    [imperfections]             # sensors.transducers.Imperfections: noise_std, quant_step,
    noise_std = 5e-3            # drift_std_per_sqrt_s, crosstalk, ...

With a ``base``, ``[layout]`` replaces the base's taxels whole; ``[pad]``, ``[imperfections]``
and a ``[transducer]`` without a ``kind`` change the base's fields one by one, and
``[pad.stack]`` or a ``[transducer]`` with a ``kind`` replace the base's. Every value is
checked before anything runs; an error names the file, the key, the value and the valid
range. Taxels of one layer must not overlap (their footprints may touch) unless
``[layout]`` says ``overlap = true`` (beside ``[layout.grid]`` too). Every taxel must lie on the pad: its footprint within the pad's patch in x and y,
its depth within the skin's thickness (:func:`~.sensor.check_pad` names the one that does
not). :func:`~.file_data.sensor_to_data` writes a sensor in this form (the presets' files in
the project's ``assets/sensors`` are written so), and a data set records it, so that its
sensor can be re-created without the file (:func:`~.file_data.sensor_from_record`).
"""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

import numpy as np

from .. import _validate as v
from ..errors import ConfigError
from ..toml_text import read_file
from .layouts import Layout, grid_layout, overlap_text, overlapping_taxels
from .pad import Finger
from .presets import PRESETS, preset_data, preset_file
from .sensor import Sensor, check_pad
from .stack import Stack
from .transducers import Capacitive, Impedance, Imperfections, Piezoelectric, PiezoResistive

#: The file format this module reads and writes.
FORMAT = 1
#: Most taxels a sensor file may define: a 64 x 64 array, as dense as tactile arrays come;
#: every slide records rate x duration x taxels samples (4096 taxels at 1 kHz for 2 s are
#: 65 MB of float64), and the encoders and classifiers scale with the channels.
MAX_TAXELS = 4096
#: Two taxels of one layer closer than this are at one point [m] (a nanometre).
SAME_POINT_M = 1e-9
TOP_KEYS = (
    "format",
    "name",
    "base",
    "description",
    "rate_hz",
    "layout",
    "pad",
    "transducer",
    "imperfections",
)
LAYOUT_KEYS = (
    "x_m",
    "y_m",
    "depth_m",
    "size_m",
    "layer",
    "names",
    "grid_shape",
    "grid",
    "overlap",
)
GRID_KEYS = ("rows", "cols", "pitch_m", "size_m", "depth_m")
TRANSDUCERS = {
    "piezoresistive": PiezoResistive,
    "capacitive": Capacitive,
    "impedance": Impedance,
    "piezoelectric": Piezoelectric,
}


def load_sensor_file(path: str | Path):
    """The :class:`~sim_tactile.sensors.Sensor` of a sensor file (TOML), every value checked."""
    data = read_file(path, "sensor file")
    return sensor_from_data(data, default_name=Path(path).stem, where=f"sensor file {str(path)!r}")


def sensor_from_data(data: dict, default_name: str = "sensor", where: str = "sensor"):
    """A :class:`~sim_tactile.sensors.Sensor` from a sensor file's data (see the module)."""
    try:
        return _sensor(data, default_name)
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _sensor(data: dict, default_name: str):
    _known("", data, TOP_KEYS)
    fmt = data.get("format", FORMAT)
    if fmt != FORMAT:
        raise ConfigError(f"format = {fmt!r} is not valid; valid: {FORMAT}")
    name = _string("name", data.get("name", default_name))
    if "description" in data:
        _string("description", data["description"])
    base = None
    if "base" in data:
        name_ = v.one_of("base", data["base"], PRESETS)
        base = sensor_from_data(
            preset_data(name_), where=f"preset sensor file {preset_file(name_)}"
        )
    if base is None:
        for key in ("layout", "pad", "transducer"):
            if key not in data:
                raise ConfigError(f"{key} is missing; valid: a [{key}] table, or a base preset")
    rate = v.positive("rate_hz", data["rate_hz"], unit="Hz") if "rate_hz" in data else None
    if rate is None and base is None:
        raise ConfigError("rate_hz is missing; valid: the sampling rate in Hz, or a base preset")
    rate = base.layout.rate_hz if rate is None else rate
    layout = (
        _layout(_table("layout", data["layout"]), name, rate)
        if "layout" in data
        else _renamed(base.layout, name, rate)
    )
    finger = _pad(_table("pad", data.get("pad", {})), base.finger if base else None)
    tr = _transducers(data.get("transducer"), base.transducer if base else None, layout)
    imp = _imperfections(data.get("imperfections"), base.imperfections if base else None)
    check_pad(layout, finger)
    return Sensor(name, layout, finger, tr, imp)


# ------------------------------------------------------------------------------ sections
def _layout(t: dict, name: str, rate: float) -> Layout:
    _known("layout.", t, LAYOUT_KEYS)
    overlap = t.get("overlap", False)
    if not isinstance(overlap, bool):
        raise ConfigError(f"layout.overlap = {overlap!r} is not valid; valid: true or false")
    layout = _placed({k: x for k, x in t.items() if k != "overlap"}, name, rate)
    return layout if overlap else _apart(layout)


def _apart(layout: Layout) -> Layout:
    """``layout``, unless two taxels of one layer overlap (:func:`.layouts.overlapping_taxels`)."""
    pair = overlapping_taxels(layout)
    if pair is not None:
        raise ConfigError(
            f"layout: {overlap_text(layout, *pair)}; valid: footprints that do not overlap "
            "(they may touch): a pitch at least the taxel size, or overlap = true in [layout] "
            "where the taxels share the skin on purpose"
        )
    return layout


def _placed(t: dict, name: str, rate: float) -> Layout:
    if "grid" in t:
        extra = sorted(set(t) - {"grid"})
        if extra:
            raise ConfigError(
                f"layout.grid and layout.{extra[0]} both place taxels; valid: one of them"
            )
        g = _table("layout.grid", t["grid"])
        _known("layout.grid.", g, GRID_KEYS)
        for k in ("rows", "cols", "pitch_m", "size_m"):
            if k not in g:
                raise ConfigError(f"layout.grid.{k} is missing")
        rows = v.integer("layout.grid.rows", g["rows"], 1, 1000)
        cols = v.integer("layout.grid.cols", g["cols"], 1, 1000)
        _count("layout.grid.rows x layout.grid.cols", rows * cols)
        pitch = v.positive("layout.grid.pitch_m", g["pitch_m"], unit="m")
        size = v.positive("layout.grid.size_m", g["size_m"], unit="m")
        depth = v.non_negative("layout.grid.depth_m", g.get("depth_m", 0.0), unit="m")
        return _distinct(grid_layout(name, cols, rows, pitch, size, depth_m=depth, rate_hz=rate))
    for k in ("x_m", "y_m"):
        if k not in t:
            raise ConfigError(
                f"layout.{k} is missing; valid: a list of taxel positions [m], "
                "or a [layout.grid] table"
            )
    if isinstance(t["x_m"], list):
        _count("layout.x_m", len(t["x_m"]))
    x = _numbers("layout.x_m", t["x_m"])
    n = len(x)
    y = _numbers("layout.y_m", t["y_m"], n)
    depth = _per_taxel("layout.depth_m", t.get("depth_m", 0.0), n)
    for i, d in enumerate(depth):
        v.non_negative(f"layout.depth_m[{i}]", d, unit="m")
    sizes = _sizes(t.get("size_m"), n)
    layer = _per_taxel("layout.layer", t.get("layer", 0), n)
    for i, la in enumerate(layer):
        v.integer(f"layout.layer[{i}]", la, 0, 63)
    names = ()
    if "names" in t:
        names = t["names"]
        if not isinstance(names, list) or not all(isinstance(s, str) for s in names):
            raise ConfigError(f"layout.names must be a list of strings, got {names!r}")
        names = tuple(names)
    grid = None
    if "grid_shape" in t:
        gs = t["grid_shape"]
        if not isinstance(gs, list) or len(gs) != 2:
            raise ConfigError(f"layout.grid_shape must be [rows, cols], got {gs!r}")
        grid = (
            v.integer("layout.grid_shape[0]", gs[0], 1),
            v.integer("layout.grid_shape[1]", gs[1], 1),
        )
    # z = -depth (-0.0 at the surface, as grid_layout has it: the same bytes, the same keys)
    pos = np.column_stack([x, y, -np.asarray(depth, dtype=float)])
    return _distinct(Layout(name, pos, sizes, np.asarray(layer, dtype=int), rate, names, grid))


def _count(name: str, n: int) -> None:
    if n > MAX_TAXELS:
        raise ConfigError(f"{name}: {n} taxels; valid: at most {MAX_TAXELS}")


def _distinct(layout: Layout) -> Layout:
    """``layout``, unless two taxels of one layer lie at one point (within
    :data:`SAME_POINT_M`): they would read one load twice."""
    key = np.column_stack([np.round(layout.positions / SAME_POINT_M), layout.layer])
    order = np.lexsort(key.T[::-1])
    same = np.flatnonzero((np.diff(key[order], axis=0) == 0).all(axis=1))
    if len(same):
        i, j = sorted((int(order[same[0]]), int(order[same[0] + 1])))
        x, y, z = layout.positions[i] * 1e3
        raise ConfigError(
            f"layout: taxels {i} ({layout.names[i]}) and {j} ({layout.names[j]}) of layer "
            f"{int(layout.layer[i])} lie at one point (x = {x:.6g} mm, y = {y:.6g} mm, depth "
            f"{-z + 0.0:.6g} mm); valid: one taxel a point in each layer"
        )
    return layout


def _renamed(layout: Layout, name: str, rate: float) -> Layout:
    from dataclasses import replace

    return replace(layout, name=name, rate_hz=rate)


def _sizes(value, n: int) -> np.ndarray:
    if value is None:
        raise ConfigError("layout.size_m is missing; valid: a taxel side [m], or [[sx, sy], ...]")
    if _is_number(value):
        s = v.positive("layout.size_m", value, unit="m")
        return np.full((n, 2), s)
    if not isinstance(value, list) or len(value) not in (1, n):
        raise ConfigError(
            f"layout.size_m must be a number, or a list of 1 or {n} sizes (one per taxel), "
            f"got {value!r}"
        )
    out = np.empty((len(value), 2))
    for i, s in enumerate(value):
        if _is_number(s):
            out[i] = v.positive(f"layout.size_m[{i}]", s, unit="m")
        elif isinstance(s, list) and len(s) == 2:
            out[i] = [v.positive(f"layout.size_m[{i}][{k}]", s[k], unit="m") for k in (0, 1)]
        else:
            raise ConfigError(f"layout.size_m[{i}] must be a side or [sx, sy] in m, got {s!r}")
    return np.broadcast_to(out, (n, 2)).copy()


def _pad(t: dict, base: Finger | None) -> Finger:
    names = [f.name for f in fields(Finger)]
    _known("pad.", t, names)
    kw = {k: tuple(x) if isinstance(x, list) else x for k, x in t.items() if k != "stack"}
    for k, x in kw.items():
        if isinstance(x, dict):
            raise ConfigError(f"pad.{k} must be a value, got a table")
    stack = None
    if "stack" in t:
        st = _table("pad.stack", t["stack"])
        _known("pad.stack.", st, ("layers", "backing", "backing_young_pa", "backing_poisson"))
        layers = st.get("layers")
        if not isinstance(layers, list) or not all(isinstance(la, dict) for la in layers):
            raise ConfigError("pad.stack.layers must be [[pad.stack.layers]] tables, one a layer")
        for i, la in enumerate(layers):
            _known(f"pad.stack.layers[{i}].", la, ("thickness_m", "young_pa", "poisson"))
        stack = _checked("pad.stack.", "stack.", lambda: Stack.from_json(st))
        for k in ("thickness_m", "young_pa", "poisson"):
            if k in kw:
                raise ConfigError(
                    f"pad.{k} and pad.stack both set the skin; valid: one of them (with a "
                    "stack, the pad's thickness and modulus are the stack's)"
                )
    from dataclasses import replace

    def build() -> Finger:
        f = replace(base, **kw) if base is not None else Finger(**kw)
        return f.layered(stack) if stack is not None else f

    try:
        return _checked("pad.", "finger.", build)
    except TypeError as exc:
        raise ConfigError(f"pad: {exc}") from None


def _transducers(t, base, layout: Layout):
    if t is None:
        return base
    if isinstance(t, list):
        if not all(isinstance(x, dict) for x in t):
            raise ConfigError("transducer must be a table, or [[transducer]] tables, one a layer")
        n_layers = int(layout.layer.max()) + 1
        if len(t) != n_layers:
            raise ConfigError(
                f"{len(t)} [[transducer]] tables for {n_layers} layers; valid: one per layer"
            )
        return tuple(_transducer(x, None, f"transducer[{i}]") for i, x in enumerate(t))
    if not isinstance(t, dict):
        raise ConfigError(f"transducer must be a table, got {t!r}")
    if "kind" not in t and isinstance(base, tuple):
        raise ConfigError(
            "transducer without a kind changes the base's fields, but the base has one "
            "transducer per layer; valid: [[transducer]] tables, one per layer"
        )
    return _transducer(t, base, "transducer")


def _transducer(t: dict, base, where: str):
    from dataclasses import replace

    kind = t.get("kind")
    kw = {k: tuple(x) if isinstance(x, list) else x for k, x in t.items() if k != "kind"}
    if kind is None:
        if base is None:
            raise ConfigError(
                f"{where}.kind is missing; valid: {', '.join([*TRANSDUCERS, 'ideal'])}"
            )
        cls = type(base)
    else:
        kind = v.one_of(f"{where}.kind", kind, [*TRANSDUCERS, "ideal"])
        if kind == "ideal":
            if kw:
                raise ConfigError(
                    f"{where}: an ideal transducer takes no parameters, got {sorted(kw)}"
                )
            return None
        cls, base = TRANSDUCERS[kind], None
    names = [f.name for f in fields(cls) if f.name != "units"]
    _known(f"{where}.", kw, names)
    prefix = f"{cls.__name__.lower()}."
    try:
        return _checked(f"{where}.", prefix, lambda: replace(base, **kw) if base else cls(**kw))
    except TypeError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _imperfections(t, base: Imperfections | None) -> Imperfections | None:
    from dataclasses import replace

    if t is None:
        return base
    t = _table("imperfections", t)
    names = [f.name for f in fields(Imperfections)]
    _known("imperfections.", t, names)
    kw = {k: tuple(x) if isinstance(x, list) else x for k, x in t.items()}
    build = lambda: replace(base, **kw) if base is not None else Imperfections(**kw)  # noqa: E731
    try:
        return _checked("imperfections.", "", build)
    except TypeError as exc:
        raise ConfigError(f"imperfections: {exc}") from None


# ------------------------------------------------------------------------------ checks
def _checked(where: str, prefix: str, build):
    """``build()``, its ConfigError naming the key as the file does (``where``) where the
    class named it with ``prefix``."""
    try:
        return build()
    except ConfigError as exc:
        msg = str(exc)
        if prefix and msg.startswith(prefix):
            msg = where + msg[len(prefix) :]
        elif not prefix and not msg.startswith(where):
            msg = where + msg
        raise ConfigError(msg) from None


def _known(where: str, t: dict, names) -> None:
    v.known_keys("", t, names, prefix=where)


def _table(name: str, t) -> dict:
    if not isinstance(t, dict):
        raise ConfigError(f"{name} must be a table, got {t!r}")
    return t


def _string(name: str, x) -> str:
    if not isinstance(x, str) or not x:
        raise ConfigError(f"{name} must be a non-empty string, got {x!r}")
    return x


def _is_number(x) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _numbers(name: str, x, n: int | None = None) -> list[float]:
    if not isinstance(x, list) or not x or not all(_is_number(y) for y in x):
        raise ConfigError(f"{name} must be a non-empty list of numbers, got {x!r}")
    if n is not None and len(x) != n:
        raise ConfigError(f"{name} has {len(x)} entries; valid: one per taxel ({n})")
    return [v.finite(f"{name}[{i}]", y) for i, y in enumerate(x)]


def _per_taxel(name: str, x, n: int) -> list:
    if _is_number(x):
        return [x] * n
    if isinstance(x, list) and len(x) == n and all(_is_number(y) for y in x):
        return list(x)
    raise ConfigError(f"{name} must be a number or a list of {n} (one per taxel), got {x!r}")
