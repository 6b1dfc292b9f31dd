"""Append-only tables of simulation results that spill to disk: memory bounded whatever the
length of the playback.

A :class:`TraceWriter` collects rows (each of one shape and dtype) a block at a time. While
the rows fit in :data:`SPILL_BYTES` they stay in memory and :meth:`TraceWriter.finish`
returns a plain numpy array; beyond that they are written to an anonymous temporary file
(:func:`tempfile.TemporaryFile`: already unlinked, so nothing is left behind however the
process ends) and :meth:`~TraceWriter.finish` returns a :class:`Trace`, which reads rows
back on demand (``trace[i]``, ``trace[a:b]``, ``trace[idx]``, ``trace[rows, cols]``;
``np.asarray(trace)`` loads it all). Memory then holds one block, not the table.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import DTypeLike, NDArray

__all__ = ["SPILL_BYTES", "Trace", "TraceWriter", "blocks"]

#: A table larger than this many bytes is kept on disk rather than in memory.
SPILL_BYTES = 32 * 1024 * 1024
#: Rows read at once when gathering scattered rows from disk.
_READ_ROWS = 1 << 15


class Trace:
    """Rows ``(n, *row_shape)`` of ``dtype`` in a temporary file (see the module docstring).
    Indexing returns numpy arrays; the file closes with the object."""

    def __init__(self, fh: Any, n: int, row_shape: tuple[int, ...], dtype: DTypeLike) -> None:
        self._fh = fh
        self._fd = fh.fileno()
        self.dtype = np.dtype(dtype)
        self.row_shape = tuple(row_shape)
        self.shape = (int(n), *self.row_shape)
        self._row_bytes = int(self.dtype.itemsize * int(np.prod(self.row_shape, dtype=np.int64)))

    @property
    def ndim(self) -> int:
        return len(self.shape)

    def __len__(self) -> int:
        return self.shape[0]

    def _read(self, start: int, stop: int) -> NDArray[Any]:
        """Rows ``start:stop`` (contiguous) read from the file."""
        count = max(0, stop - start)
        nbytes = count * self._row_bytes
        buf = bytearray(nbytes)
        view = memoryview(buf)
        done = 0
        while done < nbytes:
            got = os.preadv(self._fd, [view[done:]], start * self._row_bytes + done)
            if got <= 0:
                raise OSError(f"trace file ended early ({done} of {nbytes} bytes)")
            done += got
        return np.frombuffer(buf, dtype=self.dtype).reshape(count, *self.row_shape)

    def _gather(self, idx: NDArray[np.int64]) -> NDArray[Any]:
        n = self.shape[0]
        if idx.size and (idx.min() < -n or idx.max() >= n):
            raise IndexError(f"index out of range for a trace of {n} rows")
        idx = np.where(idx < 0, idx + n, idx)
        out = np.empty((idx.size, *self.row_shape), dtype=self.dtype)
        order = np.argsort(idx, kind="stable")
        sorted_idx = idx[order]
        i = 0
        while i < sorted_idx.size:
            lo = int(sorted_idx[i])
            j = int(np.searchsorted(sorted_idx, lo + _READ_ROWS, side="left"))
            hi = int(sorted_idx[j - 1]) + 1
            block = self._read(lo, hi)
            out[order[i:j]] = block[sorted_idx[i:j] - lo]
            i = j
        return out

    def _rows(self, key: Any) -> NDArray[Any]:
        n = self.shape[0]
        if isinstance(key, (int, np.integer)):
            k = int(key) + (n if int(key) < 0 else 0)
            if not 0 <= k < n:
                raise IndexError(f"index {int(key)} out of range for a trace of {n} rows")
            return self._read(k, k + 1)[0]
        if isinstance(key, slice):
            start, stop, step = key.indices(n)
            if step == 1:
                return self._read(start, stop)
            return self._gather(np.arange(start, stop, step, dtype=np.int64))
        arr = np.asarray(key)
        if arr.dtype == bool:
            if arr.shape != (n,):
                raise IndexError(f"boolean index of shape {arr.shape} for {n} rows")
            arr = np.flatnonzero(arr)
        if not np.issubdtype(arr.dtype, np.integer):
            raise IndexError(f"a trace is indexed by integers, slices or masks, got {arr.dtype}")
        return self._gather(arr.astype(np.int64).ravel()).reshape(*arr.shape, *self.row_shape)

    def __getitem__(self, key: Any) -> Any:
        if isinstance(key, tuple):
            if not key:
                return self._rows(slice(None))
            rows = self._rows(key[0])
            rest = key[1:]
            scalar_row = isinstance(key[0], (int, np.integer))
            return rows[rest] if scalar_row else rows[(slice(None), *rest)]
        return self._rows(key)

    def __array__(self, dtype: DTypeLike | None = None, copy: bool | None = None) -> NDArray[Any]:
        out = self._read(0, self.shape[0])
        return out if dtype is None else out.astype(dtype)

    def __iter__(self) -> Iterator[NDArray[Any]]:
        for start, block in blocks(self):
            del start
            yield from block

    def __repr__(self) -> str:
        return f"Trace(shape={self.shape}, dtype={self.dtype}, on disk)"


def blocks(table: Any, rows: int = 4096) -> Iterator[tuple[int, NDArray[Any]]]:
    """``(start, rows)`` blocks of an array or :class:`Trace`, in order (memory: one
    block)."""
    n = int(table.shape[0])
    for start in range(0, n, rows):
        yield start, np.asarray(table[start : min(n, start + rows)])


class TraceWriter:
    """Collects rows of ``row_shape`` and ``dtype`` (see the module docstring)."""

    def __init__(
        self, row_shape: tuple[int, ...], dtype: DTypeLike = np.float64, spill_bytes: int = -1
    ) -> None:
        self.row_shape = tuple(int(v) for v in row_shape)
        self.dtype = np.dtype(dtype)
        self.spill_bytes = SPILL_BYTES if spill_bytes < 0 else int(spill_bytes)
        self.n = 0
        self._blocks: list[NDArray[Any]] = []
        self._bytes = 0
        self._fh: Any = None

    def append(self, rows: NDArray[Any]) -> None:
        """Append ``rows`` (k, *row_shape)."""
        block = np.ascontiguousarray(rows, dtype=self.dtype)
        if block.shape[1:] != self.row_shape:
            raise ValueError(f"rows of shape {block.shape[1:]}, the trace's are {self.row_shape}")
        if block.shape[0] == 0:
            return
        self.n += block.shape[0]
        if self._fh is None:
            self._blocks.append(block.copy())
            self._bytes += block.nbytes
            if self._bytes > self.spill_bytes:
                self._fh = tempfile.TemporaryFile(prefix="visprim-trace-")
                for b in self._blocks:
                    self._fh.write(b.tobytes())
                self._blocks, self._bytes = [], 0
        else:
            self._fh.write(block.tobytes())

    def finish(self) -> NDArray[Any] | Trace:
        """The rows: an array if they stayed in memory, else a :class:`Trace`."""
        if self._fh is None:
            if not self._blocks:
                return np.empty((0, *self.row_shape), dtype=self.dtype)
            out = np.concatenate(self._blocks) if len(self._blocks) > 1 else self._blocks[0]
            self._blocks = []
            return out
        self._fh.flush()
        return Trace(self._fh, self.n, self.row_shape, self.dtype)
