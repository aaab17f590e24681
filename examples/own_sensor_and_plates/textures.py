"""Two textures drawn in CadQuery, for `sim-tactile` to simulate: a diamond knurl and a
chevron tread. Each function returns the part (in mm, as CAD tools draw them): a 3 mm
base with the texture rising from its top at z = 0.

A script is code: sim-tactile runs it, in a separate process and under a time limit, only
because you name it (`--plate textures.py:knurl`, or `plates = ["textures.py:chevron"]` in a
configuration).
"""

import math

import cadquery as cq

SIZE = 36.0  # the textured square [mm]
BASE = 3.0  # base thickness [mm]


def _base():
    return (
        cq.Workplane("XY")
        .box(SIZE, SIZE, BASE, centered=(True, True, False))
        .translate((0, 0, -BASE))
    )


def knurl(pitch=2.5, depth=0.4, angle_deg=30.0, flat=0.1):
    """A diamond knurl: V-grooves every ``pitch`` mm, at +-``angle_deg`` to the y axis (across
    the slide), cut into a slab of ``depth`` on the base, leaving truncated pyramids with
    diamond bases (their tops flats of ``flat`` of the pitch) on a 0.05 mm web."""
    slab = cq.Workplane("XY").box(SIZE, SIZE, depth, centered=(True, True, False))
    web, over = 0.05, 0.5  # the grooves stop 0.05 mm above the base and rise 0.5 mm above the slab
    half_top = (1 - flat) * pitch / 2  # the groove's half width at the slab's top
    half = half_top * (depth + over - web) / (depth - web)
    groove = (
        cq.Workplane("XZ")
        .polyline([(-half, depth + over), (half, depth + over), (0.0, web)])
        .close()
        .extrude(SIZE, both=True)  # a V along y, 2 x SIZE long
    )
    n = int(math.ceil(SIZE / pitch)) + 4
    step = pitch / math.cos(math.radians(angle_deg))  # along x, between grooves `pitch` apart
    for sign in (1, -1):
        turned = groove.rotate((0, 0, 0), (0, 0, 1), sign * angle_deg)
        for i in range(-n, n + 1):
            slab = slab.cut(turned.translate((i * step, 0, 0)))  # one by one: OCC is robust so
    return _base().union(slab)


def chevron(period=3.0, width=1.0, height=0.5, angle_deg=35.0):
    """A chevron tread: V-shaped ridges ``width`` mm wide and ``height`` high every
    ``period`` mm along x (the slide), their arms at ``angle_deg`` to the y axis, pointing +x."""
    t = math.tan(math.radians(angle_deg))
    h = SIZE / 2 - 1.0  # the arms' half length along y
    ridges = []
    n = int(SIZE // period)
    for i in range(n):
        x0 = -SIZE / 2 + (i + 0.5) * period - h * t / 2
        pts = [
            (x0, -h),
            (x0 + h * t, 0.0),
            (x0, h),
            (x0 - width, h),
            (x0 + h * t - width, 0.0),
            (x0 - width, -h),
        ]
        ridges.append(cq.Workplane("XY").polyline(pts).close().extrude(height).val())
    inside = cq.Workplane("XY").box(SIZE, SIZE, height, centered=(True, True, False))
    tread = cq.Workplane("XY").add(cq.Compound.makeCompound(ridges)).intersect(inside)
    return _base().union(tread)
