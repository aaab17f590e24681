"""Each preset sensor's skin as its paper describes it: the layers and what carries them.

The presets' skins are an elastic half-space (the ``-v1`` tasks keep that meaning). These
are the stacks the papers describe, for the setups built as the papers built them
(:meth:`~sim_tactile.sensors.Sensor.with_paper_stack`). The papers give the materials, the
order of the layers and the backing, but **none of them gives a layer's thickness, modulus
or Poisson ratio**: every such number here is an assumption, and each says so and why.
Each number carries its source: ``paper 00N, section: "quote"`` or ``assumption: reason``.
The research notes behind them, with the quotes in full, are ``docs/stacks.md``.

| sensor | layers from the top | backing | taxels |
|---|---|---|---|
| grid3x3 (002) | fabric array 0.75 mm, 0.75 MPa, nu 0.3 / Dragon Skin 10 wall 2.5 mm, 0.2 MPa, nu 0.49 | the finger's silicone body as a half-space (0.2 MPa): uninflated, no bone | at the surface |
| multilayer3x3x2 (003) | top fabric 0.75 mm / spacer 1 mm, 0.3 MPa, nu 0.45 / bottom fabric 0.75 mm | the rig's rigid loading bed | 0.5 and 2 mm deep |
| biotac19 (000) | silicone skin 1 mm, 0.75 MPa, nu 0.49 / the fluid 2 mm as a soft confined layer, 0.02 MPa, nu 0.4999 | the rigid core | 2.5 mm deep, in the fluid |
| icub60 (000) | conductive outer layer 0.3 mm, 0.5 MPa, nu 0.45 / dielectric foam 2 mm, 0.1 MPa, nu 0.2 | the rigid forearm shell under the PCB | 0.5 mm deep |
| pvdf2 (001) | PDMS epidermis 1 mm, 1.5 MPa, nu 0.49 / PDMS dermis 3.5 mm, 0.3 MPa, nu 0.49 | the PMMA bone, rigid | 1 mm deep: the films between the layers |

What bonded elastic layers leave out: the BioTac's liquid carries load hydrostatically
across the whole fingertip (a confined, nearly incompressible layer carries it only
locally); the soft finger's air channel lets its wall bend (a half-space backing does not);
fabric is anisotropic and compresses non-linearly. The taxel depths are the presets' own,
so each lies inside its stack.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import UnknownNameError
from .stack import Layer, Stack


@dataclass(frozen=True)
class Sourced:
    """A number and where it comes from: ``paper 00N ...`` or ``assumption: ...``."""

    value: float
    source: str


@dataclass(frozen=True)
class PaperLayer:
    """One layer: what it is, its thickness [m], Young's modulus [Pa] and Poisson ratio."""

    what: str
    thickness_m: Sourced
    young_pa: Sourced
    poisson: Sourced

    def layer(self) -> Layer:
        return Layer(self.thickness_m.value, self.young_pa.value, self.poisson.value)


@dataclass(frozen=True)
class PaperStack:
    """A sensor's skin from its paper: layers from the top, the backing and its source, and
    what the bonded layers leave out."""

    sensor: str
    layers: tuple[PaperLayer, ...]
    backing: str
    backing_source: str
    backing_young_pa: Sourced | None = None
    backing_poisson: Sourced | None = None
    leaves_out: str = ""

    def stack(self) -> Stack:
        return Stack(
            tuple(la.layer() for la in self.layers),
            self.backing,
            None if self.backing_young_pa is None else self.backing_young_pa.value,
            0.5 if self.backing_poisson is None else self.backing_poisson.value,
        )

    def numbers(self) -> list[Sourced]:
        """Every number of the stack, with its source."""
        out = [x for la in self.layers for x in (la.thickness_m, la.young_pa, la.poisson)]
        return out + [x for x in (self.backing_young_pa, self.backing_poisson) if x is not None]


_FABRIC_T = Sourced(
    0.75e-3,
    "assumption: conductive strips (about 0.1 mm each) around a piezoresistive fabric "
    "(0.3-0.5 mm); the papers give no thickness",
)
_FABRIC_E = Sourced(
    0.75e6,
    "assumption: effective compressive modulus of woven fabric, 0.5-1 MPa (anisotropic, "
    "non-linear); the papers give none",
)
_FABRIC_NU = Sourced(0.3, "assumption: fabric compresses (it is mostly air); not given")
_SILICONE_NU = Sourced(
    0.49, "assumption: cured platinum silicone and PDMS are nearly incompressible; not given"
)
_DRAGON_SKIN_E = Sourced(
    0.2e6,
    "assumption: Dragon Skin 10 (paper 002, II.B: 'The silicone rubber Dragon SkinTM 10 "
    "Medium ... composes much of the soft finger'), Shore 10A: small-strain fits of 0.1-0.3 "
    "MPa; the paper gives no modulus",
)

PAPER_STACKS: dict[str, PaperStack] = {
    "grid3x3": PaperStack(
        "grid3x3",
        (
            PaperLayer(
                "paper 002, Fig. 1: 'crossing 2 mm strips of conductive traces sandwich the "
                "piezoresistive fabric'",
                _FABRIC_T,
                _FABRIC_E,
                _FABRIC_NU,
            ),
            PaperLayer(
                "paper 002, II.B: the finger's silicone wall over its pneumatic channel",
                Sourced(
                    2.5e-3,
                    "assumption: 2-3 mm, typical of moulded fibre-reinforced pneumatic "
                    "fingers; the paper gives no size",
                ),
                _DRAGON_SKIN_E,
                _SILICONE_NU,
            ),
        ),
        "halfspace",
        "paper 002, III.A: 'The soft finger was used to in its uninflated state': no rigid "
        "bone; the silicone body below the wall is taken as a half-space",
        _DRAGON_SKIN_E,
        _SILICONE_NU,
        "the air channel under the wall, which lets it bend; the cotton layers (stiff in "
        "tension, nothing in compression)",
    ),
    "multilayer3x3x2": PaperStack(
        "multilayer3x3x2",
        (
            PaperLayer(
                "paper 003, Fig. 2: the top sensing layer ('the top layer having more "
                "sensitive sensing elements')",
                _FABRIC_T,
                _FABRIC_E,
                _FABRIC_NU,
            ),
            PaperLayer(
                "assumption: what separates the layers is not given; a compliant spacer",
                Sourced(1e-3, "assumption: about 1 mm; not given"),
                Sourced(0.3e6, "assumption: a soft spacer, 0.3 MPa; not given"),
                Sourced(0.45, "assumption: not given"),
            ),
            PaperLayer(
                "paper 003, Fig. 2: the bottom sensing layer",
                _FABRIC_T,
                _FABRIC_E,
                _FABRIC_NU,
            ),
        ),
        "rigid",
        "paper 003, II.B: the scale's 'loading bed', which the probe presses the sensor "
        "onto (rigid by inference: the text never says the sensor lies on it)",
        leaves_out="the fabric's anisotropy and non-linear compression",
    ),
    "biotac19": PaperStack(
        "biotac19",
        (
            PaperLayer(
                "assumption: the elastomer skin (paper 000, IV.B gives only 'filled with liquid')",
                Sourced(1e-3, "assumption: 0.5-1.5 mm of silicone skin; not given"),
                Sourced(0.75e6, "assumption: 0.5-1 MPa; not given"),
                _SILICONE_NU,
            ),
            PaperLayer(
                "paper 000, IV.B: 'The sensor is filled with liquid'",
                Sourced(2e-3, "assumption: a 1-3 mm gap over the core at the pad; not given"),
                Sourced(
                    0.02e6,
                    "assumption: a liquid has no shear stiffness; a soft layer stands in for it",
                ),
                Sourced(
                    0.4999,
                    "assumption: a liquid is incompressible (bulk modulus about 2 GPa)",
                ),
            ),
        ),
        "rigid",
        "assumption: the rigid core carrying the electrodes (not in paper 000)",
        leaves_out="the liquid's hydrostatic spread of load over the whole fingertip",
    ),
    "icub60": PaperStack(
        "icub60",
        (
            PaperLayer(
                "assumption: the conductive outer layer, the capacitor's upper plate (paper "
                "000, IV.A gives only 'capacitive ... dielectric deformation')",
                Sourced(0.3e-3, "assumption: 0.2-0.5 mm of conductive Lycra or silicone"),
                Sourced(0.5e6, "assumption: not given"),
                Sourced(0.45, "assumption: not given"),
            ),
            PaperLayer(
                "paper 000, IV.A: 'The capacitive tactile sensor works on the principle of "
                "dielectric deformation'",
                Sourced(2e-3, "assumption: 2-3 mm of silicone foam or spacer fabric"),
                Sourced(0.1e6, "assumption: soft foam, 0.05-0.2 MPa; not given"),
                Sourced(0.2, "assumption: foam and spacer fabric compress, 0.1-0.3"),
            ),
        ),
        "rigid",
        "assumption: the flexible PCB glued to the robot's rigid forearm shell",
        leaves_out="the foam's non-linear compression",
    ),
    "pvdf2": PaperStack(
        "pvdf2",
        (
            PaperLayer(
                "paper 001, 4.1: the harder PDMS 'epidermis'",
                Sourced(1e-3, "assumption: about 1 mm; not given"),
                Sourced(1.5e6, "assumption: PDMS at 10:1, 1-2 MPa; the ratio is not given"),
                _SILICONE_NU,
            ),
            PaperLayer(
                "paper 001, 4.1: the softer PDMS 'dermis'; the PVDF films lie between the two",
                Sourced(3.5e-3, "assumption: 3-4 mm; not given"),
                Sourced(0.3e6, "assumption: PDMS at 20-30:1, 0.2-0.5 MPa; not given"),
                _SILICONE_NU,
            ),
        ),
        "rigid",
        "paper 001, 4.1: 'A polymethyl methacrylate (PMMA) bar serves the role comparable to "
        "that of a bone' (about 3 GPa: rigid against PDMS)",
        leaves_out="the PVDF films' own stiffness (tens of um thick)",
    ),
}


def paper_stack(name: str) -> PaperStack:
    """The paper's stack of the preset sensor ``name``."""
    try:
        return PAPER_STACKS[name]
    except KeyError:
        raise UnknownNameError(
            f"no paper stack for sensor {name!r}; valid: {', '.join(PAPER_STACKS)}"
        ) from None
