"""A user's files read within bounds: their size, and a height map's shape and type, are
checked before their contents are read.

* Every file: at most :data:`MAX_FILE_BYTES`, hashed in blocks (:func:`file_sha256`).
* ``.npy``: its header alone is read first (``numpy.lib.format``); the array must be 2-D,
  of numbers (no object dtype: no pickle) and within :data:`~.spec.MAX_HEIGHTMAP_SAMPLES`,
  and the file exactly as long as the header says, before the samples are read.
* ``.png``: its size is read from the header (Pillow decodes nothing until asked), and must
  be within the same number of samples, before the pixels are decoded; a file Pillow takes
  for a decompression bomb is refused as such.

Every refusal is a :class:`~sim_tactile.errors.ConfigError` naming the file, the value and
the valid range.
"""

from __future__ import annotations

import hashlib
import math
import warnings
from pathlib import Path

import numpy as np

from ...errors import ConfigError
from ..define.spec import MAX_HEIGHTMAP_SAMPLES

#: The largest file read as a part or a height map [bytes]: the largest map (16 M float64
#: samples, 128 MB) with its header, or a binary STL of 2.6 M triangles (50 bytes each), far
#: more than a CAD part needs (the worked example's knurl tessellates into 2,202).
MAX_FILE_BYTES = 128 * 2**20
#: dtype kinds a height map's samples may have: float, signed and unsigned integer.
NUMBER_KINDS = "fiu"


def check_size(path: Path, where: str) -> int:
    """The file's size [bytes]; ConfigError beyond :data:`MAX_FILE_BYTES`."""
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise ConfigError(
            f"{where}: the file is {size / 2**20:.4g} MiB; valid: at most "
            f"{MAX_FILE_BYTES / 2**20:g} MiB"
        )
    return size


def file_sha256(path: Path) -> str:
    """SHA-256 of the file's bytes, read in blocks."""
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def _samples_ok(shape: tuple[int, ...], where: str) -> None:
    n = math.prod(shape)
    if n > MAX_HEIGHTMAP_SAMPLES:
        raise ConfigError(
            f"{where}: the map is {' x '.join(map(str, shape))} = {n} samples; valid: at most "
            f"{MAX_HEIGHTMAP_SAMPLES} (a coarser map, or a part of it)"
        )


def npy_header(path: Path, where: str) -> tuple[tuple[int, ...], np.dtype, int]:
    """``(shape, dtype, the file's length [bytes])`` of a ``.npy`` file, from its header
    alone, checked: 2-D, numbers, within the samples' cap."""
    from numpy.lib import format as npf

    try:
        with open(path, "rb") as fh:
            version = npf.read_magic(fh)
            if version == (1, 0):
                shape, _, dtype = npf.read_array_header_1_0(fh)
            elif version == (2, 0):
                shape, _, dtype = npf.read_array_header_2_0(fh)
            else:
                raise ValueError(f"format version {version[0]}.{version[1]}; valid: 1.0, 2.0")
            offset = fh.tell()
    except (ValueError, OSError, SyntaxError, TypeError) as exc:
        raise ConfigError(f"{where}: not a readable .npy header ({exc})") from None
    if dtype.hasobject or dtype.kind not in NUMBER_KINDS or dtype.shape:
        raise ConfigError(
            f"{where}: the samples' dtype is {dtype!s}; valid: numbers (float or integer), "
            "read without pickles (Python objects are not)"
        )
    if len(shape) != 2:
        raise ConfigError(f"{where}: the array has shape {shape}; valid: a 2-D height map")
    _samples_ok(shape, where)
    return shape, dtype, offset + math.prod(shape) * dtype.itemsize


def read_npy(path: Path, where: str) -> np.ndarray:
    """The samples of a ``.npy`` height map, its header checked first (:func:`npy_header`)
    and the file as long as the header says."""
    shape, dtype, want = npy_header(path, where)
    size = path.stat().st_size
    if size != want:
        raise ConfigError(
            f"{where}: the file is {size} bytes, its header describes {want} ({shape}, "
            f"{dtype!s}); valid: a whole .npy file"
        )
    try:
        return np.load(path, allow_pickle=False)
    except Exception as exc:  # noqa: BLE001  (any parse failure of the user's bytes)
        raise ConfigError(f"{where}: not a readable .npy array without pickles ({exc})") from None


def read_png(path: Path, where: str) -> np.ndarray:
    """The counts of a 16-bit (or 8-bit) grey PNG, rows as in the picture (top row first),
    its size checked from the header before any pixel is decoded."""
    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(path) as im:  # reads the header only
                if im.format != "PNG":
                    raise ConfigError(f"{where}: not a PNG file ({im.format})")
                width, height = im.size
                _samples_ok((height, width), where)
                if im.mode not in ("I;16", "I;16B", "I", "L"):
                    raise ConfigError(
                        f"{where}: PNG mode {im.mode} is not valid; valid: 16-bit grey (or 8-bit)"
                    )
                return np.asarray(im, dtype=np.float64)
    except ConfigError:
        raise
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        raise ConfigError(
            f"{where}: refused as a decompression bomb ({exc}); valid: at most "
            f"{MAX_HEIGHTMAP_SAMPLES} samples"
        ) from None
    except Exception as exc:  # noqa: BLE001
        raise ConfigError(f"{where}: not a readable PNG ({exc})") from None
