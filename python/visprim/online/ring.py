"""A fixed-capacity ring buffer of frames addressed by absolute frame index."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["FrameRing"]


class FrameRing:
    """The last ``capacity`` frames of a ``(channels,)``-per-frame stream.

    Frames are numbered from 0 in arrival order; :meth:`window` returns frames ``[a, b)``
    as long as they are still held. Memory is ``capacity × channels`` float64, allocated
    once.
    """

    def __init__(self, capacity: int, channels: int) -> None:
        if capacity < 2 or channels < 1:
            raise ValueError(f"need capacity >= 2 and channels >= 1, got {capacity}, {channels}")
        self.capacity = int(capacity)
        self._data = np.zeros((self.capacity, int(channels)))
        self.end = 0  #: absolute index one past the newest frame

    @property
    def start(self) -> int:
        """Absolute index of the oldest frame held."""
        return max(0, self.end - self.capacity)

    @property
    def nbytes(self) -> int:
        return int(self._data.nbytes)

    def extend(self, rows: NDArray[np.float64]) -> None:
        """Append ``(k, channels)`` frames (the oldest are overwritten)."""
        k = rows.shape[0]
        if k == 0:
            return
        cap = self.capacity
        if k >= cap:
            rows = rows[-cap:]
            self.end += k - cap
            k = cap
        i = self.end % cap
        if i + k <= cap:  # one copy (a frame at a time: always)
            self._data[i : i + k] = rows
        else:
            first = cap - i
            self._data[i:] = rows[:first]
            self._data[: k - first] = rows[first:]
        self.end += k

    def window(self, a: int, b: int) -> NDArray[np.float64]:
        """Frames ``[a, b)`` (absolute indices) as a new ``(b - a, channels)`` array."""
        if not self.start <= a <= b <= self.end:
            raise IndexError(f"frames [{a}, {b}) are not held (held: [{self.start}, {self.end}))")
        i = a % self.capacity
        if i + (b - a) <= self.capacity:  # not wrapped: one slice
            return self._data[i : i + (b - a)].copy()
        idx = np.arange(a, b) % self.capacity
        return self._data[idx]

    def frame(self, i: int) -> NDArray[np.float64]:
        if not self.start <= i < self.end:
            raise IndexError(f"frame {i} is not held (held: [{self.start}, {self.end}))")
        return self._data[i % self.capacity]
