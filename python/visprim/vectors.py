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

Whole turns of γ and α
----------------------
Inverse kinematics unwraps γ and α in time (:mod:`visprim.ik`), which is right for one
trial's curves but leaves a segment of a long recording (a pirouette, a dance) a whole
number of turns (2π m) away from the same movement elsewhere: without care, two identical
arm motions become two far-apart vectors and inflate PCA and k-means errors. So each
segment's *periodic channels* (``periodic_channels``, by default γ and α,
:data:`PERIODIC_CHANNELS`) are shifted by the multiple of 2π that brings the segment's
**mean angle** (the arithmetic mean of its ``n`` resampled samples of the unwrapped curve)
into (−π, π]; the curve keeps its shape (it stays continuous and may leave (−π, π]).

The mean, rather than the first sample, is the reference because it depends on the whole
segment, not on one boundary sample that moves with the segmentation; rather than the
circular mean because it is always defined (a curve spanning whole turns has no circular
mean) and, being linear, exactly follows a whole-turn offset of the input. The shifts are
kept per segment, :attr:`SegmentVectors.offsets` (N, C) radians (zero for the other
channels), and :meth:`SegmentVectors.to_trial_angles` adds them back to put reconstructed
curves onto the trial's own angles (continuous with the trial's curves). β (in [0, π]) and
the elbow flexion are not periodic and are never shifted.

Posture offsets
---------------
With ``offsets="mean"`` each channel of a segment is shifted by its own mean over the
segment's ``n`` samples instead (for every channel; this also removes whole turns): the
vector then holds the *shape* of the movement, and the segment's mean posture is kept apart
in :attr:`SegmentVectors.offsets` and added back the same way. Primitives learned from such
vectors are movements that can be placed at any posture; a segment is rebuilt from its
primitive and its own mean posture (C numbers, 6 per arm for bone directions).

Amplitude
---------
A shape can also be scaled: :func:`amplitude_gains` gives the least-squares gain ``a ≥ 0``
that brings a rebuilt shape closest to a segment's own shape, so that one primitive serves
the same movement made larger or smaller (the amplitude parameter of a generalised motor
program, beside its duration and, here, its posture). ``PrimitiveModel(amplitude=True)``
uses it when it rebuilds segments from their primitives.

The inverse operation, :func:`stretch`, puts an ``(n, 4)`` curve back onto a segment's
duration and evaluates it at given instants.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import kernels, params

#: Samples per degree of freedom (the paper's choice).
DEFAULT_N_SAMPLES: int = params.BY_NAME["n_samples"].default

#: What a segment vector is taken relative to (module docstring): ``"turns"``, the absolute
#: curves with whole turns of the periodic channels removed (the paper), or ``"mean"``, each
#: channel relative to its mean over the segment.
OFFSETS = params.OFFSETS

#: Channels of the arm's angles (γ, β, α, elbow) that are angles about an unbounded axis,
#: unwrapped in time by the IK: γ (0) and α (2). Their segments are brought to the branch
#: whose mean lies in (−π, π] (see the module docstring).
PERIODIC_CHANNELS: tuple[int, ...] = (0, 2)

TWO_PI = 2.0 * np.pi


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
    offsets : (N, channels) float array, units of the channels (radians for angles)
        What was *subtracted* from each segment's channels to build its vector: whole turns
        (multiples of 2π, zero for non-periodic channels) or, with ``offsets="mean"``, each
        channel's mean over the segment. The segment's curves on the trial's clock are its
        vector's curves plus these offsets (:meth:`to_trial_angles`).
    """

    vectors: NDArray[np.float64]
    trial: NDArray[np.int64]
    starts: NDArray[np.float64]
    ends: NDArray[np.float64]
    n_samples: int
    offsets: NDArray[np.float64]

    @property
    def durations(self) -> NDArray[np.float64]:
        """Segment durations in seconds, shape (N,)."""
        return self.ends - self.starts

    @property
    def n_channels(self) -> int:
        """Number of angle channels C (4 for the arm)."""
        return int(self.vectors.shape[1] // self.n_samples)

    def to_trial_angles(self, vectors: ArrayLike) -> NDArray[np.float64]:
        """Curves ``(N, n, C)`` radians of ``vectors`` ``(N, C * n)`` — one per segment, in
        this object's segment order (e.g. reconstructions of :attr:`vectors`) — with each
        segment's :attr:`offsets` added back, i.e. on the trial's own (unwrapped) angles."""
        v = np.asarray(vectors, dtype=np.float64)
        if v.shape != self.vectors.shape:
            raise ValueError(
                f"to_trial_angles: expected vectors of shape {self.vectors.shape} (one per "
                f"segment), got {v.shape}"
            )
        return to_curves(v, self.n_channels) + self.offsets[:, None, :]

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


def _check_periodic(periodic_channels: Sequence[int], n_channels: int) -> tuple[int, ...]:
    out = tuple(int(c) for c in periodic_channels)
    bad = [c for c in out if not 0 <= c < n_channels]
    if bad:
        raise ValueError(
            f"periodic_channels {list(out)}: channel(s) {bad} out of range for "
            f"{n_channels} channel(s)"
        )
    if len(set(out)) != len(out):
        raise ValueError(f"periodic_channels {list(out)}: repeated channel")
    return out


def turn_offsets(
    vectors: ArrayLike,
    n_samples: int,
    periodic_channels: Sequence[int] = PERIODIC_CHANNELS,
) -> NDArray[np.float64]:
    """Whole-turn offsets ``(N, C)`` radians of channel-major vectors ``(N, C * n)``.

    For each periodic channel, ``2π m`` with the integer ``m`` such that the channel's mean
    over the segment minus ``2π m`` lies in (−π, π]; zero for the other channels.
    """
    v = np.atleast_2d(np.asarray(vectors, dtype=np.float64))
    n = int(n_samples)
    if v.ndim != 2 or n < 1 or v.shape[1] % n:
        raise ValueError(f"vectors of shape {v.shape} are not (N, C * {n_samples})")
    c = v.shape[1] // n
    periodic = list(_check_periodic(periodic_channels, c))
    offsets = np.zeros((v.shape[0], c))
    if periodic:
        means = v.reshape(v.shape[0], c, n)[:, periodic, :].mean(axis=2)
        # "+ 0.0" turns the -0.0 of ceil on (-1, 0] into 0.0.
        offsets[:, periodic] = TWO_PI * np.ceil((means - np.pi) / TWO_PI) + 0.0
    return offsets


def mean_offsets(vectors: ArrayLike, n_samples: int) -> NDArray[np.float64]:
    """Posture offsets ``(N, C)`` of channel-major vectors ``(N, C * n)``: each channel's
    mean over its ``n`` samples (units of the vectors)."""
    v = np.atleast_2d(np.asarray(vectors, dtype=np.float64))
    n = int(n_samples)
    if v.ndim != 2 or n < 1 or v.shape[1] % n:
        raise ValueError(f"vectors of shape {v.shape} are not (N, C * {n_samples})")
    return v.reshape(v.shape[0], v.shape[1] // n, n).mean(axis=2)


def amplitude_gains(shapes: ArrayLike, rebuilt: ArrayLike) -> NDArray[np.float64]:
    """Least-squares gains ``a (N,) ≥ 0`` minimising ``‖shapes_i − a_i rebuilt_i‖`` for
    each row: ``a = max(0, ⟨s, r⟩ / ⟨r, r⟩)``, 1 where ``rebuilt`` is zero. Both are
    ``(N, d)`` posture-relative vectors (``offsets="mean"``); the gain has no unit."""
    s = np.atleast_2d(np.asarray(shapes, dtype=np.float64))
    r = np.atleast_2d(np.asarray(rebuilt, dtype=np.float64))
    if s.shape != r.shape or s.ndim != 2:
        raise ValueError(f"shapes {s.shape} and rebuilt {r.shape} must be equal (N, d) arrays")
    rr = np.einsum("ij,ij->i", r, r)
    sr = np.einsum("ij,ij->i", s, r)
    gains = np.ones(s.shape[0])
    np.divide(sr, rr, out=gains, where=rr > 0.0)
    return np.maximum(gains, 0.0)


def vectors_from_frames(
    values: NDArray[np.float64],
    start_frames: ArrayLike,
    end_frames: ArrayLike,
    *,
    trial: ArrayLike,
    starts: ArrayLike,
    ends: ArrayLike,
    n_samples: int,
    periodic_channels: Sequence[int],
    offsets: str,
) -> SegmentVectors:
    """Segment vectors of a concatenated corpus from fractional frame limits (one kernel call).

    Parameters
    ----------
    values : (F, C) float64 array, radians
        All trials' angle curves, concatenated.
    start_frames, end_frames : (N,) arrays
        Segment limits as fractional row indices into ``values`` (clipped into range:
        interpolated indices may exceed the last row by rounding).
    trial, starts, ends : (N,) arrays
        Trial index and limits in seconds of each segment (kept in the result).
    n_samples : int
        Samples per channel.
    periodic_channels : sequence of int
        Channels brought to the branch whose segment mean lies in (−π, π] (module
        docstring); ``()`` keeps every channel as it is.
    offsets : {"turns", "mean"}
        What is kept apart per segment (:data:`OFFSETS`): whole turns of the periodic
        channels (the paper), or every channel's mean over the segment (the model's
        default, :mod:`visprim.params`).
    """
    if offsets not in OFFSETS:
        raise ValueError(f"offsets must be one of {list(OFFSETS)}, got {offsets!r}")
    values = np.ascontiguousarray(values, dtype=np.float64)
    if values.ndim != 2:
        raise ValueError(f"values must have shape (F, C), got {values.shape}")
    periodic = _check_periodic(periodic_channels, values.shape[1])
    last = float(values.shape[0] - 1)
    s = np.clip(np.asarray(start_frames, dtype=np.float64), 0.0, last)
    e = np.clip(np.asarray(end_frames, dtype=np.float64), 0.0, last)
    vectors = np.asarray(kernels.resample_segments(values, s, e, n=int(n_samples)))
    if offsets == "mean":
        shift = mean_offsets(vectors, int(n_samples))
    else:
        shift = turn_offsets(vectors, int(n_samples), periodic)
    if np.any(shift):
        c = values.shape[1]
        vectors = (vectors.reshape(-1, c, int(n_samples)) - shift[:, :, None]).reshape(
            vectors.shape
        )
    return SegmentVectors(
        vectors=vectors,
        trial=np.asarray(trial, dtype=np.int64),
        starts=np.asarray(starts, dtype=np.float64),
        ends=np.asarray(ends, dtype=np.float64),
        n_samples=int(n_samples),
        offsets=shift,
    )


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
    periodic_channels: Sequence[int] = PERIODIC_CHANNELS,
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
    periodic_channels : sequence of int
        Channels shifted by whole turns per segment (default γ and α; see the module
        docstring and :attr:`SegmentVectors.offsets`); ``()`` for none.

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
    return vectors_from_frames(
        np.concatenate(values, axis=0),
        np.concatenate(starts),
        np.concatenate(ends),
        trial=np.concatenate(trial_idx),
        starts=np.concatenate(seg_starts),
        ends=np.concatenate(seg_ends),
        n_samples=int(n_samples),
        periodic_channels=periodic_channels,
        offsets="turns",
    )


def segment_vectors(
    times: ArrayLike,
    angles: ArrayLike,
    segments: ArrayLike,
    n_samples: int = DEFAULT_N_SAMPLES,
    periodic_channels: Sequence[int] = PERIODIC_CHANNELS,
) -> NDArray[np.float64]:
    """Vectors ``(n_segments, C * n_samples)`` of one trial's segments (seconds), periodic
    channels shifted by whole turns as :func:`corpus_vectors` does."""
    return corpus_vectors(
        [times], [angles], [segments], n_samples=n_samples, periodic_channels=periodic_channels
    ).vectors


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
