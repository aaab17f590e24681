"""Micro-roughness: the plate's roughness profile acting through the contact patch.

Ra of 0.4-50 um is far below any skin node or MuJoCo contact resolution (docs/physics.md), so the
finger simulation sees a roughness plate as nearly flat; this model adds the load that the
roughness profile z(x) puts on each taxel while it slides over it in contact.

Model (linear elasticity of the skin half-space, full contact assumed): a surface
undulation of wavenumber k and amplitude Z pressed flat by the skin needs a pressure
E* k Z / 2 (plane strain), whose vertical stress at depth d is damped by (1 + k d) exp(-k d).
A taxel of length s along the slide averages it with sinc(k s / 2), and the sensor's sample
period, over which the taxel travels v / rate, with sinc(k v / (2 rate)) (anti-aliasing). So
in the profile's Fourier domain

    p_micro(k) = E*/2 |k| (1 + |k| d) exp(-|k| d) sinc(k s / 2) sinc(k v / (2 rate)) Z(k)

and the taxel's extra load is p_micro at its position times its area, only while the taxel
carries load (in contact) and over the textured area. Limits: it assumes the skin stays in
contact in the valleys (true when the mean contact pressure exceeds the micro pressure; the
total load is clipped at zero where it does not), no friction-induced stick-slip, a lay
along y (the profile is constant across the slide), and a speed that is constant within a
slide.
"""

from __future__ import annotations

import numpy as np

from ..plates import Plate, surface_of


def micro_pressure_profile(
    plate: Plate, e_star_pa: float, depth_m: float, length_m: float, travel_per_sample_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """(x, p) the micro pressure [Pa] felt at depth ``depth_m`` by a taxel of length
    ``length_m`` along the slide, on the profile's grid x [m]."""
    x, z = surface_of(plate).profile
    n = len(x)
    m = 2 * n  # zero padding: the profile does not wrap around
    dx = x[1] - x[0]
    k = 2 * np.pi * np.fft.rfftfreq(m, d=dx)
    H = 0.5 * e_star_pa * k * (1 + k * depth_m) * np.exp(-k * depth_m)
    H *= np.sinc(k * length_m / (2 * np.pi)) * np.sinc(k * travel_per_sample_m / (2 * np.pi))
    p = np.fft.irfft(np.fft.rfft(z, n=m) * H, n=m)[:n]
    return x, p


def micro_loads(
    plate: Plate,
    layout,
    x_pad: np.ndarray,
    in_contact: np.ndarray,
    e_star_pa: float,
    rate_hz: float,
) -> np.ndarray:
    """(T, N) extra load [N] of the roughness on each taxel; zero for plates without one.

    x_pad: (T,) the pad centre's x in the plate frame at each sample [m]; in_contact: (T, N)
    bool, the taxel carries load.
    """
    T, N = in_contact.shape
    out = np.zeros((T, N))
    if surface_of(plate).profile is None or T < 2:
        return out
    travel = float(np.median(np.abs(np.diff(x_pad))))
    for i in range(N):
        sx, sy = layout.sizes[i]
        xg, p = micro_pressure_profile(
            plate, e_star_pa, float(layout.depth_m[i]), float(sx), travel
        )
        xt = x_pad + layout.positions[i, 0]
        out[:, i] = np.interp(xt, xg, p, left=0.0, right=0.0) * sx * sy * in_contact[:, i]
    return out
