"""The slide's speed command along its window's strokes (:class:`Strokes`), shared by the
per-step slide and the tabled one."""

from __future__ import annotations

from ..plan.protocol import SPEED_RAMP_S, SlideWindow


class Strokes:
    """The slide's speed command along the window's strokes: ramped at the start of each
    stroke, zero once the pad reaches the plate's end (``stopped_at_s``)."""

    def __init__(self, window: SlideWindow, speed_m_s: float, dt: float) -> None:
        self.w, self.speed, self.dt = window, speed_m_s, dt
        self.i = 0
        self.sign = window.strokes[0][2]
        self.t_stroke = 0.0
        self.t = 0.0
        self.stopped_at_s: float | None = None
        self.v = 0.0

    def command(self, x: float) -> float:
        """The speed command [m/s] for the pad at ``x`` (the plate frame) for the next step."""
        w = self.w
        if self.sign * (x - w.strokes[self.i][1]) >= 0 and self.i + 1 < len(w.strokes):
            self.i += 1
            self.sign = w.strokes[self.i][2]
            self.t_stroke = 0.0
        v = self.sign * self.speed * min(1.0, self.t_stroke / SPEED_RAMP_S)
        if self.sign * x >= w.x_limit_m:
            v = 0.0
            if self.stopped_at_s is None:
                self.stopped_at_s = self.t
        self.t += self.dt
        self.t_stroke += self.dt
        self.v = v
        return v
