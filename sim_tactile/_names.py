"""Names a user may mistype (tasks, plates, sensors, classifiers): the closest valid ones,
for the error that refuses the name."""

from __future__ import annotations

import difflib
from collections.abc import Iterable

#: How alike a valid name must be to be offered (difflib's ratio, 0..1): "finger7-v9" finds
#: "finger7-v1" (0.9), "grid3x4" "grid3x3" (0.86), "svm_spike" "svm-spike" (0.89).
CUTOFF = 0.6


def did_you_mean(name: object, valid: Iterable[str], n: int = 3) -> str:
    """``" (did you mean 'a' or 'b'?)"`` for the valid names closest to ``name``, or ``""``
    where none is close. Names of the form ``family/name`` (the plates) are compared by
    their last part, within the family the name gives where it has one: "finger7/ridge-4"
    finds "finger7/ridges-4", "ridges-4" finds it too, and "finger7/nope" finds nothing
    (the shared family is no likeness)."""
    valid = list(dict.fromkeys(str(v) for v in valid))
    text = str(name)
    if any("/" in v for v in valid):
        family, _, tail = text.rpartition("/")
        same = [v for v in valid if v.rpartition("/")[0] == family]
        pool: dict[str, str] = {}
        for v in same or valid:
            pool.setdefault(v.rpartition("/")[2], v)
        found = [pool[t] for t in difflib.get_close_matches(tail, list(pool), n, CUTOFF)]
    else:
        found = difflib.get_close_matches(text, valid, n, CUTOFF)
    if not found:
        return ""
    return " (did you mean " + " or ".join(repr(f) for f in found) + "?)"
