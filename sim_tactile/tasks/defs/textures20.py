"""``textures20-v1``: the first paper's (seed 000) protocol on 20 synthetic textures, one part
per sensor (``textures20-biotac19-v1``, ``textures20-icub60-v1``), with the encodings and
networks of its real-data tasks."""

from __future__ import annotations

from ...plates import preset_names
from ...sim.protocol import Protocol
from ...slides import SlideSet
from ..registry import BenchScene, TaskSpec, register
from . import real

TEXTURES20_REF = (
    "Fast texture classification using tactile neural coding and spiking neural network "
    "(seed paper 000), its protocol on 20 synthetic textures: BioTac (19 electrodes, 100 Hz) "
    "and iCub RoboSkin (60 taxels, 50 Hz), threshold encoding K = 2, linear SVMs, LSTM and "
    "SNN, 7:3 x 5, accuracy over time"
)


def _textures20_part(sensor: str, protocol: Protocol, times, quick_times, bench, remarks):
    real_spec = real.TASKS_BY_SENSOR[sensor]
    return TaskSpec(
        id=f"textures20-{sensor}-v1",
        title=f"{sensor} on the 20 textures20 plates x 50 slides (simulated)",
        get_data=SlideSet(
            plates=TEXTURES20_PLATES,
            sensor=sensor,
            protocol=protocol,
            slides=50,
            quick_slides=3,
            quick_plates=TEXTURES20_QUICK,
        ),
        classifiers=real.MODELS,
        split="7:3",
        encoder=real_spec.encoder,
        encoding=real_spec.encoding,
        full=real.paper000_settings(times, real_spec.full.params),
        quick=real.paper000_settings(quick_times, real_spec.quick.params, quick=True, split="2/1"),
        paper=dict(real_spec.paper),
        remarks=(
            f"The encoding and the networks are those of {real_spec.id}; the paper's numbers "
            "beside ours are its real-data Table I.",
            *remarks,
        ),
        reference=TEXTURES20_REF,
        bench=bench,
    )


TEXTURES20_PLATES = tuple(p for p in preset_names() if p.startswith("textures20/"))
#: the quick run's plates: four distinct kinds with features of 1.5 mm or more (cheap to
#: simulate: coarse nodes and long steps)
TEXTURES20_QUICK = (
    "textures20/flat",
    "textures20/grating-4.0mm",
    "textures20/boxes-4.5mm",
    "textures20/hemispheres-6.0mm",
)

register(
    _textures20_part(
        "biotac19",
        Protocol(
            speed_m_s=0.025,
            force_n=0.5,
            speed_jitter=0.01,
            force_jitter=0.03,
            offset_jitter_m=0.5e-3,
        ),
        (0.25, 0.5, 1.0, 1.5, 2.0, 2.48),
        (0.5, 2.48),
        BenchScene("textures20", "textures20/grating-3.0mm"),
        remarks=(
            "BioTac slides: 25 mm/s and 0.5 N under force and velocity control (KUKA iiwa; "
            "+- 1% speed, +- 3% force), crossing the 36 mm textured area from flat ground to "
            "flat ground in 2.48 s (the paper's window: 4 s of a 20 cm slide on the material).",
        ),
    )
)
register(
    _textures20_part(
        "icub60",
        Protocol(
            speed_m_s=0.04,
            force_n=1.0,
            speed_jitter=0.15,
            force_jitter=0.25,
            offset_jitter_m=1e-3,
        ),
        (0.25, 0.5, 1.0, 1.5, 1.92),
        (0.5, 1.92),
        BenchScene(
            "textures20-icub",
            "textures20/grating-3.0mm",
            left_out="the iCub patch (32 x 22 mm, about 600 nodes at L1) runs at about half "
            "of real time at L1 and its L2 reference has four times the nodes, many minutes "
            "for its sweep; run it with --scenes textures20-icub",
        ),
        remarks=(
            "iCub slides: about 40 mm/s and 1 N without force or speed control (a tendon-"
            "driven arm: +- 15% speed, +- 25% force, +- 1 mm offset, one SD per slide), "
            "crossing the textured area in 1.92 s (the paper's window: 1.5 s).",
        ),
    )
)
register(
    TaskSpec(
        id="textures20-v1",
        title="Seed paper 000's protocol on 20 synthetic textures: BioTac and iCub (simulated)",
        get_data=None,
        classifiers=(),
        parts=("textures20-biotac19-v1", "textures20-icub60-v1"),
        remarks=(
            "Two parts, one per sensor, each with its own report in a sub-folder; the quick "
            "run uses 4 of the plates (flat, grating-4.0mm, boxes-4.5mm, hemispheres-6.0mm), 3 "
            "slides each, split 2/1 per class.",
        ),
        reference=TEXTURES20_REF,
    )
)
