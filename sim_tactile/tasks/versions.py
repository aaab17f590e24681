"""Task ids as families and versions: ``finger7-v2`` is version 2 of the family ``finger7``.

A released id never changes meaning; a change is a new version of its family, which may
supersede an older one (``TaskSpec.supersedes``: the older id still runs, and warns once
that it is out of date, as Gymnasium's environments do). :func:`unknown_task` is the error
of an id that is not registered: the versions of its family, or the ids it is close to.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable

_VERSIONED = re.compile(r"^(?P<family>.+)-v(?P<version>[1-9]\d*)$")


def split_task_id(task_id: str) -> tuple[str, int | None]:
    """``(family, version)`` of an id: ``("finger7", 2)`` for ``finger7-v2``; an id without
    a ``-vN`` ending is its own family, of no version (an alias such as ``biotac20-real``)."""
    m = _VERSIONED.match(task_id)
    if m is None:
        return task_id, None
    return m["family"], int(m["version"])


def unknown_task(task_id: str, known: Iterable[str]) -> str:
    """The one-line error for an unregistered ``task_id``, given the ``known`` ids (and
    aliases): its family's versions where it has a family, else the closest ids, else all."""
    known = list(known)
    family = split_task_id(task_id)[0]
    kin = sorted(
        (t for t in known if split_task_id(t)[1] is not None and split_task_id(t)[0] == family),
        key=lambda t: split_task_id(t)[1],
    )
    if kin:
        versions = ", ".join(f"v{split_task_id(t)[1]}" for t in kin)
        return (
            f"task {task_id!r} is not known; the family {family} has versions {versions}: "
            f"{', '.join(kin)}"
        )
    close = difflib.get_close_matches(task_id, known, n=3, cutoff=0.6)
    if close:
        return (
            f"task {task_id!r} is not known; did you mean {' or '.join(close)}? (every task: "
            "sim-tactile tasks)"
        )
    return f"task {task_id!r} is not known; valid: {', '.join(known) or '(none)'}"
