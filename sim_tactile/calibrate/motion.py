"""How the real slides moved: the force and its variation, measured from the recordings.

The simulated tasks that follow a real data set's protocol (``textures20-*-v2``) take their
force and its slide-to-slide variation from here, not from a guess:

- :func:`biotac_force`: the BioTac's static pressure (pdc, 100 counts per newton) gives the
  normal force in every sample; over a window of each slide its mean, and over the slides
  the median and the coefficient of variation;
- :func:`clip_level_variation`: where no force was recorded (the iCub), a clip's summed
  level over its taxels is what the force moves; within one material its coefficient of
  variation from clip to clip bounds the force's (the material's own unevenness and where
  the patch lands add to it). The median over the materials is the estimate.

Speed cannot be read from clips that carry no position and whose texture period is unknown:
:func:`clip_level_variation` also reports how still a loaded taxel's level is within a clip
(the coefficient of variation of its loaded samples), which is why no fluctuation could be
timed from them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError


@dataclass(frozen=True)
class ForceStats:
    """A force over slides [N]: the median slide's, the coefficient of variation from slide
    to slide, and its quartiles, over ``n`` slides."""

    median_n: float
    cv: float
    quartiles_n: tuple[float, float]
    n: int


def biotac_force(forces: list[np.ndarray], rate_hz: float, window_s: tuple[float, float]):
    """:class:`ForceStats` of each slide's mean force over ``window_s`` (forces (T,) [N] at
    ``rate_hz``); slides shorter than the window are refused by name."""
    a, b = (round(t * rate_hz) for t in window_s)
    if not 0 <= a < b:
        raise ConfigError(f"window_s = {window_s}; valid: 0 <= start < end [s]")
    means = []
    for k, f in enumerate(forces):
        if len(f) < b:
            raise ConfigError(
                f"slide {k} has {len(f)} samples; the window {window_s} s needs {b} at "
                f"{rate_hz:g} Hz"
            )
        means.append(float(np.mean(f[a:b])))
    m = np.asarray(means)
    return ForceStats(
        float(np.median(m)),
        float(m.std() / m.mean()),
        (float(np.quantile(m, 0.25)), float(np.quantile(m, 0.75))),
        len(m),
    )


@dataclass(frozen=True)
class LevelVariation:
    """The clip-to-clip coefficient of variation of the summed level within each material:
    the median over materials and its quartiles; and the median coefficient of variation of
    a loaded taxel's loaded samples within a clip (``within_clip_cv``)."""

    cv: float
    quartiles: tuple[float, float]
    within_clip_cv: float
    n_classes: int


def clip_level_variation(
    data: np.ndarray, labels: np.ndarray, noise: np.ndarray, loaded_sigmas: float = 8.0
) -> LevelVariation:
    """:class:`LevelVariation` of clips ``data`` (R, T, C) with material ``labels`` (R,) and
    channel noise ``noise`` (C,): a taxel is loaded in a clip where it rises
    ``loaded_sigmas`` noise deviations above 0, and its loaded samples are those above that."""
    data = np.asarray(data, dtype=float)
    labels = np.asarray(labels)
    if data.ndim != 3 or len(labels) != len(data):
        raise ConfigError(f"clips {data.shape} with {len(labels)} labels; valid: (R, T, C), R")
    total = np.clip(data, 0.0, None).sum(axis=(1, 2))
    cvs = []
    for c in np.unique(labels):
        t = total[labels == c]
        if len(t) >= 2 and t.mean() > 0:
            cvs.append(float(t.std() / t.mean()))
    if not cvs:
        raise ConfigError("no material has two clips with a level: nothing to compare")
    thr = loaded_sigmas * np.asarray(noise, dtype=float)[None, None, :]
    within = []
    for r, c in zip(*np.nonzero((data >= thr).any(axis=1)), strict=True):
        x = data[r, :, c]
        x = x[x >= thr[0, 0, c]]
        if len(x) >= 2:
            within.append(float(x.std() / x.mean()))
    return LevelVariation(
        float(np.median(cvs)),
        (float(np.quantile(cvs, 0.25)), float(np.quantile(cvs, 0.75))),
        float(np.median(within)) if within else float("nan"),
        len(cvs),
    )
