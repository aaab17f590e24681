"""Everything a store serves is checked: its attributes, every array's metadata file and
every index array's values against digests written when the store was made.

- The attributes of each group carry ``attrs_sha256``, the SHA-256 of the canonical JSON of
  all its other attributes (updated with them, in the same atomic write of ``zarr.json``),
  and are checked for type and range, so a crafted or damaged ``zarr.json`` is refused
  before any of it is used (no huge allocation, no path out of the store).
- ``integrity.files``: the SHA-256 of each array's (and sub-group's) ``zarr.json`` and of
  each index array's chunk files, written once when the store is made: a changed shape,
  chunk grid, codec or fill value is found, and any flipped bit of an index chunk (even one
  that decodes to the same values).
- ``integrity.values``: the SHA-256 of each index array (``lengths``, ``labels``, ``slide``,
  ``seed``, ``params``) and of each stored height map: a flipped bit in their chunks is
  found even where it still decodes.
- A slide's samples carry their own checksum (the ``checksum`` array, keyed by the slide's
  index and the configuration: :func:`slide_digest`), so a chunk moved to another slide is
  found too.

Every fault becomes one :class:`~sim_tactile.errors.StoreError` naming the store, the array
or slide and the damage, and saying what to do.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..errors import StoreError
from ..hashing import array_digest, content_hash, file_digest

FORMAT = "sim_tactile.slides"
#: 2: digests of the attributes, metadata files and index arrays; slide checksums keyed by
#: the slide's index and the configuration
FORMAT_VERSION = 2
#: the columns of ``params``: as drawn for each slide (NaN for measured data)
PARAM_NAMES = ("speed_m_s", "force_n", "offset_y_m")
#: the per-slide arrays other than the samples, and their types
INDEX_DTYPES = {
    "lengths": "int64",
    "labels": "int64",
    "slide": "int64",
    "seed": "uint64",
    "params": "float64",
}
DIGEST_ATTR = "attrs_sha256"
#: generous bounds on what a store's metadata may claim (a crafted store must not make a
#: reader allocate without limit)
MAX_SLIDES = 10**8
MAX_TIME = 10**8
MAX_CHANNELS = 10**6
MAX_SLIDE_VALUES = 10**8  # samples x channels of one slide (400 MB)
#: the index arrays' chunks hold this many slides (fewer where the data set is smaller)
INDEX_CHUNK = 65536
#: names a store's metadata may use as a folder: a part of a suite, an array
_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,199}")

SLIDE_HINT = (
    "datasets.open(...).verify() lists every damaged slide; 'sim-tactile generate ... "
    "--resume' writes them again"
)
INDEX_HINT = "'sim-tactile generate ... --resume' writes it again from the configuration"
REMAKE_HINT = "the store cannot be trusted: generate it again into a new --out"


def config_hash(config: dict) -> str:
    """The content hash (16 hex digits) of a configuration."""
    return content_hash(config, 16)


def slide_digest(x: np.ndarray, index: int, key: str) -> int:
    """The checksum of slide ``index``'s samples in the data set of configuration hash
    ``key``: never 0 (0 marks an absent slide)."""
    x = np.ascontiguousarray(x, dtype="<f4")
    h = hashlib.sha256(f"{key}:{int(index)}:{x.shape}".encode())
    h.update(x.tobytes())
    return int.from_bytes(h.digest()[:8], "little") or 1


def values_digest(x: np.ndarray) -> str:
    """SHA-256 of an array's type, shape and values (little-endian, whatever the machine)."""
    x = np.asarray(x)
    return array_digest(x.astype(x.dtype.newbyteorder("<"), copy=False))


def _plain_default(obj):
    if hasattr(obj, "tolist"):  # numpy scalars and arrays
        return obj.tolist()
    raise TypeError(f"{type(obj).__name__} is not JSON data")


def plain(obj: object) -> object:
    """``obj`` as it reads back from ``zarr.json`` (tuples as lists, numpy as Python)."""
    return json.loads(json.dumps(obj, default=_plain_default, allow_nan=True))


def attrs_digest(attrs: dict) -> str:
    """SHA-256 of the canonical JSON of a group's attributes, its own digest left out."""
    return content_hash({k: v for k, v in attrs.items() if k != DIGEST_ATTR})


def sealed(attrs: dict) -> dict:
    """``attrs`` in plain JSON types with their digest (what a group's ``zarr.json`` holds)."""
    out = plain({k: v for k, v in attrs.items() if k != DIGEST_ATTR})
    out[DIGEST_ATTR] = attrs_digest(out)
    return out


@contextmanager
def reading(where: str, what: str, hint: str = REMAKE_HINT) -> Iterator[None]:
    """Any failure to read or decode ``what`` as one :class:`StoreError`."""
    try:
        yield
    except StoreError:
        raise
    except Exception as exc:
        msg = " ".join(str(exc).split())[:160]
        raise StoreError(
            f"{where}: {what} cannot be read ({type(exc).__name__}: {msg}); it is damaged: {hint}"
        ) from None


def plain_name(name: object) -> bool:
    """Whether ``name`` is a plain relative name (no folder, no ``..``, no absolute path)."""
    return isinstance(name, str) and bool(_NAME.fullmatch(name)) and name not in (".", "..")


def _bad(where: str, key: str, value: object, want: str) -> StoreError:
    text = repr(value)
    text = text if len(text) <= 60 else text[:57] + "..."
    return StoreError(
        f"{where}: attribute {key} = {text} is not valid ({want}): the store's metadata is "
        f"damaged or was not written by sim_tactile; {REMAKE_HINT}"
    )


def _int_in(attrs: dict, key: str, lo: int, hi: int, where: str) -> int:
    v = attrs.get(key)
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise _bad(where, key, v, f"an integer in [{lo}, {hi}]")
    return v


def _names(attrs: dict, key: str, hi: int, where: str) -> list[str]:
    v = attrs.get(key)
    if not isinstance(v, list) or not 1 <= len(v) <= hi or not all(isinstance(s, str) for s in v):
        raise _bad(where, key, v, f"a list of 1 to {hi} names")
    return v


def _typed(attrs: dict, where: str, **types) -> None:
    for key, t in types.items():
        if not isinstance(attrs.get(key), t):
            names = " or ".join(x.__name__ for x in (t if isinstance(t, tuple) else (t,)))
            raise _bad(where, key, attrs.get(key), f"{names} expected")


def check_root_attrs(attrs: object, where: str) -> dict:
    """A store's root attributes: its format, version and digest; a suite's part names."""
    if not isinstance(attrs, dict) or attrs.get("format") != FORMAT:
        raise StoreError(f"{where} is a Zarr store but not a sim_tactile data set")
    v = attrs.get("format_version")
    if v != FORMAT_VERSION:
        if isinstance(v, int) and not isinstance(v, bool) and 0 < v < FORMAT_VERSION:
            raise StoreError(
                f"{where} was made by an older version of sim_tactile (store format {v}; "
                f"this version reads format {FORMAT_VERSION}): generate it again"
            )
        raise StoreError(
            f"{where} has store format {v!r}; this version of sim_tactile reads format "
            f"{FORMAT_VERSION} (a newer sim_tactile made it, or it is damaged)"
        )
    if attrs.get(DIGEST_ATTR) != attrs_digest(attrs):
        raise StoreError(
            f"{where}: its attributes (zarr.json) do not match their digest: altered or "
            f"damaged; {REMAKE_HINT}"
        )
    if "runs" in attrs:
        _typed(attrs, where, runs=list)
    parts = attrs.get("parts")
    if parts is not None:
        if (
            not isinstance(parts, list)
            or not parts
            or len(set(map(str, parts))) != len(parts)
            or not all(plain_name(p) for p in parts)
        ):
            raise _bad(where, "parts", parts, "distinct plain folder names, no path")
        _typed(attrs, where, suite=str, config_hash=str)
    return attrs


def check_data_attrs(attrs: dict, where: str) -> dict:
    """A data set's group attributes, checked for type, range and consistency."""
    check_root_attrs(attrs, where)
    _typed(
        attrs,
        where,
        name=str,
        config=dict,
        config_hash=str,
        code_version=(str, type(None)),
        units=str,
        dataset_meta=dict,
        complete=bool,
        sim_warnings=dict,
        integrity=dict,
    )
    if attrs["config_hash"] != config_hash(attrs["config"]):
        raise _bad(where, "config_hash", attrs["config_hash"], "the hash of its config")
    _int_in(attrs, "n_slides", 0, MAX_SLIDES, where)
    _int_in(attrs, "n_time", 1, MAX_TIME, where)
    _names(attrs, "class_names", MAX_SLIDES, where)
    channels = _names(attrs, "channel_names", MAX_CHANNELS, where)
    if attrs["n_time"] * len(channels) > MAX_SLIDE_VALUES:
        raise _bad(where, "n_time", attrs["n_time"], f"n_time x channels <= {MAX_SLIDE_VALUES}")
    rate = attrs.get("rate_hz")
    if isinstance(rate, bool) or not isinstance(rate, int | float) or not 0 < rate < math.inf:
        raise _bad(where, "rate_hz", rate, "a positive number")
    if attrs.get("param_names") != list(PARAM_NAMES):
        raise _bad(where, "param_names", attrs.get("param_names"), f"{list(PARAM_NAMES)}")
    pos = attrs.get("taxel_positions")
    if pos is not None:
        try:
            ok = np.asarray(pos, dtype=np.float64).shape == (len(channels), 3)
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise _bad(where, "taxel_positions", pos, f"({len(channels)}, 3) numbers or null")
    integ = attrs["integrity"]
    for key in ("files", "values"):
        d = integ.get(key)
        if not isinstance(d, dict) or not all(isinstance(s, str) for s in d.values()):
            raise _bad(where, f"integrity.{key}", d, "names and digests")
    need = {f"{a}/zarr.json" for a in ("data", "checksum", *INDEX_DTYPES)}
    if not need <= set(integ["files"]) or not set(INDEX_DTYPES) <= set(integ["values"]):
        raise _bad(where, "integrity", integ, "a digest of every array")
    _check_claimed_slides(attrs, where)
    return attrs


def _check_claimed_slides(attrs: dict, where: str) -> None:
    """``n_slides`` against the chunk files of ``lengths`` the store recorded when it was
    made: every one is written (a slide's length is at least 1, never the fill value 0), so
    a store of ``n`` slides records exactly ``ceil(n / INDEX_CHUNK)`` of them. A claim of
    more slides than the store holds is refused here, before any array is read (a store
    claiming 10^8 slides had its readers read for minutes, and print thousands of lines)."""
    n = attrs["n_slides"]
    want = {f"lengths/c/{k}" for k in range(math.ceil(n / INDEX_CHUNK))}
    got = {k for k in attrs["integrity"]["files"] if k.startswith("lengths/")} - {
        "lengths/zarr.json"
    }
    if got != want:
        held = f"{len(got)} chunk file(s) of lengths recorded, for {len(want)} expected"
        raise _bad(where, "n_slides", n, held)


def chunk_files(folder: Path, name: str) -> dict[str, str]:
    """``{relative path: digest}`` of the chunk files of the array ``name`` in ``folder``
    (an index array's chunks are written once, with the store: their bytes are recorded)."""
    base = folder / name / "c"
    files = sorted(p for p in base.rglob("*") if p.is_file()) if base.is_dir() else []
    return {p.relative_to(folder).as_posix(): file_digest(p) for p in files}


def check_files(folder: Path, attrs: dict, where: str) -> dict[str, str]:
    """Every file the group's ``integrity.files`` names, against its digest: a metadata
    file that fails raises; an index array's chunk file that fails (or is missing) is
    returned as that array's damage (``{array: damage}``: ``--resume`` writes it again)."""
    damage = {}
    for rel, want in attrs["integrity"]["files"].items():
        parts = rel.split("/")
        if not all(plain_name(p) for p in parts):
            raise _bad(where, "integrity.files", rel, "relative names inside the store")
        chunk = parts[0] in INDEX_DTYPES and len(parts) > 2 and parts[1] == "c"
        with reading(where, rel):
            got = file_digest(folder / rel)
        if got == want:
            continue
        if chunk:
            damage.setdefault(parts[0], f"its chunk file {rel} is altered, truncated or missing")
            continue
        what = "is missing" if got == "absent" else "does not match its digest (altered or damaged)"
        raise StoreError(f"{where}: {rel} {what}; {REMAKE_HINT}")
    return damage


def array_layout(attrs: dict) -> dict[str, tuple[tuple, tuple | None, str]]:
    """``name -> (shape, chunks or None (any), dtype)`` of a data set's arrays: their chunks
    as the writer makes them, so a crafted chunk grid cannot make a reader read millions of
    chunks."""
    n, t, c = attrs["n_slides"], attrs["n_time"], len(attrs["channel_names"])
    out: dict[str, tuple[tuple, tuple | None, str]] = {
        "data": ((n, t, c), (1, t, c), "float32"),
        "checksum": ((n,), (1,), "uint64"),
    }
    rows = min(n, INDEX_CHUNK) or None  # (an empty data set's chunks: any)
    for name, dtype in INDEX_DTYPES.items():
        if name == "params":
            out[name] = ((n, len(PARAM_NAMES)), rows and (rows, len(PARAM_NAMES)), dtype)
        else:
            out[name] = ((n,), rows and (rows,), dtype)
    return out


def check_arrays(group, attrs: dict, where: str) -> dict:
    """The group's arrays, opened and checked against the attributes' shapes."""
    out = {}
    for name, (shape, chunks, dtype) in array_layout(attrs).items():
        with reading(where, f"the array {name!r}"):
            a = group[name]
            ok = (
                tuple(a.shape) == shape
                and str(a.dtype) == dtype
                and (chunks is None or tuple(a.chunks) == chunks)
            )
        if not ok:
            raise StoreError(
                f"{where}: the array {name!r} is {tuple(a.shape)} {a.dtype}, the attributes "
                f"say {shape} {dtype}; {REMAKE_HINT}"
            )
        out[name] = a
    with reading(where, "the array 'checksum'"):
        if int(out["checksum"].fill_value) != 0:
            raise StoreError(f"{where}: the checksum array's fill value is not 0; {REMAKE_HINT}")
    return out


def index_values(arrays: dict, attrs: dict, where: str) -> tuple[dict, dict[str, str]]:
    """The index arrays' values, and ``{name: damage}`` for those that fail to read or to
    match their digest (or hold values out of range)."""
    values, damage = {}, {}
    for name in INDEX_DTYPES:
        try:
            with reading(where, f"the array {name!r}", INDEX_HINT):
                x = np.asarray(arrays[name][...])
        except StoreError:
            damage[name] = "its chunks cannot be read (truncated or altered)"
            continue
        if values_digest(x) != attrs["integrity"]["values"][name]:
            damage[name] = "its values do not match their digest (altered or damaged)"
        values[name] = x
    if not damage:
        t, k = attrs["n_time"], len(attrs["class_names"])
        if values["labels"].size and not (
            0 <= values["labels"].min() <= values["labels"].max() < k
        ):
            damage["labels"] = f"labels outside [0, {k - 1}]"
        if values["lengths"].size and not (
            1 <= values["lengths"].min() <= values["lengths"].max() <= t
        ):
            damage["lengths"] = f"lengths outside [1, {t}]"
    return values, damage


def damaged_index(where: str, damage: dict[str, str]) -> StoreError:
    what = "; ".join(f"the array {k!r}: {v}" for k, v in damage.items())
    return StoreError(f"{where}: {what}; {INDEX_HINT}")


def compare_index(values: dict, expected: dict, where: str) -> None:
    """The index arrays against the ones the configuration gives (derived again from it):
    raises naming the first array and slide that differ."""
    for name, want in expected.items():
        got = values[name]
        if got.shape != want.shape:
            raise StoreError(
                f"{where}: the array {name!r} has shape {got.shape}, the configuration gives "
                f"{want.shape}; {REMAKE_HINT}"
            )
        same = got == want
        if got.dtype.kind == "f":
            same |= np.isnan(got) & np.isnan(want)
        if not same.all():
            i = int(np.flatnonzero(~same.reshape(len(got), -1).all(axis=1))[0])
            raise StoreError(
                f"{where}: {name} of slide {i} is {got[i].tolist()}, its configuration gives "
                f"{want[i].tolist()}: the store does not hold this configuration's data set; "
                "generate it again"
            )
