"""Reading a data set from its store lazily: :class:`SlideStore` and :func:`open_store`."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ..errors import StoreError
from ..records import Recording, TactileDataset
from .store import FORMAT, PARAM_NAMES, check_slide, open_root, plate_maps, slide_digest


def parts_of(path: str | Path) -> list[str]:
    """The part groups of a suite's store ([] for a store holding one data set)."""
    return list(open_root(path).attrs.get("parts") or [])


class SlideStore:
    """A data set in a store, read lazily: the per-slide indices (labels, seeds, parameters)
    are loaded on open, the samples only when a slide is read; every read checks the slide's
    checksum. ``len(store)`` slides; ``store[i]`` is slide ``i``'s ``(T_i, N)`` samples;
    iterating yields ``(samples, label)`` pairs one slide at a time."""

    def __init__(self, group, path: Path) -> None:
        self.path = path
        self.group = group
        self.meta: dict = group.attrs.asdict()
        if self.meta.get("format") != FORMAT or "data" not in group:
            raise StoreError(f"{str(path)!r} holds no sim_tactile data set")
        self.labels: np.ndarray = group["labels"][:]
        self.lengths: np.ndarray = group["lengths"][:]
        self.slide_numbers: np.ndarray = group["slide"][:]
        self.seeds: np.ndarray = group["seed"][:]
        p = group["params"][:]
        self.params: dict[str, np.ndarray] = {k: p[:, j] for j, k in enumerate(PARAM_NAMES)}
        self.data = group["data"]  # the Zarr array itself: slicing reads only those chunks
        self._checksum = group["checksum"]
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
            raise StoreError(f"{str(self.path)!r} records no plates (not a simulated data set)")
        maps = plate_maps(self.group)
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
        return self._checksum[:]

    def __len__(self) -> int:
        return int(self.labels.shape[0])

    def _index(self, i: int) -> int:
        n = len(self)
        if not isinstance(i, int | np.integer) or not -n <= i < n:
            raise IndexError(f"slide index {i} out of range; valid: [{-n}, {n - 1}]")
        return int(i) % n

    def __getitem__(self, i: int) -> np.ndarray:
        i = self._index(i)
        expected = int(self._checksum[i])
        bad = check_slide(self.data, self.lengths, i, expected)
        if bad:
            raise StoreError(
                f"slide {i} of {str(self.path)!r}: {bad}; 'sim-tactile generate ... --resume' "
                f"writes it again"
            )
        return np.asarray(self.data[i, : int(self.lengths[i])])

    def __iter__(self) -> Iterator[tuple[np.ndarray, int]]:
        for i in range(len(self)):
            yield self[i], int(self.labels[i])

    def batches(self, size: int = 256) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """``(samples (b, T, N), labels (b,))`` for consecutive slides, ``size`` at a time
        (one read per batch; the slides must have one length)."""
        sums = self.checksums()
        for a in range(0, len(self), size):
            b = min(a + size, len(self))
            x = np.asarray(self.data[a:b])
            for k in range(a, b):
                if int(sums[k]) == 0 or slide_digest(x[k - a, : self.lengths[k]]) != sums[k]:
                    self[k]  # raises with the reason
            if (self.lengths[a:b] != x.shape[1]).any():
                raise StoreError("batches needs slides of one length; index slides instead")
            yield x, self.labels[a:b].copy()

    def verify(self) -> list[tuple[int, str]]:
        """``(slide, reason)`` of every slide that is absent or fails its checksum."""
        sums = self.checksums()
        out = []
        for i in range(len(self)):
            bad = check_slide(self.data, self.lengths, i, int(sums[i]))
            if bad:
                out.append((i, bad))
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

    def to_tactile(self) -> TactileDataset:
        """The whole data set in memory, as the classifiers and protocols take it."""
        if len(set(self.lengths.tolist())) != 1:
            raise StoreError(
                f"{str(self.path)!r}: slides of several lengths ({sorted(set(self.lengths))}); "
                "a TactileDataset needs one length: crop them first"
            )
        missing = int((self.checksums() == 0).sum())
        if missing:
            raise StoreError(
                f"{str(self.path)!r} is incomplete: {missing} of {len(self)} slides are not "
                "written; finish it with 'sim-tactile generate ... --resume'"
            )
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
            "written": int((self.checksums() != 0).sum()),
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
    return SlideStore(root[part], path / part)
