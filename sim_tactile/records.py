"""Frozen record types passed between the stages, in SI units.

:class:`Recording` is one simulated (or measured) slide: a (time x taxel) array with its
times, the taxel positions and full metadata. It saves to and loads from ``.npz`` without
loss and without pickle (metadata is stored as JSON text).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import ConfigError

#: Keys every Recording .npz holds.
NPZ_KEYS = ("data", "times", "taxels", "meta_json")


@dataclass(frozen=True)
class Recording:
    """One slide.

    data: (T, N) float32, the transducer output per taxel (``units``; N for ideal loads).
    times: (T,) float64 [s], sample times (the centre of each averaging window).
    taxels: (N, 3) float64 [m], taxel centres in the pad frame (x along the slide, z out
    of the skin; a taxel under the surface has z < 0).
    units: unit of ``data`` (e.g. "N").
    meta: JSON-able metadata: configuration, versions, seed, fidelity, timings, warnings.
    """

    data: np.ndarray
    times: np.ndarray
    taxels: np.ndarray
    units: str = "N"
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        data = np.asarray(self.data, dtype=np.float32)
        times = np.asarray(self.times, dtype=np.float64)
        taxels = np.asarray(self.taxels, dtype=np.float64)
        if data.ndim != 2 or times.shape != (data.shape[0],) or taxels.shape != (data.shape[1], 3):
            raise ConfigError(
                f"recording shapes do not agree: data {data.shape}, times {times.shape}, "
                f"taxels {taxels.shape}; valid: (T, N), (T,), (N, 3)"
            )
        try:  # metadata is JSON data; normalise it (tuples -> lists) so a round trip is exact
            object.__setattr__(self, "meta", json.loads(json.dumps(self.meta)))
        except (TypeError, ValueError) as exc:
            raise ConfigError(f"recording metadata must be JSON data: {exc}") from None
        for name, arr in (("data", data), ("times", times), ("taxels", taxels)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def rate_hz(self) -> float:
        return float(
            self.meta.get(
                "rate_hz", 1.0 / np.median(np.diff(self.times)) if len(self.times) > 1 else 0.0
            )
        )

    @property
    def n_taxels(self) -> int:
        return int(self.data.shape[1])

    def save(self, path: str | Path) -> Path:
        """Write an .npz (atomically) with ``data``, ``times``, ``taxels`` and ``meta_json``."""
        import io

        from .cache import atomic_write

        buf = io.BytesIO()
        meta = dict(self.meta, units=self.units)
        np.savez(
            buf,
            data=self.data,
            times=self.times,
            taxels=self.taxels,
            meta_json=np.array(json.dumps(meta, sort_keys=True)),
        )
        path = Path(path)
        atomic_write(path, buf.getvalue())
        return path

    @classmethod
    def load(cls, path: str | Path) -> Recording:
        """Read an .npz written by :meth:`save` (no pickle)."""
        path = Path(path)
        if not path.is_file():
            raise ConfigError(f"recording file {str(path)!r} does not exist")
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in NPZ_KEYS if k not in z.files]
            if missing:
                raise ConfigError(f"{path} is not a sim_tactile recording: missing {missing}")
            meta = json.loads(str(z["meta_json"]))
            return cls(z["data"], z["times"], z["taxels"], units=meta.pop("units", "N"), meta=meta)
