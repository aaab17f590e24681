"""The seed papers' setups in simulation: plates -> finger and sensor -> slides -> encoder ->
features or distances -> classifiers -> the paper's protocol (issue 7).

Each task id is versioned: a change of plates, sensor, protocol, encoding or classifier
settings is a new id. The choices a paper leaves open are fixed here and said in the task's
remarks, which every report repeats.
"""

from __future__ import annotations

from ..encoders import IzhikevichEncoder
from ..learn.classifiers import LearnContext, Steps
from ..plates import preset_names
from ..sim.protocol import Protocol
from ..slides import SlideSet
from .registry import PaperCell, Run, Settings, TaskSpec, register

# ------------------------------------------------------------------------------ finger7-v1
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


def finger7_encoding(ctx: LearnContext) -> Steps:
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
                rate_hz=100.0,
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
    )
)


# -------------------------------------------------------------------------- multilayer3-v1
MULTILAYER_REF = (
    "Dynamic texture decoding using a neuromorphic multilayer tactile sensor (seed paper "
    "003): 2 x 3x3 elements, 3 textures, 5 N, about 6.5 cm/s, RS (bottom) and FS (top) "
    "Izhikevich neurons, LDA / SVM / SRC with 10 training and 200 test samples per texture"
)
_TOP = tuple(range(9))
_BOTTOM = tuple(range(9, 18))


def multilayer_encoding(ctx: LearnContext) -> Steps:
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
register(
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
                rate_hz=100.0,
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
    )
)


# --------------------------------------------------------------------------- roughness8-v1
ROUGHNESS_REF = (
    "Recognizing tactile surface roughness with a biomimetic fingertip: a soft neuromorphic "
    "approach (seed paper 001): 2 PVDF films at 1 kHz, 8 surfaces Ra 0.4-50 um, 10 hand slides "
    "each at about 0.24 m/s, RS Izhikevich neurons with I = G V, kNN on spike features and "
    "spike-train distances, splits 5:5 / 7:3 / 9:1 x 500"
)
#: I = G V [model units per V]: the RS neuron's rheobase (3.45, 1 Hz over 1 s) at three noise
#: SDs of the film's output (pvdf2 noise 2 mV): the receptor fires for what rises above noise
ROUGHNESS_G = 600.0


def roughness_encoding(ctx: LearnContext) -> Steps:
    """Paper 001: a regular-spiking Izhikevich neuron per film, input current I = G V (no
    normalisation), RK4 at 0.1 ms on the 1 kHz samples (zero-order hold)."""
    return [
        (
            "encode",
            IzhikevichEncoder(rate_hz=ctx.rate_hz, preset="RS", gain=ROUGHNESS_G, normalize="none"),
        )
    ]


_R001 = "paper 001"


def _rough_runs() -> tuple[Run, ...]:
    vp = {"metric": "victor_purpura", "q": 24.0}
    runs = [
        Run(
            "std-knn",
            channels="film1",
            split=split,
            params={**vp, "n_neighbors": k},
            label=f"VP q=24/s k={k} film1 {split}",
            paper=PaperCell(mean, sd, f"{_R001}, Table 3"),
        )
        for split, k, mean, sd in (
            ("5:5", 7, 0.723, 0.053),
            ("7:3", 11, 0.751, 0.065),
            ("9:1", 11, 0.776, 0.137),
        )
    ]
    for metric, extra, label in (
        ("van_rossum", {"tau": 0.1}, "van Rossum tau=100ms"),
        ("isi_distance", {}, "ISI"),
        ("spike_distance", {}, "SPIKE"),
        ("event_sync_distance", {}, "event sync"),
    ):
        runs.append(
            Run(
                "std-knn",
                channels="film1",
                split="9:1",
                params={"metric": metric, **extra, "n_neighbors": 11},
                label=f"{label} k=11 film1 9:1",
            )
        )
    runs += [
        Run(
            "knn",
            channels="film1",
            split="9:1",
            params={"features": "rate_hz", "n_neighbors": 7},
            label="rate kNN k=7 film1 9:1",
            paper=PaperCell(0.722, 0.109, f"{_R001}, Section 5"),
        ),
        Run(
            "knn",
            channels="film1",
            split="9:1",
            params={"features": "inv_mean_isi_hz", "n_neighbors": 7},
            label="1/ISI kNN k=7 film1 9:1",
        ),
        Run(
            "std-knn",
            channels="film2",
            split="9:1",
            params={"metric": "van_rossum", "tau": 0.09681, "n_neighbors": 9},
            label="van Rossum tau=96.81ms k=9 film2 9:1",
            paper=PaperCell(0.368, 0.130, f"{_R001}, Section 5"),
        ),
    ]
    return tuple(runs)


register(
    TaskSpec(
        id="roughness8-v1",
        title="Biomimetic fingertip, 2 PVDF films at 1 kHz, 8 roughness plates (Ra 0.4-50 um) "
        "x 10 slides, about 0.24 m/s by hand (simulated)",
        get_data=SlideSet(
            plates=tuple(
                f"roughness8/ra-{r}"
                for r in ("50", "25", "12.5", "6.3", "3.2", "1.6", "0.8", "0.4")
            ),
            sensor="pvdf2",
            protocol=Protocol(
                speed_m_s=0.24,
                force_n=1.0,
                rate_hz=1000.0,
                speed_jitter=0.15,
                force_jitter=0.25,
                offset_jitter_m=1e-3,
            ),
            slides=10,
            quick_slides=6,
        ),
        classifiers=("std-knn", "knn"),
        split="9:1",
        encoder=roughness_encoding,
        encoding=f"RS Izhikevich per film, I = G V with G = {ROUGHNESS_G:g} per V, RK4 at 0.1 ms",
        features=("rate_hz", "inv_mean_isi_hz"),
        encode_once=True,
        channel_sets={"film1": (0,), "film2": (1,)},
        runs=_rough_runs(),
        full=Settings(repeats=500),
        quick=Settings(repeats=50, split="4/2"),
        remarks=(
            "Slides by hand: speed 0.24 m/s +- 15%, force 1 N +- 25%, offset across the "
            "slide +- 1 mm (one SD per slide), a spherical fingertip (R 10 mm) crossing the 36 "
            "mm rough area; film 1 across the slide, film 2 along it, 1 mm deep.",
            f"G = {ROUGHNESS_G:g} per V puts the RS neuron's rheobase at three noise SDs of the "
            "simulated film (the paper's G = 0.4 belongs to its amplifier, whose gain is not "
            "given); 'sim-tactile ablate roughness8-v1 --set gain=...' sweeps it.",
            "The quick run splits 4/2 per class (6 slides per plate) for every row; the full "
            "run uses each row's split.",
        ),
        reference=ROUGHNESS_REF,
    )
)


# --------------------------------------------------------------------------- textures20-v1
TEXTURES20_REF = (
    "Fast texture classification using tactile neural coding and spiking neural network "
    "(seed paper 000), its protocol on 20 synthetic textures: BioTac (19 electrodes, 100 Hz) "
    "and iCub RoboSkin (60 taxels, 50 Hz), threshold encoding K = 2, linear SVMs, LSTM and "
    "SNN, 7:3 x 5, accuracy over time"
)


def _textures20_part(sensor: str, protocol: Protocol, real: str, times, quick_times, **kw):
    from . import real as R

    real_spec = R.TASKS_BY_SENSOR[sensor]
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
        classifiers=R.MODELS,
        split="7:3",
        encoder=real_spec.encoder,
        encoding=real_spec.encoding,
        full=Settings(
            repeats=5,
            repeats_by_classifier={"lstm": 2},
            time_points_s=times,
            time_repeats=1,
            params=real_spec.full.params,
        ),
        quick=Settings(
            repeats=2,
            repeats_by_classifier={"lstm": 1, "snn": 1},
            time_points_s=quick_times,
            time_repeats=1,
            params=real_spec.quick.params,
            split="2/1",
        ),
        paper=dict(real_spec.paper),
        remarks=(
            f"The encoding and the networks are those of {real}; the paper's numbers beside "
            "ours are its real-data Table I.",
            *kw.get("remarks", ()),
        ),
        reference=TEXTURES20_REF,
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
            rate_hz=100.0,
            speed_jitter=0.01,
            force_jitter=0.03,
            offset_jitter_m=0.5e-3,
        ),
        "biotac20-real",
        (0.25, 0.5, 1.0, 1.5, 2.0, 2.48),
        (0.5, 2.48),
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
            rate_hz=50.0,
            speed_jitter=0.15,
            force_jitter=0.25,
            offset_jitter_m=1e-3,
        ),
        "icub20-real",
        (0.25, 0.5, 1.0, 1.5, 1.92),
        (0.5, 1.92),
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
        get_data=SlideSet(
            plates=TEXTURES20_PLATES,
            sensor="biotac19",
            protocol=Protocol(),
            slides=2,
            quick_slides=2,
        ),
        classifiers=("svm-raw",),
        parts=("textures20-biotac19-v1", "textures20-icub60-v1"),
        remarks=(
            "Two parts, one per sensor, each with its own report in a sub-folder; the quick "
            "run uses 4 of the plates (flat, grating-4.0mm, boxes-4.5mm, hemispheres-6.0mm), 3 "
            "slides each, split 2/1 per class.",
        ),
        reference=TEXTURES20_REF,
    )
)
