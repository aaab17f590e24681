"""``textures20-v1`` and ``-v2``: the first paper's (seed 000) protocol on 20 synthetic
textures, one part per sensor (``textures20-biotac19-*``, ``textures20-icub60-*``), with the
encodings and networks of its real-data tasks.

- ``-v1``: the pad crosses the 36 mm textured area from flat ground to flat ground;
- ``-v2``: the paper's protocol whole. The pad starts on a 156 mm textured strip
  (``textures20-long/*``) and stays on it for the whole window: the BioTac for the paper's
  4 s (its seconds 1 to 5 of a 20 cm slide at 2.5 cm/s), the iCub for its 1.5 s clips. The
  forces and their variation are measured from the real recordings
  (:mod:`sim_tactile.calibrate.motion`); what could not be measured is listed as a free
  parameter in the remarks.
"""

from __future__ import annotations

from dataclasses import replace

from ...plates import preset_names
from ...plates.read.presets import LONG_FAMILY
from ...sim.plan.protocol import Protocol
from ...slides import SlideSet
from ..registry import BenchScene, TaskSpec, register
from . import real

TEXTURES20_REF = (
    "Fast texture classification using tactile neural coding and spiking neural network "
    "(seed paper 000), its protocol on 20 synthetic textures: BioTac (19 electrodes, 100 Hz) "
    "and iCub RoboSkin (60 taxels, 50 Hz), threshold encoding K = 2, linear SVMs, LSTM and "
    "SNN, 7:3 x 5, accuracy over time"
)


def _textures20_part(sensor: str, protocol: Protocol, times, quick_times, bench, remarks, history):
    """The ``-v1`` part of ``sensor``: the real-data task's encoding, networks and paper
    cells on the 20 synthetic plates."""
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
        history=history,
    )


def _textures20_v2(v1: TaskSpec, protocol: Protocol, times, quick_times, remarks, history):
    """The ``-v2`` part: ``v1`` on the long strips, under the paper's whole protocol (only
    what changed from ``v1`` is given)."""
    real_spec = real.TASKS_BY_SENSOR[v1.get_data.sensor]
    return replace(
        v1,
        id=v1.id.removesuffix("-v1") + "-v2",
        title=v1.title.replace("textures20 plates", "textures20-long plates"),
        get_data=replace(
            v1.get_data,
            plates=tuple(_long_names(TEXTURES20_PLATES)),
            quick_plates=tuple(_long_names(TEXTURES20_QUICK)),
            protocol=protocol,
        ),
        full=real.paper000_settings(times, real_spec.full.params),
        quick=real.paper000_settings(quick_times, real_spec.quick.params, quick=True, split="2/1"),
        remarks=(v1.remarks[0], *remarks),
        bench=None,
        history=history,
        supersedes=v1.id,
    )


def _long_names(names):
    return (LONG_FAMILY + n.split("/", 1)[1] for n in names)


TEXTURES20_PLATES = tuple(p for p in preset_names() if p.startswith("textures20/"))
#: the quick run's plates: four distinct kinds with features of 1.5 mm or more (cheap to
#: simulate: coarse nodes and long steps)
TEXTURES20_QUICK = (
    "textures20/flat",
    "textures20/grating-4.0mm",
    "textures20/boxes-4.5mm",
    "textures20/hemispheres-6.0mm",
)

#: the iCub's v1 protocol (its v2 measures the force's variation and stays on the strip)
ICUB_V1 = Protocol(
    speed_m_s=0.04, force_n=1.0, speed_jitter=0.15, force_jitter=0.25, offset_jitter_m=1e-3
)

BIOTAC_V1 = register(
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
        history=(
            "0.1.0: first release: the pad crosses the 36 mm textured area from flat ground "
            "to flat ground.",
        ),
    )
)
ICUB60_V1 = register(
    _textures20_part(
        "icub60",
        ICUB_V1,
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
        history=(
            "0.1.0: first release: the pad crosses the 36 mm textured area from flat ground "
            "to flat ground.",
        ),
    )
)
TEXTURES20_V1 = register(
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
        history=(
            "0.1.0: first release: each part's pad crosses the 36 mm textured area from flat "
            "ground to flat ground.",
        ),
    )
)

# --- textures20-v2: the paper's protocol whole, on the long strips
#: Measured on the public data set (``tests/test_motion.py`` recomputes them there):
#: the BioTac's force over seconds 1-5, the median slide's mean of pdc / 100 [N] ...
BIOTAC_FORCE_N = 0.45
#: ... and its slide-to-slide coefficient of variation as pdc reads it
BIOTAC_PDC_FORCE_CV = 0.45
#: the iCub clips' summed level, coefficient of variation from clip to clip within a
#: material (median over the 20): an upper bound on the force's variation
ICUB_LEVEL_CV = 0.14
#: a loaded iCub taxel's level within a clip, coefficient of variation of its loaded samples
ICUB_WITHIN_CLIP_CV = 0.064

register(
    _textures20_v2(
        BIOTAC_V1,
        Protocol(
            speed_m_s=0.025,
            force_n=BIOTAC_FORCE_N,
            speed_jitter=0.01,
            force_jitter=0.03,
            offset_jitter_m=0.5e-3,
            duration_s=4.0,
            start="texture",
        ),
        (0.25, 0.5, 1.0, 2.0, 3.0, 4.0),
        (0.5, 4.0),
        remarks=(
            "BioTac slides as seed 000 made them: 2.5 cm/s under force and velocity control "
            "(KUKA iiwa) on a strip that the pad never leaves, recorded for the paper's 4 s "
            "(its seconds 1 to 5; the simulated slide is pressed and settled before its "
            "window, so no first second is discarded).",
            f"Force {BIOTAC_FORCE_N:g} N: the median slide's mean of pdc / 100 over seconds "
            "1-5 of the 1000 real slides (the force the calibration was fitted at).",
            "Free parameters, as v1: +- 1% speed and +- 3% force (one SD per slide), the "
            "spread of a force-controlled arm. pdc itself varies by "
            f"{BIOTAC_PDC_FORCE_CV:.0%} from slide to slide and falls within a slide (its "
            "first second 2.4x its last): the static pressure relaxing under a held force, "
            "which the simulation does not model (docs/real_data.md).",
        ),
        history=(
            "0.1.0: the paper's protocol whole: the pad stays on a 156 mm textured strip for "
            "the paper's whole window, its force and the force's variation measured from the "
            "real recordings; supersedes textures20-biotac19-v1.",
        ),
    )
)
register(
    _textures20_v2(
        ICUB60_V1,
        replace(ICUB_V1, force_jitter=ICUB_LEVEL_CV, duration_s=1.5, start="texture"),
        (0.25, 0.5, 1.0, 1.5),
        (0.5, 1.5),
        remarks=(
            "iCub slides on a strip that the patch never leaves, for the paper's 1.5 s clips "
            "(75 samples at 50 Hz).",
            f"Force variation +- {ICUB_LEVEL_CV:.0%} (one SD per slide): measured, the "
            "clip-to-clip coefficient of variation of a clip's summed level within one "
            "material, median over the 20 materials of the real clips (an upper bound: the "
            "material's unevenness adds to it).",
            "Free parameters: the force, 1 N (none was recorded; the iCub calibration's), "
            "the speed, 40 mm/s, and its variation, +- 15% (v1's). The clips cannot give a "
            "speed: they carry no position, the textures' periods are unknown, and a loaded "
            f"taxel's level is steady within a clip (its loaded samples vary by "
            f"{ICUB_WITHIN_CLIP_CV:.1%}), so no fluctuation can be timed.",
        ),
        history=(
            "0.1.0: the paper's protocol whole: the pad stays on a 156 mm textured strip for "
            "the paper's whole window, its force and the force's variation measured from the "
            "real recordings; supersedes textures20-icub60-v1.",
        ),
    )
)
#: textures20-v2 is textures20-v1 with the v2 parts: only what changed is given
register(
    replace(
        TEXTURES20_V1,
        id="textures20-v2",
        title="Seed paper 000's protocol, whole, on 20 synthetic textures: BioTac and iCub "
        "(simulated)",
        parts=("textures20-biotac19-v2", "textures20-icub60-v2"),
        remarks=(
            "Two parts, one per sensor, each with its own report in a sub-folder; the quick "
            "run uses 4 of the long plates (flat, grating-4.0mm, boxes-4.5mm, "
            "hemispheres-6.0mm), 3 slides each, split 2/1 per class.",
        ),
        history=(
            "0.1.0: the paper's protocol whole: the pad stays on a 156 mm textured strip for "
            "the paper's whole window, its force and the force's variation measured from the "
            "real recordings; supersedes textures20-v1.",
        ),
        supersedes="textures20-v1",
    )
)
