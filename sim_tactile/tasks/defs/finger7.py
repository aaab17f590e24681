"""The soft-finger paper (seed 002) in simulation: SA Izhikevich neurons; a linear SVM on mean
rate and mean ISI per taxel, 24/8 per plate over 1000 splits.

- ``finger7-v1``: the 3x3 fabric array on a flat soft pad, held at 1 N, slides over the
  paper's seven plates;
- ``finger7-v2``: the paper's finger: the array on the palmar surface of a curved silicone
  finger (the paper's stack on the finger's soft body), brought down on one side of the plate
  until the array touches, then palpating along the plate at that height at 60 mm/s, in 9 s
  windows.
"""

from __future__ import annotations

from dataclasses import replace

from ...encoders import IzhikevichEncoder
from ...encoders.encodings import EncodingContext, Steps
from ...sensors import get_sensor
from ...sensors.pad import Finger
from ...sim.plan.protocol import Protocol
from ...slides import SlideSet
from ..registry import BenchScene, PaperCell, Run, Settings, TaskSpec, register

FINGER7_REF = (
    "Texture discrimination using a flexible tactile sensor array on a soft biomimetic finger "
    "(seed paper 002): 3x3 taxels, 7 plates, 60 mm/s, 32 slides per plate, SA Izhikevich "
    "neurons (gain 15), mean rate and mean ISI per taxel, linear SVM 24/8 x 1000"
)
FINGER7_PLATES = (
    "finger7/flat",
    "finger7/ridges-2",
    "finger7/ridges-4",
    "finger7/ridges-8",
    "finger7/bumps-3x3",
    "finger7/bumps-4x4",
    "finger7/bumps-6x6",
)


def finger7_encoding(ctx: EncodingContext) -> Steps:
    """Paper 002: each taxel's output normalised to [0, 1] (min-max over all slides) times the
    gain k = 15 drives an SA-I (regular-spiking) Izhikevich neuron, zero-order held."""
    return [
        (
            "encode",
            IzhikevichEncoder(rate_hz=ctx.rate_hz, preset="SA", gain=15.0, normalize="minmax"),
        )
    ]


_TAXELS = {f"t{i}": (i,) for i in range(9)}

FINGER7_V1 = register(
    TaskSpec(
        id="finger7-v1",
        title="Soft finger, grid3x3 (2 x 2 mm taxels at 2.5 mm), 7 plates x 32 slides, "
        "60 mm/s, 100 Hz (simulated)",
        get_data=SlideSet(
            plates=FINGER7_PLATES,
            sensor="grid3x3",
            protocol=Protocol(
                speed_m_s=0.06,
                force_n=1.0,
                speed_jitter=0.05,
                force_jitter=0.10,
                offset_jitter_m=0.5e-3,
            ),
            slides=32,
            quick_slides=8,
        ),
        classifiers=("svm",),
        split="24/8",
        encoder=finger7_encoding,
        encoding="SA-I Izhikevich (a 0.02, b 0.2, c -65, d 8) per taxel, input = 15 x "
        "min-max normalised output, RK4 at 0.1 ms",
        features=("rate_hz", "mean_isi_s"),
        encode_once=True,
        channel_sets=_TAXELS,
        runs=(
            Run("svm", label="svm all taxels", paper=PaperCell(0.9921, None, "paper 002, Fig. 6")),
            *(Run("svm", channels=name, label=f"svm {name} only") for name in _TAXELS),
            Run("svm-raw", label="svm-raw all taxels (no encoding)"),
        ),
        full=Settings(repeats=1000),
        quick=Settings(repeats=50, split="6/2"),
        remarks=(
            "Slides: the pad (flat, 12 x 12 mm, E 0.3 MPa, 4 mm thick) presses with 1 N and "
            "crosses the 36 mm textured area from flat ground to flat ground; speed 60 mm/s "
            "+- 5%, force +- 10%, start offset across the slide +- 0.5 mm (one SD, per slide). "
            "The paper's 9 s windows hold a whole robot trial (descent, slide, lift); the "
            "window here is the slide only (0.87 s), which carries all of the texture.",
            "Normalisation: min-max per taxel over all slides, before any split (the paper "
            "encodes offline); the features are therefore computed once, and each of the 1000 "
            "splits fits the standardised linear SVM (libsvm, C = 1) only.",
            "Paper: 99.21% with all taxels, 54.01-92.86% with one taxel's two features; "
            "'svm tN only' rows are the single-taxel runs (t4 is the centre, t0-t2 the "
            "leading row along the slide). 'svm-raw' (the mean output of each taxel, no "
            "spikes) is not in the paper: it shows what the encoding keeps.",
        ),
        reference=FINGER7_REF,
        bench=BenchScene("finger7", "finger7/ridges-4"),
        history=(
            "0.1.0: first release: a flat 12 x 12 mm pad held at 1 N crosses the 36 mm "
            "textured area from flat ground to flat ground.",
        ),
    )
)


#: The finger of finger7-v2: its palmar surface an ellipsoidal cap (assumption: the paper
#: gives no dimensions; its finger [13] mimics a human index finger: about 18 mm across, the
#: pad gently curved along the finger), carrying the paper's stack (fabric array over the
#: Dragon Skin 10 wall, on the uninflated finger's silicone body as a half-space).
FINGER7_V2_FINGER = Finger(
    shape="ellipsoid", radii_m=(0.015, 0.009, 0.009), size_m=(0.022, 0.016)
).layered(get_sensor("grid3x3").with_paper_stack().finger.stack)

#: finger7-v2 is finger7-v1 with the paper's finger and protocol: only what changed is given
FINGER7_V2 = register(
    replace(
        FINGER7_V1,
        id="finger7-v2",
        title="Soft finger as built: grid3x3 on a curved silicone finger (paper stack), "
        "brought down to touch, palpating at 60 mm/s at that height, 7 plates x 32, 9 s "
        "windows, 100 Hz (simulated)",
        get_data=replace(
            FINGER7_V1.get_data,
            protocol=replace(
                FINGER7_V1.get_data.protocol,
                force_n=0.05,
                duration_s=9.0,
                force_control="position",
                speed_jitter=0.01,
                force_jitter=0.0,
            ),
            finger=FINGER7_V2_FINGER,
            pitch_m=0.25e-3,
        ),
        remarks=(
            "The finger (paper 002, II.B-C): the 3x3 array on the palmar surface of the "
            "uninflated Dragon Skin 10 finger, its skin the paper's stack (sensors."
            "paper_stacks: fabric 0.75 mm over the 2.5 mm wall, on the finger's silicone body "
            "as a half-space). The palmar surface is an ellipsoidal cap of radii 15 mm along "
            "the finger and 9 mm across and deep (assumption: not given; a human index "
            "finger's size), its node patch 22 x 16 mm (where 2.5 mm features reach it).",
            "The protocol (paper 002, II.D): the finger is lowered on the flat ground before "
            "the texture until the array carries 0.05 N (assumption: the paper stops 'until "
            "the sensor array made physical contact'), then moves along the plate at that "
            "height at 60 mm/s (+- 1%: a UR5 arm; offset across the slide +- 0.5 mm, one SD), "
            "across the texture to the plate's end, where it rests for the rest of the 9 s "
            "window (the paper segmented its trials into 9 s windows). The load follows the "
            "2.5 mm features: nothing holds the force.",
            "Node pitch 0.25 mm (fixed): the taxel loads within 4.3-5.4% (largest difference "
            "along the pass, of the peak) of 0.14 mm nodes on ridges-4, ridges-8 and "
            "bumps-6x6; on bumps-4x4 29% (7.5% rms), where the bumps' walls fall 0.25 mm "
            "inside the outer taxels and their peaks are not converged (0.22 / 0.38 / 0.30 N "
            "at 0.5 / 0.25 / 0.14 mm; every pitch feels the bumps). Our own finer grid: no "
            "independent solver serves a layered curved finger (docs/finger7_v2.md).",
            "Normalisation, features and SVM as finger7-v1.",
        ),
        bench=None,
        history=(
            "0.1.0: the paper's finger and protocol: the array on a curved Dragon Skin finger "
            "with the paper's stack, lowered to a touch and palpating at that height "
            "(position control) in 9 s windows; supersedes finger7-v1.",
        ),
        supersedes="finger7-v1",
    )
)
