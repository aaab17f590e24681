"""Writing one chunk of a Zarr array as Zarr's local store writes it, without Zarr's
asynchronous write path (:class:`ChunkFile`), and removing the temporary files a killed
writer left (:func:`remove_partial_chunks`).

A data set's writer puts two chunks a slide (its samples and its checksum). Through Zarr's
``array[i] = x`` each took about 0.45 ms of CPU beyond the file's own write (its event
loop's thread, the codec pipeline's tasks), about 1 ms of a 9 ms slide of the small sets
(``pvdf2``, the L0 grids). The file is the same: the bytes of the array's own codecs, here
``bytes`` (little endian) and, for the samples, ``zstd`` through numcodecs (the library
Zarr's codec calls), under the chunk's key, written to a temporary name beside it and
renamed, as Zarr does (a run killed between the two leaves a ``.partial`` file that
:func:`remove_partial_chunks` removes). Only arrays in that layout on a local store
take this path; any other, and a chunk that holds the fill value (Zarr removes its file),
go through Zarr. Tested: the files are Zarr's own, byte for byte.
"""

from __future__ import annotations

import os
import re
import stat
import uuid
from pathlib import Path

import numpy as np

from .fs import fs_errors


class ChunkFile:
    """Writes chunks of one array of a Zarr v3 store on the local file system whose chunks
    are whole rows along the first axis (``chunks = (1, *shape[1:])``), encoded by ``bytes``
    little endian then, optionally, ``zstd``: :meth:`for_array` makes one, or None for any
    other array."""

    def __init__(self, folder: Path, key_of, dtype: np.dtype, row_shape: tuple, zstd) -> None:
        self.folder = folder
        self.key_of = key_of
        self.dtype = dtype
        self.row_shape = row_shape
        self.zstd = zstd
        #: the folders this writer has made or found (a chunk's folder is looked for once)
        self._folders: set[Path] = set()

    @classmethod
    def for_array(cls, arr) -> ChunkFile | None:
        """The writer of ``arr``'s chunks, or None where they are not in the layout above
        (then Zarr writes them)."""
        try:
            from zarr.codecs import BytesCodec, ZstdCodec
            from zarr.core.metadata.v3 import ArrayV3Metadata
            from zarr.storage import LocalStore
        except ImportError:  # another Zarr: its own path
            return None
        meta, store = arr.metadata, arr.store
        if not isinstance(meta, ArrayV3Metadata) or not isinstance(store, LocalStore):
            return None
        shape, chunks = tuple(arr.shape), tuple(arr.chunks)
        if chunks != (1, *shape[1:]) or len(meta.codecs) not in (1, 2):
            return None
        if not isinstance(meta.codecs[0], BytesCodec) or meta.codecs[0].endian.value != "little":
            return None
        zstd = None
        if len(meta.codecs) == 2:
            z = meta.codecs[1]
            if not isinstance(z, ZstdCodec):
                return None
            from numcodecs import Zstd

            zstd = Zstd(level=z.level, checksum=z.checksum)
        dtype = np.dtype(arr.dtype).newbyteorder("<")
        folder = Path(store.root) / arr.path
        return cls(folder, meta.chunk_key_encoding.encode_chunk_key, dtype, shape[1:], zstd)

    def write(self, i: int, row: np.ndarray) -> None:
        """Write row ``i`` (of the array's row shape; not all of it the fill value)."""
        data = np.ascontiguousarray(row, dtype=self.dtype).reshape(self.row_shape).tobytes()
        if self.zstd is not None:
            data = self.zstd.encode(data)
        path = self.folder / self.key_of((i,) + (0,) * len(self.row_shape))
        if path.parent not in self._folders:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._folders.add(path.parent)
        tmp = path.with_suffix(f".{uuid.uuid4().hex}.partial")
        try:
            with open(tmp, "wb") as f:
                f.write(data)
            os.replace(tmp, path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise


#: the temporary name Zarr's local store writes a file under before renaming it
#: (``<name>.<hex digits>.partial``, 32 of them; ``zarr.json`` becomes ``zarr.<hex>.partial``)
_ZARR_PARTIAL = re.compile(r".+\.[0-9a-f]+\.partial")


def remove_partial_chunks(path: str | Path) -> int:
    """Remove the files a killed writer left half written (Zarr, and :class:`ChunkFile`,
    write each chunk to ``<chunk>.<hex>.partial`` and rename it; ``kill -9`` between the two
    leaves the temporary file, which no read uses). Only files of that name, in the store's own
    folders: never a folder (a killed export's temporary folder inside the store is not
    the store's), nothing in a hidden folder. The caller holds the store's lock, so no
    writer is between the two now. Returns how many were removed."""
    n = 0
    with fs_errors(Path(path)):
        for folder, dirs, files in os.walk(path):
            dirs[:] = [d for d in dirs if not d.startswith(".")]  # the store's are never hidden
            for name in files:
                f = Path(folder) / name
                if _ZARR_PARTIAL.fullmatch(name) and stat.S_ISREG(f.lstat().st_mode):
                    f.unlink(missing_ok=True)
                    n += 1
    return n
