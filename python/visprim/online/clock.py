"""A stream's frames on the model's clock.

A model learns from recordings resampled to one frame period (``frame_period_``, 34 ms by
default), and its filter's cutoff, SEG-2's local minima and the primitives' shapes are
those of frames at that period. A stream at another rate (a 60 Hz LSL feed, a 25 fps
camera) is therefore put on the model's clock before it is segmented: :class:`ModelClock`
emits the frame at ``t₀ + n · period`` as soon as an input frame at or after it has
arrived, the input frame itself when one falls on it, else the linear interpolation of the
two around it (body frames brought back to rotations), in Rust
(:class:`visprim.kernels.StreamResampler`). A frame with a NaN or infinite value (an
occluded marker) is left out and counted, and the clock interpolates across it, up to
``max_gap`` seconds between complete frames: after a longer gap it starts again at the
frame after it, and says where (``breaks``), so that the segmenter starts afresh there.
That costs at most one input period of latency, and the frames do not depend on how the stream
is cut into chunks. Offline, the recording
is resampled by a cubic spline (:func:`visprim.io.resample_trial`); for movement sampled at
60 Hz or faster the two differ far below the model's filter cutoff.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from visprim import kernels

if TYPE_CHECKING:
    from visprim.online.segmenter import Frames

__all__ = ["ModelClock"]


class ModelClock:
    """Frames pushed in chunks → the frames every ``period`` seconds (module docstring)."""

    def __init__(self, period: float, max_gap: float = float("inf")) -> None:
        self.period = float(period)
        #: Longest gap between complete frames interpolated across, seconds.
        self.max_gap = float(max_gap)
        self._resampler: kernels.StreamResampler | None = None
        self._layout: tuple[int, int | None, bool] | None = None
        #: Input frames left out for a NaN or infinite value (an occluded marker).
        self.missing_frames = 0

    @property
    def memory_bytes(self) -> int:
        return 0 if self._resampler is None else int(self._resampler.memory_bytes)

    def reset(self) -> None:
        """Forget the stream."""
        if self._resampler is not None:
            self._resampler.reset()

    def push(self, frames: Frames) -> tuple[Frames, NDArray[np.float64] | None, list[int]]:
        """The clock's frames this chunk completes; when each arrived (the time of the
        input frame that completed it, seconds; None when they are the input frames, each
        on the clock); and the indices of those frames where the clock started again after
        a gap longer than ``max_gap``."""
        k = len(frames)
        m = frames.markers.reshape(k, -1)
        j = None if frames.joints is None else frames.joints.reshape(k, -1)
        layout = (m.shape[1], None if j is None else j.shape[1], frames.body_frame is not None)
        if self._layout is None:
            width = m.shape[1] + (0 if j is None else j.shape[1])
            rotations = width if frames.body_frame is not None else None
            self._resampler = kernels.StreamResampler(
                self.period,
                width + (9 if frames.body_frame is not None else 0),
                rotations,
                self.max_gap,
            )
            self._layout = layout
        elif layout != self._layout:
            raise ValueError(
                "every chunk of a stream must carry the same arrays (markers, joints, "
                "body_frame) as the first"
            )
        assert self._resampler is not None
        if j is None and frames.body_frame is None:
            rows = np.ascontiguousarray(m, dtype=np.float64)
        else:
            parts = [m] + ([] if j is None else [j])
            if frames.body_frame is not None:
                parts.append(frames.body_frame.reshape(k, 9))
            rows = np.ascontiguousarray(np.concatenate(parts, axis=1), dtype=np.float64)
        times, arrivals, out, dropped, unchanged, breaks = self._resampler.push(
            np.ascontiguousarray(frames.times, dtype=np.float64), rows
        )
        self.missing_frames += dropped
        if unchanged:  # every frame on the clock: as it came
            return frames, None, breaks
        n = times.shape[0]
        a = m.shape[1]
        b = a + (0 if j is None else j.shape[1])
        return (
            type(frames)(
                times,
                out[:, :a].reshape((n,) + frames.markers.shape[1:]),
                None
                if frames.joints is None
                else out[:, a:b].reshape((n,) + frames.joints.shape[1:]),
                None if frames.body_frame is None else out[:, b:].reshape(n, 3, 3),
            ),
            arrivals,
            breaks,
        )
