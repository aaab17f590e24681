"""A sensor written as a sensor file's data, and re-created from what a data set recorded
(the inverse of :func:`~.files.sensor_from_data`, and of :meth:`~.sensor.Sensor.to_json`)."""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

import numpy as np

from ..toml_text import write_file
from .files import FORMAT, TRANSDUCERS, sensor_from_data
from .layouts import Layout, grid_layout, overlapping_taxels


def sensor_to_data(sensor) -> dict:
    """A sensor as a sensor file's data (:func:`sensor_from_data` reads it back equal)."""
    lay = sensor.layout
    d: dict = {"format": FORMAT, "name": sensor.name, "rate_hz": float(lay.rate_hz)}
    d["layout"] = _layout_data(lay)
    pad = sensor.finger.to_json()
    pad = {k: (list(x) if isinstance(x, tuple) else x) for k, x in pad.items()}
    if sensor.finger.stack is not None:
        for k in ("thickness_m", "young_pa", "poisson"):
            pad.pop(k)  # the stack's
    d["pad"] = pad
    tr = sensor.transducer
    if tr is None:
        d["transducer"] = {"kind": "ideal"}
    elif isinstance(tr, tuple):
        d["transducer"] = [_transducer_data(x) for x in tr]
    else:
        d["transducer"] = _transducer_data(tr)
    if sensor.imperfections is not None:
        imp = sensor.imperfections.to_json()
        d["imperfections"] = {k: (list(x) if isinstance(x, tuple) else x) for k, x in imp.items()}
    return d


def sensor_from_record(d: dict):
    """The sensor a data set recorded (:meth:`~sim_tactile.sensors.Sensor.to_json`, kept
    under ``sensor_definition`` in its setup): the sensor re-created without its file."""
    lay = d["layout"]
    pos = np.asarray(lay["positions_m"], dtype=float)
    layout = {
        "x_m": pos[:, 0].tolist(),
        "y_m": pos[:, 1].tolist(),
        "depth_m": [float(-z) if z != 0 else 0.0 for z in pos[:, 2]],
        "size_m": lay["sizes_m"],
        "layer": lay["layer"],
        "names": lay["names"],
        "overlap": True,  # the record was checked when its data set was made
    }
    if lay.get("grid_shape") is not None:
        layout["grid_shape"] = lay["grid_shape"]
    pad = dict(d["pad"])
    if pad.get("stack") is not None:
        for k in ("thickness_m", "young_pa", "poisson"):
            pad.pop(k, None)
    data = {
        "format": FORMAT,
        "name": d["name"],
        "rate_hz": lay["rate_hz"],
        "layout": layout,
        "pad": pad,
    }
    tr = d["transducer"]
    if tr == "ideal":
        data["transducer"] = {"kind": "ideal"}
    else:
        kinds = {c.__name__: k for k, c in TRANSDUCERS.items()}
        trs = [
            {"kind": kinds[t["kind"]], **{k: x for k, x in t.items() if k not in ("kind", "units")}}
            for t in tr["transducer"]
        ]
        data["transducer"] = trs[0] if len(trs) == 1 else trs
        if tr.get("imperfections") is not None:
            data["imperfections"] = {k: x for k, x in tr["imperfections"].items() if x is not None}
    return sensor_from_data(data, where=f"the recorded sensor {d['name']!r}")


def write_sensor_file(sensor, path: str | Path, header: str = "") -> Path:
    """Write ``sensor`` as a sensor file (to a temporary name first: a failed write leaves
    nothing half written)."""
    return write_file(sensor_to_data(sensor), path, "sensor file", header)


def _layout_data(lay: Layout) -> dict:
    over = {"overlap": True} if overlapping_taxels(lay) is not None else {}
    grid = _as_grid(lay)
    if grid is not None:
        return {"grid": grid, **over}
    depth = [float(-z) if z != 0 else 0.0 for z in lay.positions[:, 2]]
    sizes = lay.sizes.tolist()
    d = {
        "x_m": lay.positions[:, 0].tolist(),
        "y_m": lay.positions[:, 1].tolist(),
        "depth_m": depth[0] if len(set(depth)) == 1 else depth,
        "size_m": [sizes[0]] if all(s == sizes[0] for s in sizes) else sizes,
        "layer": int(lay.layer[0]) if len(set(lay.layer.tolist())) == 1 else lay.layer.tolist(),
        "names": list(lay.names),
    }
    if lay.grid_shape is not None:
        d["grid_shape"] = list(lay.grid_shape)
    return {**d, **over}


def _as_grid(lay: Layout) -> dict | None:
    """The ``[layout.grid]`` that generates ``lay`` exactly, or None."""
    if lay.grid_shape is None or len(set(lay.sizes.ravel().tolist())) != 1:
        return None
    rows, cols = lay.grid_shape
    pitch = float(lay.positions[1, 0] - lay.positions[0, 0]) if cols > 1 else None
    if pitch is None and rows > 1:
        pitch = float(lay.positions[cols, 1] - lay.positions[0, 1])
    if pitch is None or not pitch > 0:
        return None
    g = {
        "rows": rows,
        "cols": cols,
        "pitch_m": pitch,
        "size_m": float(lay.sizes[0, 0]),
        "depth_m": float(-lay.positions[0, 2]) if lay.positions[0, 2] != 0 else 0.0,
    }
    made = grid_layout(
        lay.name, cols, rows, pitch, g["size_m"], depth_m=g["depth_m"], rate_hz=lay.rate_hz
    )
    same = (
        made.positions.tobytes() == lay.positions.tobytes()
        and made.sizes.tobytes() == lay.sizes.tobytes()
        and made.layer.tobytes() == lay.layer.tobytes()
        and made.names == lay.names
    )
    return g if same else None


def _transducer_data(t) -> dict:
    kind = {c: k for k, c in TRANSDUCERS.items()}[type(t)]
    d = {"kind": kind}
    for f in fields(t):
        if f.name != "units":
            x = getattr(t, f.name)
            d[f.name] = list(x) if isinstance(x, tuple) else x
    return d
