"""Task ids as families and versions: ``finger7-v2`` is version 2 of the family ``finger7``.

A released id never changes meaning; a change is a new version of its family, which may
supersede an older one (``TaskSpec.supersedes``: the older id still runs, and warns once
that it is out of date, as Gymnasium's environments do). :func:`unknown_task` is the error
of an id that is not registered: the versions of its family, or the ids it is close to.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from .._names import did_you_mean

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
    aliases): the closest ids ("did you mean"), and its family's versions where it has a
    family, else every id."""
    known = list(known)
    family = split_task_id(task_id)[0]
    kin = sorted(
        (t for t in known if split_task_id(t)[1] is not None and split_task_id(t)[0] == family),
        key=lambda t: split_task_id(t)[1],
    )
    head = f"task {task_id!r} is not known{did_you_mean(task_id, known)}"
    if kin:
        versions = ", ".join(f"v{split_task_id(t)[1]}" for t in kin)
        return f"{head}; the family {family} has versions {versions}: {', '.join(kin)}"
    return f"{head}; valid: {', '.join(known) or '(none)'}"
