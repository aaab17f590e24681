"""A tactile sensor: its taxels (the layout, with the hardware's rate), the pad that carries
them, the transducer from load to output and its imperfections."""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from ..errors import ConfigError
from .layouts import Layout
from .pad import Finger
from .transducers import Imperfections, Transducer


@dataclass(frozen=True)
class Sensor:
    """A tactile sensor: its taxels (``layout``, with the hardware's rate), the pad that
    carries them (``finger``), the transducer from load to output (one per layer, or None
    for a bare layout that reports the ideal normal load [N]) and its imperfections."""

    name: str
    layout: Layout
    finger: Finger
    transducer: Transducer | tuple[Transducer, ...] | None
    imperfections: Imperfections | None = None

    @classmethod
    def bare(cls, layout: Layout, finger: Finger | None = None) -> Sensor:
        """Taxels without hardware: the ideal normal loads [N] on a default pad."""
        return cls(layout.name, layout, finger or Finger(), None, None)

    @property
    def rate_hz(self) -> float:
        return self.layout.rate_hz

    def with_paper_stack(self) -> Sensor:
        """This preset with the skin its paper describes (layers on their backing, from
        :mod:`~sim_tactile.sensors.paper_stacks`, most numbers assumptions) instead of the
        half-space."""
        from .paper_stacks import paper_stack

        return replace(self, finger=self.finger.layered(paper_stack(self.name).stack()))

    @property
    def grid_shape(self) -> tuple[int, int] | None:
        return self.layout.grid_shape

    def transduce(
        self, loads_n: np.ndarray, rate_hz: float, rng: np.random.Generator
    ) -> np.ndarray:
        """(T, N) ideal loads [N] -> (T, N) hardware output, with seeded imperfections."""
        layout = self.layout
        tr = self.transducer
        if tr is None:
            return loads_n
        if isinstance(tr, tuple):  # one transducer per layer
            out = np.empty(loads_n.shape)
            for lay, t in enumerate(tr):
                cols = layout.layer == lay
                out[:, cols] = t.apply(loads_n[:, cols], rate_hz)
        else:
            out = tr.apply(loads_n, rate_hz)
        if self.imperfections is None:
            return out
        return self.imperfections.apply(out, layout.positions, rate_hz, rng)

    @property
    def transducers(self) -> tuple:
        """The transducers: one per layer, one for every taxel, or none (a bare layout's ideal
        loads)."""
        tr = self.transducer
        if tr is None:
            return ()
        return tr if isinstance(tr, tuple) else (tr,)

    @property
    def units(self) -> str:
        trs = self.transducers
        return trs[0].units if trs else "N"

    def transducer_json(self) -> dict | str:
        """The transducer and imperfections as JSON data ("ideal" for a bare layout)."""
        if self.transducer is None:
            return "ideal"
        trs = [asdict(t) | {"kind": type(t).__name__} for t in self.transducers]
        imp = self.imperfections.to_json() if self.imperfections is not None else None
        return {"name": self.name, "transducer": trs, "imperfections": imp}

    def to_json(self) -> dict:
        """The whole definition as JSON data: everything a recording of it depends on."""
        return {
            "name": self.name,
            "layout": self.layout.to_json(),
            "pad": self.finger.to_json(),
            "transducer": self.transducer_json(),
        }


def check_pad(layout: Layout, finger: Finger) -> None:
    """Raise a ConfigError unless ``finger``'s pad carries every taxel of ``layout``: each
    taxel's footprint within the pad's patch in x and y (``|x| + size / 2 <= patch / 2``)
    and its depth within the skin (``0 <= depth <= thickness_m``). The error names the
    taxel furthest out, its value and the valid range."""
    pos, half = layout.positions, layout.sizes / 2
    reach = np.abs(pos[:, :2]) + half  # (N, 2) [m]
    for axis, key in ((0, "x_m"), (1, "y_m")):
        lim = finger.patch_m[axis] / 2
        out = np.flatnonzero(reach[:, axis] > lim + 1e-9)
        if out.size:
            k = int(out[np.argmax(reach[out, axis])])
            raise ConfigError(
                f"taxel {k} ({layout.names[k]!r}) of the {layout.name} layout lies beyond the "
                f"pad: {key} = {pos[k, axis]:g} m, its {2 * half[k, axis]:g} m footprint "
                f"reaching {reach[k, axis]:g} m from the pad's centre; valid: |{key}| + size/2 "
                f"<= {lim:g} m, the pad's half-patch ({out.size} taxel(s) beyond it: the pad "
                f"is smaller than the {layout.name} layout)"
            )
    depth = layout.depth_m
    out = np.flatnonzero(depth > finger.thickness_m * (1 + 1e-9))
    if out.size:
        k = int(out[np.argmax(depth[out])])
        raise ConfigError(
            f"taxel {k} ({layout.names[k]!r}) of the {layout.name} layout lies below the "
            f"skin: depth_m = {depth[k]:g} m; valid: 0 <= depth_m <= {finger.thickness_m:g} m, "
            f"the pad's thickness_m ({out.size} taxel(s) below it)"
        )
