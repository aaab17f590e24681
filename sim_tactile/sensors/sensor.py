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
    def units(self) -> str:
        tr = self.transducer
        if tr is None:
            return "N"
        return (tr[0] if isinstance(tr, tuple) else tr).units

    def transducer_json(self) -> dict | str:
        """The transducer and imperfections as JSON data ("ideal" for a bare layout)."""
        tr = self.transducer
        if tr is None:
            return "ideal"
        trs = [
            asdict(t) | {"kind": type(t).__name__} for t in (tr if isinstance(tr, tuple) else (tr,))
        ]
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
    """Raise a ConfigError unless ``finger``'s pad carries every taxel of ``layout``."""
    ex, ey = layout.extent_m
    px, py = finger.patch_m
    if ex > px / 2 + 1e-9 or ey > py / 2 + 1e-9:
        raise ConfigError(
            f"the {layout.name} layout spans +-({ex:g}, {ey:g}) m, beyond the pad's "
            f"+-({px / 2:g}, {py / 2:g}) m: the pad is smaller than the {layout.name} layout; "
            "valid: a pad that carries the taxels"
        )
