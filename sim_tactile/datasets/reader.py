"""Reading a data set from its store lazily: :class:`SlideStore` and :func:`open_store`.

Everything served is checked first (:mod:`.integrity`): opening checks the attributes, the
arrays' metadata files and the index arrays against their digests; every slide read is
checked against its checksum. A fault is a :class:`~sim_tactile.errors.StoreError` naming
the slide or array and the damage, never a value read wrong.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ..errors import StoreError
from ..records import Recording, TactileDataset
from .integrity import SLIDE_HINT, compare_index, damaged_index, reading
from .store import (
    PARAM_NAMES,
    check_slide,
    open_data,
    open_root,
    plate_maps,
    read_checksums,
    rows_damage,
)


def parts_of(path: str | Path) -> list[str]:
    """The part groups of a suite's store ([] for a store holding one data set)."""
    return list(open_root(path).attrs.get("parts") or [])


class SlideStore:
    """A data set in a store, read lazily: the per-slide indices (labels, seeds, parameters)
    are loaded (and checked against their digests) on open, the samples only when a slide is
    read; every read checks the slide's checksum. ``len(store)`` slides; ``store[i]`` is
    slide ``i``'s ``(T_i, N)`` samples; iterating yields ``(samples, label)`` pairs one slide
    at a time."""

    def __init__(self, group, path: Path) -> None:
        self.path = Path(path)
        self._where = repr(str(self.path))
        dg = open_data(group, self.path, self._where)
        if dg.damage:
            raise damaged_index(self._where, dg.damage)
        self.group = group
        self.meta: dict = dg.attrs
        self._key = str(self.meta["config_hash"])
        self.labels: np.ndarray = dg.index["labels"]
        self.lengths: np.ndarray = dg.index["lengths"]
        self.slide_numbers: np.ndarray = dg.index["slide"]
        self.seeds: np.ndarray = dg.index["seed"]
        p = dg.index["params"]
        self.params: dict[str, np.ndarray] = {k: p[:, j] for j, k in enumerate(PARAM_NAMES)}
        self.data = dg.arrays["data"]  # the Zarr array itself: slicing reads only those chunks
        self._checksum = dg.arrays["checksum"]
        self.class_names = tuple(self.meta["class_names"])
        self.channel_names = tuple(self.meta["channel_names"])
        self.rate_hz = float(self.meta["rate_hz"])
        self.units = str(self.meta["units"])
        pos = self.meta.get("taxel_positions")
        self.taxel_positions = None if pos is None else np.asarray(pos, dtype=np.float64)

    @property
    def config(self) -> dict:
        return self.meta["config"]

    def plates(self) -> list:
        """The plates of a simulated data set, re-created from what the store records (their
        parameters, and a height-map plate's samples, checked against its SHA-256), in class
        order: no file the configuration named is needed."""
        from ..plates import Plate

        params = self.config.get("plate_params")
        if params is None:
            raise StoreError(f"{self._where} records no plates (not a simulated data set)")
        maps = plate_maps(self.group, self.meta, self._where)
        return [
            Plate.from_params(p, name=name, maps=maps)
            for p, name in zip(params, self.class_names, strict=True)
        ]

    @property
    def config_hash(self) -> str:
        return self.meta["config_hash"]

    @property
    def complete(self) -> bool:
        return bool(self.meta.get("complete")) or bool(self.checksums().all())

    def checksums(self) -> np.ndarray:
        """Each slide's checksum (0: not written, or its checksum chunk is unreadable)."""
        return read_checksums(self._checksum, self._where)[0]

    def index_arrays(self) -> dict[str, np.ndarray]:
        """The index arrays as stored (name -> values), e.g. to compare with a configuration."""
        params = np.stack([self.params[k] for k in PARAM_NAMES], axis=1)
        return {
            "lengths": self.lengths,
            "labels": self.labels,
            "slide": self.slide_numbers,
            "seed": self.seeds,
            "params": params,
        }

    def check_against(self, expected: dict[str, np.ndarray]) -> None:
        """Raise unless the index arrays equal ``expected`` (e.g. ``StoreSpec.index()`` of the
        configuration derived again), naming the first array and slide that differ."""
        compare_index(self.index_arrays(), expected, self._where)

    def __len__(self) -> int:
        return int(self.labels.shape[0])

    def _index(self, i: int) -> int:
        n = len(self)
        if not isinstance(i, int | np.integer) or not -n <= i < n:
            raise IndexError(f"slide index {i} out of range; valid: [{-n}, {n - 1}]")
        return int(i) % n

    def _damaged(self, i: int, why: str) -> StoreError:
        return StoreError(f"slide {i} of {self._where}: {why}; {SLIDE_HINT}")

    def _sums(self, a: int, b: int) -> np.ndarray:
        try:
            return np.asarray(self._checksum[a:b], dtype=np.uint64)
        except Exception:
            sums, bad = read_checksums(self._checksum, self._where)
            for i in range(a, b):
                if i in bad:
                    raise self._damaged(i, bad[i]) from None
            return sums[a:b]

    def _rows(self, a: int, b: int) -> np.ndarray:
        """Slides ``a..b-1`` as stored ``(b - a, T, N)``, each checked against its checksum."""
        sums = self._sums(a, b)
        try:
            x = np.asarray(self.data[a:b])
        except Exception as exc:
            if b - a == 1:
                msg = " ".join(str(exc).split())[:120]
                raise self._damaged(a, f"chunk unreadable ({type(exc).__name__}: {msg})") from None
            for k in range(a, b):
                self._rows(k, k + 1)  # raises naming the slide
            raise
        bad = rows_damage(x, self.lengths[a:b], sums, a, self._key)
        if bad:
            raise self._damaged(*bad)
        return x

    def __getitem__(self, i: int) -> np.ndarray:
        i = self._index(i)
        return self._rows(i, i + 1)[0, : int(self.lengths[i])]

    def __iter__(self) -> Iterator[tuple[np.ndarray, int]]:
        for i in range(len(self)):
            yield self[i], int(self.labels[i])

    def batches(self, size: int = 256) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """``(samples (b, T, N), labels (b,))`` for consecutive slides, ``size`` at a time
        (one read per batch; the slides must have one length)."""
        if (self.lengths != self.data.shape[1]).any():
            raise StoreError("batches needs slides of one length; index slides instead")
        for a in range(0, len(self), size):
            b = min(a + size, len(self))
            yield self._rows(a, b), self.labels[a:b].copy()

    def padded_batches(self, size: int = 256) -> Iterator[tuple[int, np.ndarray]]:
        """``(first slide, samples (b, T, N))``, NaN past each slide's length: every slide,
        checked, ``size`` at a time (what exports copy)."""
        for a in range(0, len(self), size):
            yield a, self._rows(a, min(a + size, len(self)))

    def verify(self) -> list[tuple[int, str]]:
        """Check the whole data set as it is on disk now: the attributes, the arrays'
        metadata, the index arrays and the plate maps (a fault there raises
        :class:`StoreError`), then every slide; returns ``(slide, reason)`` of every slide
        that is absent or fails its checksum."""
        dg = open_data(self.group, self.path, self._where)
        if dg.damage:
            raise damaged_index(self._where, dg.damage)
        plate_maps(self.group, dg.attrs, self._where)
        sums, bad = read_checksums(self._checksum, self._where)
        out = []
        for i in range(len(self)):
            why = bad.get(i) or check_slide(self.data, self.lengths, i, int(sums[i]), self._key)
            if why:
                out.append((i, why))
        return out

    def recording(self, i: int) -> Recording:
        """Slide ``i`` as a :class:`Recording` (times, taxels, units, per-slide metadata)."""
        i = self._index(i)
        x = self[i]
        pos = self.taxel_positions
        if pos is None:
            pos = np.full((x.shape[1], 3), np.nan)
        meta = {
            "rate_hz": self.rate_hz,
            "class": self.class_names[int(self.labels[i])],
            "label": int(self.labels[i]),
            "slide": int(self.slide_numbers[i]),
            "seed": int(self.seeds[i]),
            "params": {k: _num(v[i]) for k, v in self.params.items()},
            "store": str(self.path),
            "config_hash": self.config_hash,
            "channel_names": list(self.channel_names),
        }
        return Recording(x, (np.arange(x.shape[0]) + 0.5) / self.rate_hz, pos, self.units, meta)

    def missing(self) -> int:
        """The number of slides not written (or whose checksum chunk is unreadable)."""
        return int((self.checksums() == 0).sum())

    def require_complete(self, what: str = "") -> None:
        """Raise unless every slide is written (naming a slide whose checksum chunk is
        unreadable, else how many are missing)."""
        sums, bad = read_checksums(self._checksum, self._where)
        for i, why in bad.items():
            raise self._damaged(i, why)
        missing = int((sums == 0).sum())
        if missing:
            raise StoreError(
                f"{self._where} is incomplete: {missing} of {len(self)} slides are not "
                f"written; finish it with 'sim-tactile generate ... --resume'{what}"
            )

    def to_tactile(self) -> TactileDataset:
        """The whole data set in memory, as the classifiers and protocols take it."""
        if len(set(self.lengths.tolist())) != 1:
            raise StoreError(
                f"{self._where}: slides of several lengths ({sorted(set(self.lengths))}); "
                "a TactileDataset needs one length: crop them first"
            )
        self.require_complete()
        x = np.concatenate([b for b, _ in self.batches()]) if len(self) else None
        meta = dict(self.meta.get("dataset_meta") or {})
        meta.update(
            store=str(self.path),
            config_hash=self.config_hash,
            simulate_s=0.0,
            slides_simulated=0,
            slides_cached=len(self),
            sim_warnings=[f"{w} (x{c})" for w, c in (self.meta.get("sim_warnings") or {}).items()],
        )
        return TactileDataset(
            x,
            self.labels,
            self.rate_hz,
            self.channel_names,
            self.class_names,
            self.taxel_positions,
            self.units,
            meta,
        )

    def describe(self) -> dict:
        return {
            "path": str(self.path),
            "name": self.meta.get("name"),
            "slides": len(self),
            "written": len(self) - self.missing(),
            "config_hash": self.config_hash,
            "classes": list(self.class_names),
            "channels": len(self.channel_names),
            "n_time": int(self.meta["n_time"]),
            "rate_hz": self.rate_hz,
            "units": self.units,
        }


def _num(v) -> float | None:
    v = float(v)
    return v if math.isfinite(v) else None


def open_store(path: str | Path, part: str | None = None) -> SlideStore:
    """Open a data set written by ``sim-tactile generate`` (or :func:`from_tactile`) for
    reading. A suite's store (e.g. ``textures20-v1``) holds one data set per part: name it
    with ``part`` (or open ``path/part``)."""
    path = Path(path)
    if not path.exists():
        raise StoreError(f"data set {str(path)!r} does not exist")
    root = open_root(path)
    parts = list(root.attrs.get("parts") or [])
    if part is None:
        if parts:
            raise StoreError(
                f"{str(path)!r} holds the parts of {root.attrs.get('suite')}: open one with "
                f"part=... ({', '.join(parts)})"
            )
        return SlideStore(root, path)
    if part not in parts:
        raise StoreError(
            f"{str(path)!r} has no part {part!r}; valid: {', '.join(parts) or '(none)'}"
        )
    with reading(repr(str(path / part)), "its zarr.json"):
        group = root[part]
    return SlideStore(group, path / part)
