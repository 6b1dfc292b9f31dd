"""Segment vectors: each segment of a movement resampled to ``n`` samples per degree of freedom.

The paper (Fod, Matarić & Jenkins) turns every segment of the 4 arm angles into one point of
a 400-dimensional space: each angle curve between the segment's start and end is resampled
at ``n = 100`` equally spaced instants and the four curves are concatenated *channel-major*:

``vector = [γ(0..n-1), β(0..n-1), α(0..n-1), elbow(0..n-1)]`` (radians).

The resampling runs in the Rust kernel :func:`visprim.kernels.resample_segments` on a whole
corpus at once. Segment limits are given in seconds and converted to *fractional frame
indices* by linear interpolation of the trial's timestamps; the kernel then samples equally
spaced fractional frame indices, i.e. equally spaced instants when the frame rate is uniform
(and up to the timestamp jitter otherwise).

The inverse operation, :func:`stretch`, puts an ``(n, 4)`` curve back onto a segment's
duration and evaluates it at given instants.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import kernels

#: Samples per degree of freedom (the paper's choice).
DEFAULT_N_SAMPLES = 100


@dataclass(frozen=True)
class SegmentVectors:
    """The segments of a corpus as vectors, with where each one came from.

    Attributes
    ----------
    vectors : (N, channels * n) float array, radians
        Channel-major resampled segments.
    trial : (N,) int array
        Index of the trial (in the corpus given) each segment belongs to.
    starts, ends : (N,) float arrays, seconds
        Segment limits on the trial's clock.
    n_samples : int
        Samples per channel ``n``.
    """

    vectors: NDArray[np.float64]
    trial: NDArray[np.int64]
    starts: NDArray[np.float64]
    ends: NDArray[np.float64]
    n_samples: int

    @property
    def durations(self) -> NDArray[np.float64]:
        """Segment durations in seconds, shape (N,)."""
        return self.ends - self.starts

    def __len__(self) -> int:
        return int(self.vectors.shape[0])


def time_to_frame(times: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
    """Fractional frame indices of instants ``t`` (seconds) on a trial's clock ``times``.

    Linear interpolation between timestamps; instants outside ``[times[0], times[-1]]`` are
    an error (a segment must lie inside its trial).
    """
    times = np.asarray(times, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    if t.size and (t.min() < times[0] - 1e-9 or t.max() > times[-1] + 1e-9):
        raise ValueError(
            f"segment times must lie within the trial [{times[0]:.6g}, {times[-1]:.6g}] s, "
            f"got [{t.min():.6g}, {t.max():.6g}] s"
        )
    return np.interp(t, times, np.arange(times.shape[0], dtype=np.float64))


def _check_segments(segments: ArrayLike, where: str) -> NDArray[np.float64]:
    seg = np.asarray(segments, dtype=np.float64)
    if seg.size == 0:
        return np.zeros((0, 2))
    if seg.ndim != 2 or seg.shape[1] != 2:
        raise ValueError(
            f"{where}: segments must have shape (n, 2) (start, end seconds), got {seg.shape}"
        )
    if not np.all(np.isfinite(seg)):
        raise ValueError(f"{where}: segment times contain NaN or infinity")
    if np.any(seg[:, 1] <= seg[:, 0]):
        i = int(np.argmax(seg[:, 1] <= seg[:, 0]))
        raise ValueError(
            f"{where}: segment {i} ends ({seg[i, 1]:.6g} s) before or when it starts "
            f"({seg[i, 0]:.6g} s)"
        )
    return seg


def corpus_vectors(
    times_list: Sequence[ArrayLike],
    angles_list: Sequence[ArrayLike],
    segments_list: Sequence[ArrayLike],
    n_samples: int = DEFAULT_N_SAMPLES,
    names: Sequence[str] | None = None,
) -> SegmentVectors:
    """Resample every segment of every trial in ONE kernel call.

    Parameters
    ----------
    times_list : sequence of (T_i,) arrays, seconds
        Each trial's timestamps.
    angles_list : sequence of (T_i, C) arrays
        Each trial's angle curves (radians; C = 4 for the arm).
    segments_list : sequence of (n_i, 2) arrays, seconds
        Each trial's segments (start, end) on its own clock.
    n_samples : int
        Samples per channel (default 100).
    names : sequence of str, optional
        Trial names, used in error messages.

    Returns
    -------
    SegmentVectors
        Vectors ``(N, C * n_samples)`` in trial order, then segment order.
    """
    if not (len(times_list) == len(angles_list) == len(segments_list)):
        raise ValueError(
            f"times, angles and segments lists differ in length: {len(times_list)}, "
            f"{len(angles_list)}, {len(segments_list)}"
        )
    if int(n_samples) < 2:
        raise ValueError(f"n_samples must be >= 2, got {n_samples}")
    if len(times_list) == 0:
        raise ValueError("corpus_vectors: the corpus is empty")
    starts, ends, trial_idx, seg_starts, seg_ends = [], [], [], [], []
    values = []
    offset = 0
    n_channels = None
    for i, (times, angles, segments) in enumerate(
        zip(times_list, angles_list, segments_list, strict=True)
    ):
        where = names[i] if names is not None else f"trial {i}"
        times = np.asarray(times, dtype=np.float64)
        angles = np.asarray(angles, dtype=np.float64)
        if angles.ndim != 2 or angles.shape[0] != times.shape[0]:
            raise ValueError(
                f"{where}: angles must have shape (T, C) with T = {times.shape[0]} frames, "
                f"got {angles.shape}"
            )
        if n_channels is None:
            n_channels = angles.shape[1]
        elif angles.shape[1] != n_channels:
            raise ValueError(
                f"{where}: {angles.shape[1]} channels where earlier trials have {n_channels}"
            )
        seg = _check_segments(segments, where)
        if seg.shape[0]:
            try:
                f = time_to_frame(times, seg)
            except ValueError as exc:
                raise ValueError(f"{where}: {exc}") from None
            starts.append(f[:, 0] + offset)
            ends.append(f[:, 1] + offset)
            trial_idx.append(np.full(seg.shape[0], i, dtype=np.int64))
            seg_starts.append(seg[:, 0])
            seg_ends.append(seg[:, 1])
        values.append(angles)
        offset += times.shape[0]
    if not starts:
        raise ValueError("corpus_vectors: no segments in the corpus")
    all_values = np.ascontiguousarray(np.concatenate(values, axis=0))
    s = np.concatenate(starts)
    e = np.concatenate(ends)
    # Interpolated indices may exceed the last frame by rounding; clip into range.
    last = float(all_values.shape[0] - 1)
    np.clip(s, 0.0, last, out=s)
    np.clip(e, 0.0, last, out=e)
    vectors = kernels.resample_segments(all_values, s, e, n=int(n_samples))
    return SegmentVectors(
        vectors=np.asarray(vectors),
        trial=np.concatenate(trial_idx),
        starts=np.concatenate(seg_starts),
        ends=np.concatenate(seg_ends),
        n_samples=int(n_samples),
    )


def segment_vectors(
    times: ArrayLike, angles: ArrayLike, segments: ArrayLike, n_samples: int = DEFAULT_N_SAMPLES
) -> NDArray[np.float64]:
    """Vectors ``(n_segments, C * n_samples)`` of one trial's segments (seconds)."""
    return corpus_vectors([times], [angles], [segments], n_samples=n_samples).vectors


def to_curves(vectors: ArrayLike, n_channels: int = 4) -> NDArray[np.float64]:
    """Split channel-major vectors ``(N, C * n)`` (or one ``(C * n,)``) into curves
    ``(N, n, C)`` (or ``(n, C)``)."""
    v = np.asarray(vectors, dtype=np.float64)
    single = v.ndim == 1
    v = np.atleast_2d(v)
    if v.ndim != 2 or v.shape[1] % n_channels:
        raise ValueError(
            f"vectors must have shape (N, {n_channels} * n), got {np.asarray(vectors).shape}"
        )
    n = v.shape[1] // n_channels
    curves = v.reshape(v.shape[0], n_channels, n).transpose(0, 2, 1)
    return curves[0] if single else curves


def to_vectors(curves: ArrayLike) -> NDArray[np.float64]:
    """Inverse of :func:`to_curves`: ``(N, n, C)`` → ``(N, C * n)``; ``(n, C)`` → ``(C * n,)``."""
    c = np.asarray(curves, dtype=np.float64)
    if c.ndim == 2:
        return np.ascontiguousarray(c.T).reshape(-1)
    if c.ndim != 3:
        raise ValueError(f"curves must have shape (N, n, C) or (n, C), got {c.shape}")
    return np.ascontiguousarray(c.transpose(0, 2, 1)).reshape(c.shape[0], -1)


def stretch(curve: ArrayLike, start: float, end: float, times: ArrayLike) -> NDArray[np.float64]:
    """Put a resampled curve back onto a segment's duration.

    Parameters
    ----------
    curve : (n, C) array
        Samples at ``n`` equally spaced instants from ``start`` to ``end`` inclusive.
    start, end : float, seconds
        The segment's limits.
    times : (m,) array, seconds
        Instants to evaluate (normally the trial's frame times within the segment); values
        outside ``[start, end]`` are an error.

    Returns
    -------
    (m, C) array: the curve linearly interpolated at ``times``.
    """
    c = np.asarray(curve, dtype=np.float64)
    t = np.asarray(times, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] < 2:
        raise ValueError(f"curve must have shape (n >= 2, C), got {c.shape}")
    if not end > start:
        raise ValueError(f"segment end ({end:.6g} s) must be after its start ({start:.6g} s)")
    if t.size and (t.min() < start - 1e-9 or t.max() > end + 1e-9):
        raise ValueError(
            f"instants [{t.min():.6g}, {t.max():.6g}] s fall outside the segment "
            f"[{start:.6g}, {end:.6g}] s"
        )
    grid = np.linspace(start, end, c.shape[0])
    return np.stack([np.interp(t, grid, c[:, j]) for j in range(c.shape[1])], axis=-1)
