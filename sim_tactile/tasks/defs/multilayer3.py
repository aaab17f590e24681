"""The multilayer paper (seed 003) in simulation: FS (top) and RS (bottom) Izhikevich neurons;
LDA, linear SVM and SRC on spike features, 10/200 per texture over 1000 splits.

- ``multilayer3-v1``: two 3x3 layers on a soft 16 mm pad cross three textures at 5 N;
- ``multilayer3-v2``: the paper's rig: the sensor's stack lies on the rig's rigid bed and a
  rigid probe carrying each 36 x 36 mm texture presses on it with 5 N and slides across it
  at 65 mm/s, one way or the other, between pauses, in 5 s windows (:mod:`~sim_tactile.sim.plan.rig`).
"""

from __future__ import annotations

from dataclasses import replace

from ...encoders import IzhikevichEncoder
from ...encoders.encodings import EncodingContext, Steps
from ...sensors import get_sensor
from ...sim.plan.protocol import Protocol
from ...sim.plan.rig import ProbeRig
from ...slides import SlideSet
from ..registry import BenchScene, PaperCell, Run, Settings, TaskSpec, register

MULTILAYER_REF = (
    "Dynamic texture decoding using a neuromorphic multilayer tactile sensor (seed paper "
    "003): 2 x 3x3 elements, 3 textures, 5 N, about 6.5 cm/s, RS (bottom) and FS (top) "
    "Izhikevich neurons, LDA / SVM / SRC with 10 training and 200 test samples per texture"
)
_TOP = tuple(range(9))
_BOTTOM = tuple(range(9, 18))


def multilayer_encoding(ctx: EncodingContext) -> Steps:
    """Paper 003: FS neurons (RA) on the top layer, RS (SA) on the bottom, each element's
    output min-max normalised and scaled so that its largest value drives the neuron at 200 /
    100 Hz; the 100 Hz samples are held (zero-order) on the neuron's 1 ms Euler grid (the
    paper's millisecond-scale implementation: Izhikevich's 2003 scheme)."""
    return [
        (
            "encode",
            IzhikevichEncoder(
                rate_hz=ctx.rate_hz,
                preset=["FS"] * 9 + ["RS"] * 9,
                max_rate_hz=[200.0] * 9 + [100.0] * 9,
                normalize="minmax",
                scheme="izhikevich2003",
            ),
        )
    ]


_ML = PaperCell  # the paper gives the means of Fig. 5A (both layers) without SDs
MULTILAYER3_V1 = register(
    TaskSpec(
        id="multilayer3-v1",
        title="Multilayer sensor, 2 x 3x3 elements (3 x 3 mm at 5 mm), 3 textures, 5 N, "
        "65 mm/s, 100 Hz (simulated)",
        get_data=SlideSet(
            plates=("multilayer3/flat", "multilayer3/grating-9", "multilayer3/hemispheres-6x6"),
            sensor="multilayer3x3x2",
            protocol=Protocol(
                speed_m_s=0.065,
                force_n=5.0,
                speed_jitter=0.02,
                force_jitter=0.02,
                offset_jitter_m=0.5e-3,
            ),
            slides=210,
            quick_slides=10,
        ),
        classifiers=("lda", "svm", "src"),
        split="10/200",
        encoder=multilayer_encoding,
        encoding="FS (top layer) / RS (bottom layer) Izhikevich, gains for 200 / 100 Hz at "
        "each element's maximum, Euler 1 ms (Izhikevich 2003)",
        features=("rate_nonzero_hz", "mean_isi_s"),
        encode_once=True,
        channel_sets={"top": _TOP, "bottom": _BOTTOM},
        runs=tuple(
            Run(
                clf,
                channels=layer,
                label=f"{clf} {layer}",
                paper=_ML(mean, None, "paper 003, Fig. 5A") if layer == "all" else None,
            )
            for clf, mean in (("lda", 0.953), ("svm", 0.966), ("src", 0.970))
            for layer in ("all", "top", "bottom")
        ),
        full=Settings(repeats=1000),
        quick=Settings(repeats=50, split="3/7"),
        remarks=(
            "Slides: a flat 16 x 16 mm pad carrying the two layers presses with 5 N and "
            "crosses the 36 mm textured area at 65 mm/s (+- 2%, force +- 2%: a robot and a "
            "scale set them; offset +- 0.5 mm across the slide, one SD). In the paper the texture moves over a fixed sensor; "
            "relative motion is what the skin sees. The paper's 5 s windows hold one pass and "
            "the pauses at the track's ends; the window here is the pass (0.93 s).",
            "Encoding fitted once on all slides (the paper encodes offline); features: mean of "
            "the non-zero 100 ms bin rates and mean ISI per element (18 per layer); SRC: "
            "OMP with sparsity 5 on standardised, unit-norm samples.",
            "'all' rows use both layers (36 features), as the paper's headline numbers do; "
            "the paper gives no SDs and no numbers for the single layers (only '> 90%').",
        ),
        reference=MULTILAYER_REF,
        bench=BenchScene("multilayer3", "multilayer3/grating-9"),
        history=(
            "0.1.0: first release: a flat 16 x 16 mm pad carrying the two layers presses "
            "with 5 N and crosses the 36 mm textured area.",
        ),
    )
)


#: multilayer3-v2 is multilayer3-v1 on the paper's probe rig: only what changed is given
MULTILAYER3_V2 = register(
    replace(
        MULTILAYER3_V1,
        id="multilayer3-v2",
        title="Multilayer sensor on the rig's bed under a sliding textured probe (36 x 36 mm, "
        "5 N, 65 mm/s both ways, 5 s windows), 2 x 3x3 elements, 3 textures, 100 Hz "
        "(simulated)",
        get_data=replace(
            MULTILAYER3_V1.get_data,
            protocol=replace(MULTILAYER3_V1.get_data.protocol, duration_s=5.0),
            finger=get_sensor("multilayer3x3x2").with_paper_stack().finger,
            rig=ProbeRig(),
        ),
        encoding=MULTILAYER3_V1.encoding + ", the 100 Hz samples held (zero-order) on the 1 ms "
        "grid",
        remarks=(
            "The rig (paper 003, Fig. 3): the sensor lies on the rig's rigid loading bed and "
            "stays; a rigid probe carrying the 36 x 36 mm texture, features across the slide "
            "(parallel to the element rows), is held at 5 N and slides across the sensor at "
            "65 mm/s (speed and force +- 2%: a robot and a scale set them; offset across the "
            "slide +- 0.5 mm, one SD), from where its edge is clear of the elements to where "
            "it is clear on the other side (2 mm plus twice the sensor's 2.5 mm, where the "
            "stress of its edge has died out), pausing before and after.",
            "Free parameters, with the values chosen: the pass sits in the middle of its 5 s "
            "window (the paper segments the cycles at the pauses; the split of the 5 s is not "
            "given); each slide's direction is drawn from its seed, half each way (the paper "
            "slides both ways and uses every pass); the sensor's layers cover the bed along "
            "the whole track (the paper presses the 5 N before the slide and the force stays "
            "set, which a step onto a sheet's edge would break); the probe's carriage weighs "
            "0.3 kg (not given; it only sets how closely the carriage follows its command).",
            "The sensor's skin is its paper stack (sensors.paper_stacks: fabric 0.75 mm / "
            "spacer 1 mm / fabric 0.75 mm on the rigid bed, most numbers assumptions), the "
            "elements 0.5 and 2 mm deep; frictionless. The contact is solved on the probe's "
            "face at 0.25 mm nodes (docs/probe_rig.md).",
            "Encoding fitted once on all slides (the paper encodes offline); features: mean of "
            "the non-zero 100 ms bin rates and mean ISI per element (18 per layer); SRC: "
            "OMP with sparsity 5 on standardised, unit-norm samples.",
        ),
        bench=None,
        history=(
            "0.1.0: the paper's rig: the sensor lies on the rig's bed and a rigid probe "
            "carrying the texture slides over it at 5 N, both ways, in 5 s windows; "
            "supersedes multilayer3-v1.",
        ),
        supersedes="multilayer3-v1",
    )
)
