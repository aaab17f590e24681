"""The preset plates, by their released names (``sim-tactile plates list``). Every dimension a paper leaves open is chosen
here, in one place, and listed in the README's plate table.

Choices where the papers are silent (all plates: base 108 x 36 x 5 mm, textured area
36 x 36 mm centred; the base length gives 36 mm of flat run-in and run-out on each side):

- ``finger7/*`` (soft-finger paper, seed 002): "2.5 mm raised ridges and bumps" is read as
  features 2.5 mm high and 2.5 mm wide (square bumps of 2.5 x 2.5 mm), spread evenly over
  the 36 mm: ridge pitch 18 / 9 / 4.5 mm, bump pitch 12 / 9 / 6 mm.
- ``multilayer3/*`` (multilayer paper, seed 003): "9 ridges spaced by 2 mm with a 30 degree
  draft": ridges 2 mm wide at the base with 2 mm gaps (4 mm period, 9 x 4 = 36 mm), 1 mm
  high, sides drafted 30 degrees from vertical (top 0.85 mm wide). Hemispheres of 4 mm
  diameter, 2 mm edge to edge (6 mm pitch), 2 mm high.
- ``roughness8/ra-*`` (roughness paper, seed 001; standards made by cylindrical turning):
  the profile varies along the slide with its lay along y. Correlation length from the
  turning relation Ra = f^2 / (32 r) with a 0.8 mm tool nose radius r: the feed f =
  sqrt(32 r Ra), correlation length f / 2 (0.57 mm at Ra 50 um, 0.05 mm at Ra 0.4 um).
- ``textures20/*`` (our set for the first paper's protocol): gratings over periods 1.5-6 mm
  and heights 0.25-1 mm, drafted and narrow variants, boxes, cylinders and hemispheres at
  three pitches, and two random roughnesses. Hard pairs on purpose: grating periods 2.0 vs
  2.5 mm, boxes vs cylinders at 3 mm pitch, grating duty 0.5 vs 0.25.
- ``textures20-long/*``: the same 20 textures on a long plate (base 196 x 36 x 5 mm,
  textured area 156 x 36 mm), for slides that stay on the texture the whole window, as seed
  000's BioTac slid 20 cm over each material strip. The area is the short one plus 120 mm,
  a whole even number of every grating period and bump pitch, so each long plate is its
  short plate extended: the same features at the same places over the short plate's area
  (tested); the grids of bumps keep their rows and take the most columns of the same parity
  that fit. The roughness fields are new draws of the same statistics.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

from ..errors import UnknownNameError
from .spec import Bumps, Flat, Grating, Plate, Ridges, Roughness

MM = 1e-3
UM = 1e-6

#: Tool nose radius for the turned roughness standards [m] (a common finishing insert).
TURNING_NOSE_RADIUS_M = 0.8 * MM
#: Ra values of the roughness paper's eight nickel standards [um], roughest first.
ROUGHNESS8_RA_UM = (50, 25, 12.5, 6.3, 3.2, 1.6, 0.8, 0.4)


def turned_corr_length_m(ra_m: float) -> float:
    """Correlation length of a turned profile of roughness ``ra_m``: half the feed."""
    return 0.5 * math.sqrt(32 * TURNING_NOSE_RADIUS_M * ra_m)


def _ra_name(ra_um: float) -> str:
    return f"ra-{ra_um:g}"


def _build_registry() -> dict[str, Callable[[], Plate]]:
    reg: dict[str, Callable[[], Plate]] = {}

    def add(name: str, texture_factory: Callable[[], object]) -> None:
        reg[name] = lambda: Plate(texture=texture_factory(), name=name)

    # --- finger7: the soft-finger paper's 7 plates
    add("finger7/flat", Flat)
    for n in (2, 4, 8):
        add(f"finger7/ridges-{n}", lambda n=n: Ridges(count=n, width_m=2.5 * MM, height_m=2.5 * MM))
    for n in (3, 4, 6):
        add(
            f"finger7/bumps-{n}x{n}",
            lambda n=n: Bumps(rows=n, cols=n, shape="box", size_m=2.5 * MM, height_m=2.5 * MM),
        )
    # --- multilayer3: the multilayer paper's 3 textures
    add("multilayer3/flat", Flat)
    add(
        "multilayer3/grating-9",
        lambda: Grating(
            period_m=4 * MM, height_m=1 * MM, duty=None, width_m=2 * MM, draft_deg=30.0
        ),
    )
    add(
        "multilayer3/hemispheres-6x6",
        lambda: Bumps(rows=6, cols=6, shape="hemisphere", size_m=4 * MM, spacing_m=6 * MM),
    )
    # --- roughness8: the roughness paper's 8 standards
    for i, ra in enumerate(ROUGHNESS8_RA_UM):
        add(
            f"roughness8/{_ra_name(ra)}",
            lambda ra=ra, i=i: Roughness(
                ra_m=ra * UM, corr_length_m=turned_corr_length_m(ra * UM), seed=1000 + i
            ),
        )
    # --- textures20: 20 synthetic textures for the first paper's protocol
    g = "textures20/"
    add(g + "flat", Flat)
    for p in (1.5, 2.0, 2.5, 3.0, 4.0, 6.0):
        add(g + f"grating-{p:.1f}mm", lambda p=p: Grating(period_m=p * MM, height_m=0.5 * MM))
    add(g + "grating-3.0mm-low", lambda: Grating(period_m=3 * MM, height_m=0.25 * MM))
    add(g + "grating-3.0mm-high", lambda: Grating(period_m=3 * MM, height_m=1.0 * MM))
    add(
        g + "grating-3.0mm-draft30",
        lambda: Grating(period_m=3 * MM, height_m=0.5 * MM, draft_deg=30.0),
    )
    add(g + "grating-3.0mm-narrow", lambda: Grating(period_m=3 * MM, height_m=0.5 * MM, duty=0.25))
    for shape, label in (("box", "boxes"), ("cylinder", "cylinders")):
        for p, n in ((3.0, 12), (4.5, 8)):
            add(
                g + f"{label}-{p:.1f}mm",
                lambda shape=shape, p=p, n=n: Bumps(
                    rows=n,
                    cols=n,
                    shape=shape,
                    size_m=1.5 * MM,
                    height_m=0.5 * MM,
                    spacing_m=p * MM,
                ),
            )
    for p, n, d in ((3.0, 12, 1.5), (4.5, 8, 2.0), (6.0, 6, 3.0)):
        add(
            g + f"hemispheres-{p:.1f}mm",
            lambda p=p, n=n, d=d: Bumps(
                rows=n, cols=n, shape="hemisphere", size_m=d * MM, spacing_m=p * MM
            ),
        )
    add(g + "rough-ra25", lambda: Roughness(ra_m=25 * UM, corr_length_m=0.5 * MM, seed=2001))
    add(g + "rough-ra100", lambda: Roughness(ra_m=100 * UM, corr_length_m=1.0 * MM, seed=2002))
    # --- textures20-long: the same textures on a long strip
    for name in [n for n in reg if n.startswith(g)]:
        long_name = LONG_FAMILY + name[len(g) :]
        reg[long_name] = lambda name=name, long_name=long_name: _long(reg[name](), long_name)
    return reg


#: The long plates' family, textured area and base length [m] (see the module docstring).
LONG_FAMILY = "textures20-long/"
LONG_AREA_M = 0.156
LONG_PLATE_M = 0.196


def _long(short: Plate, name: str) -> Plate:
    """``short`` on the long plate: its texture over :data:`LONG_AREA_M`, a bump grid with the
    most columns of its own parity that fit (its features then stay where they were)."""
    t = short.texture
    if isinstance(t, Bumps):
        spacing = t.spacing_m or min(short.area_length_m / t.cols, short.area_width_m / t.rows)
        cols = math.floor((LONG_AREA_M - t.size_m) / spacing + 1e-9) + 1
        if (cols - t.cols) % 2:
            cols -= 1
        t = replace(t, cols=cols, spacing_m=spacing)
    return replace(short, texture=t, name=name, length_m=LONG_PLATE_M, area_length_m=LONG_AREA_M)


_REGISTRY = _build_registry()


def preset_names() -> list[str]:
    """All preset names, in a fixed order."""
    return list(_REGISTRY)


def get_plate(name: str) -> Plate:
    """The preset plate called ``name`` (e.g. ``"finger7/ridges-4"``)."""
    try:
        return _REGISTRY[name]()
    except KeyError:
        fams = sorted({n.split("/")[0] for n in _REGISTRY})
        close = [n for n in _REGISTRY if name and name.split("/")[-1] in n][:5]
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise UnknownNameError(
            f"plate {name!r} is not a preset; valid: one of the {len(_REGISTRY)} names of "
            f"`sim-tactile plates list` (families {', '.join(fams)}){hint}"
        ) from None
