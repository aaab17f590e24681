"""The splits of a task's protocol, and their digest."""

from __future__ import annotations

import hashlib

import numpy as np

from ..hashing import derive_seed
from ..learn.protocols import repeated_splits


def task_splits(labels, split: str, repeats: int, seed: int) -> list:
    """The (train, test) index pairs of a task's protocol: ``repeats`` draws of ``split``
    from one generator seeded by ``(seed, 0)``. Each draw follows the ones before it, so the
    first ``k`` pairs are the same whatever ``repeats`` is (a run's rows of fewer repeats take
    the first pairs of the longest)."""
    return repeated_splits(labels, split, repeats, derive_seed(seed, 0))


def splits_digest(pairs) -> str:
    """SHA-256 of a list of (train, test) index pairs (the report's ``splits_sha256``: a
    user's framework can check it uses the same splits)."""
    h = hashlib.sha256()
    for tr, te in pairs:
        h.update(np.asarray(tr, dtype=np.int64).tobytes() + b"|")
        h.update(np.asarray(te, dtype=np.int64).tobytes() + b";")
    return h.hexdigest()
