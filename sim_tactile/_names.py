"""Names a user may mistype (tasks, plates, sensors, classifiers): the closest valid ones,
for the error that refuses the name."""

from __future__ import annotations

import difflib
from collections.abc import Iterable

#: How alike a valid name must be to be offered (difflib's ratio, 0..1): "finger7-v9" finds
#: "finger7-v1" (0.9), "grid3x4" "grid3x3" (0.86), "ridges4" "finger7/ridges-4" (0.61).
CUTOFF = 0.6


def did_you_mean(name: object, valid: Iterable[str], n: int = 3) -> str:
    """``" (did you mean 'a' or 'b'?)"`` for the valid names closest to ``name`` (also its
    last path part: a plate's name without its family), or ``""`` where none is close."""
    valid = list(dict.fromkeys(str(v) for v in valid))
    text = str(name)
    found = difflib.get_close_matches(text, valid, n=n, cutoff=CUTOFF)
    if not found:
        tails = {v.rsplit("/", 1)[-1]: v for v in valid}
        found = [tails[t] for t in difflib.get_close_matches(text, list(tails), n=n, cutoff=CUTOFF)]
    if not found:
        return ""
    return " (did you mean " + " or ".join(repr(f) for f in found) + "?)"
