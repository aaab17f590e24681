"""``roughness8-v1``: the roughness paper (seed 001) in simulation: a fingertip with two PVDF
films slides by hand over eight roughness standards; RS Izhikevich neurons with I = G V; kNN
on spike features and on spike-train distances (STD-kNN), splits 5:5, 7:3, 9:1 x 500."""

from __future__ import annotations

from ...encoders import IzhikevichEncoder
from ...encoders.encodings import EncodingContext, Steps
from ...sim.plan.protocol import Protocol
from ...slides import SlideSet
from ..registry import BenchScene, PaperCell, Run, Settings, TaskSpec, register

ROUGHNESS_REF = (
    "Recognizing tactile surface roughness with a biomimetic fingertip: a soft neuromorphic "
    "approach (seed paper 001): 2 PVDF films at 1 kHz, 8 surfaces Ra 0.4-50 um, 10 hand slides "
    "each at about 0.24 m/s, RS Izhikevich neurons with I = G V, kNN on spike features and "
    "spike-train distances, splits 5:5 / 7:3 / 9:1 x 500"
)
#: I = G V [model units per V]: the RS neuron's rheobase (3.45, 1 Hz over 1 s) at three noise
#: SDs of the film's output (pvdf2 noise 2 mV): the receptor fires for what rises above noise
ROUGHNESS_G = 600.0


def roughness_encoding(ctx: EncodingContext) -> Steps:
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
        bench=BenchScene("roughness8", "roughness8/ra-50"),
    )
)
