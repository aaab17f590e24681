"""``finger7-v1``: the soft-finger paper (seed 002) in simulation: the 3x3 fabric array on a
soft pad slides over the paper's seven plates; SA Izhikevich neurons; a linear SVM on mean
rate and mean ISI per taxel, 24/8 per plate over 1000 splits."""

from __future__ import annotations

from ...encoders import IzhikevichEncoder
from ...encoders.encodings import EncodingContext, Steps
from ...sim.protocol import Protocol
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

register(
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
    )
)
