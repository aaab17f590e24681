"""Signed distances of a point to the compiled collider's non-primitive plate geoms, in each
geom's frame: a drafted ridge (a box whose x-walls slope in) and a cylinder (but over an
upright one's footprint, the height above its top face, as the plate's height map has it)."""

from __future__ import annotations

import math

from ..._jit import njit


@njit
def _segment_distance(u, v, ax, az, bx, bz):
    """Distance from (u, v) to the segment from (ax, az) to (bx, bz)."""
    ex, ez = bx - ax, bz - az
    t = ((u - ax) * ex + (v - az) * ez) / (ex * ex + ez * ez)
    t = min(max(t, 0.0), 1.0)
    px, pz = u - ax - t * ex, v - az - t * ez
    return math.sqrt(px * px + pz * pz)


@njit
def ridge_distance(lx, ly, lz, hx, hy, hz, tx):
    """Signed distance from (lx, ly, lz) to a drafted ridge in its frame (centred at
    mid-height; its cross-section in x-z a trapezoid from half-width ``hx`` at ``lz = -hz`` to
    ``tx`` at ``lz = hz``, extruded over ``|ly| <= hy``), except over its footprint below its
    top surface, where it is the (negative) height above that surface: the height map's depth."""
    u = abs(lx)
    # the top surface's height over the footprint at u
    s = hz if u <= tx else hz - 2.0 * hz * (u - tx) / (hx - tx)
    if u <= hx and abs(ly) <= hy and lz <= s:
        return lz - s
    # the cross-section's signed distance: its three edges on the u >= 0 side
    db = math.sqrt(max(u - hx, 0.0) ** 2 + (lz + hz) ** 2)
    dt = math.sqrt(max(u - tx, 0.0) ** 2 + (lz - hz) ** 2)
    ds = _segment_distance(u, lz, hx, -hz, tx, hz)
    d2 = min(db, dt, ds)
    if abs(lz) <= hz and u <= hx + (tx - hx) * (lz + hz) / (2.0 * hz):
        d2 = -d2
    # extruded along y
    wy = abs(ly) - hy
    inside = min(max(d2, wy), 0.0)
    ox, oy = max(d2, 0.0), max(wy, 0.0)
    return inside + math.sqrt(ox * ox + oy * oy)


@njit
def cylinder_distance(lx, ly, lz, radius, hz, upright):
    """Signed distance from (lx, ly, lz) to a cylinder in its frame (axis z, half-height
    ``hz``), but over an upright one's footprint the height above its top face."""
    qr = math.sqrt(lx * lx + ly * ly) - radius
    if qr <= 0.0 and upright:
        return lz - hz
    qz = abs(lz) - hz
    if qr > 0.0 or qz > 0.0:
        ox, oz = max(qr, 0.0), max(qz, 0.0)
        return math.sqrt(ox * ox + oz * oz)
    return max(qr, qz)
