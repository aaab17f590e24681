"""The closed forms a slide is checked against: the pulse period of a grating under the
probe taxel (feature spacing over the pad's speed), and where a slide's steady part lies."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..plates import Plate
from ..records import Recording
from ..sensors import Finger, Layout
from ..sim.plan.protocol import SPEED_RAMP_S, START_MARGIN_M


def probe_taxel(layout: Layout) -> int:
    """The shallowest taxel nearest the pad's centre (ties: the first)."""
    depth = layout.depth_m
    cand = np.flatnonzero(np.isclose(depth, depth.min()))
    r = np.hypot(layout.positions[cand, 0], layout.positions[cand, 1])
    return int(cand[np.argmin(r)])


def pulse_period(
    rec: Recording,
    taxel: int,
    area_length_m: float,
    spacing_m: float,
    speed_m_s: float,
    pad_length_m: float,
    *,
    x_m: np.ndarray | None = None,
) -> dict:
    """Measure the period of ``taxel``'s signal while the whole pad is over the texture: the
    one estimator of a texture's temporal period (the grating law's check in the benchmarks
    and the tests).

    ``area_length_m``: the textured area's length along the slide; ``x_m`` (T,): where the
    pad's centre is over the plate at each sample [m] (default: the recording's
    ``x_pad_m``; the probe rig's ``x_probe_m``, where the texture moves over the sensor).

    The closed form holds in the steady state: while the pad (``pad_length_m`` along the
    slide) is entering or leaving the textured area its contact patch changes, and so does
    the signal's apparent period (by up to 4% here). The signal is detrended by
    ``(I - M)^2``, M a moving average over one nominal period ``spacing / speed`` (M removes
    the periodic part, so this keeps it and takes out trends up to quadratic); over the
    steady window a periodic model, a line plus ``K <= 3`` harmonics evaluated at the sample
    times (harmonics that the sensor's rate aliases are modelled as aliased), is fitted by
    least squares for each period in [0.8, 1.25] x nominal, and the best period refined.

    Returns ``{period_s, periods, ripple, pad_speed_m_s}``: ``periods`` is the steady
    window's length in periods, ``ripple`` the peak-to-peak of the fitted periodic part over
    the largest signal in the window (a weak ripple makes a weak check), ``pad_speed_m_s`` the
    pad's mean speed over the window. ``period_s`` is None, with a ``reason``, when the window
    holds fewer than 2 periods or the rate gives fewer than 3 samples per period.
    """
    from scipy import optimize

    rate = float(rec.meta["rate_hz"])
    t = np.asarray(rec.times, float)
    x_pad = np.asarray(rec.meta["x_pad_m"] if x_m is None else x_m, float)
    y = np.asarray(rec.data[:, taxel], float)
    steady = np.abs(x_pad) <= area_length_m / 2 - pad_length_m / 2
    out: dict = {"period_s": None, "periods": 0.0, "ripple": None, "pad_speed_m_s": None}
    if steady.sum() >= 2:
        out["pad_speed_m_s"] = float(np.polyfit(t[steady], x_pad[steady], 1)[0])
    nominal = spacing_m / speed_m_s
    per = nominal * rate  # samples per period
    if per < 3:
        out["reason"] = f"{rate:g} Hz gives {per:.1f} samples per period; at least 3 are needed"
        return out
    n_win = round(per)
    r = y - ndimage.uniform_filter1d(y, n_win, mode="nearest")
    r = r - ndimage.uniform_filter1d(r, n_win, mode="nearest")
    tt, rr = t[steady], r[steady]
    span = float(tt[-1] - tt[0]) if tt.size else 0.0
    out["periods"] = span / nominal
    if span < 2 * nominal:
        out["reason"] = (
            f"the whole pad is over the texture for {span / nominal:.1f} periods; 2 are needed"
        )
        return out
    tc = tt - tt.mean()
    n_harm = max(1, min(3, int(per // 2)))

    def design(period: float) -> np.ndarray:
        cols = [np.ones_like(tc), tc]
        for k in range(1, n_harm + 1):
            w = 2 * np.pi * k / period
            cols += [np.cos(w * tc), np.sin(w * tc)]
        return np.column_stack(cols)

    def sse(period: float) -> float:
        a = design(period)
        coef = np.linalg.lstsq(a, rr, rcond=1e-10)[0]
        return float(np.sum((rr - a @ coef) ** 2))

    grid = np.linspace(0.8 * nominal, 1.25 * nominal, 451)
    k = int(np.argmin([sse(p) for p in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    best = float(optimize.minimize_scalar(sse, bounds=(lo, hi), method="bounded").x)
    a = design(best)
    fit = a[:, 2:] @ np.linalg.lstsq(a, rr, rcond=1e-10)[0][2:]
    top = float(np.max(np.abs(y[steady])))
    out["period_s"] = best
    out["ripple"] = float(np.ptp(fit) / top) if top > 0 else None
    return out


def quick_duration(
    plate: Plate, finger: Finger, speed: float, spacing: float | None, n_periods: int
) -> float | None:
    """Slide time [s] until the pad has spent ``n_periods`` feature spacings (and half one
    more) wholly over the texture; None when that is the whole crossing or no spacing."""
    if spacing is None:
        return None
    px = finger.patch_m[0]
    half = plate.area_length_m / 2
    x_start = -(half + px / 2 + START_MARGIN_M)
    steady_lo, steady_hi = -(half - px / 2), half - px / 2
    target = min(steady_lo + (n_periods + 0.5) * spacing, steady_hi + spacing / 2)
    t = (target - x_start) / speed + SPEED_RAMP_S
    full = 2 * abs(x_start) / speed
    return None if t >= full else float(t)
