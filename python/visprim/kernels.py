"""visprim's numeric kernels (implemented in Rust, :mod:`visprim._visprim`).

Thin, documented re-exports: every function validates its input (dtype, shape, NaN/inf,
empty input) and raises :class:`ValueError` or :class:`TypeError` with a readable message;
the computation runs with the GIL released and results come back as numpy arrays without a
copy. Arrays are float64; signals are laid out with time along the first axis of
``(frames, channels)`` for the ragged forms and along the last axis for ``sosfiltfilt``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import _visprim

# --- signal kernels (filter, zvc, resample) ---

_F64 = NDArray[np.float64]
_I64 = NDArray[np.int64]


def _f64(x: ArrayLike) -> Any:
    """Arrays pass through unchanged (the kernel checks their dtype strictly: float32 or int
    arrays raise TypeError); lists and scalars become float64 arrays."""
    return x if isinstance(x, np.ndarray) else np.asarray(x, dtype=np.float64)


def _offsets(offsets: ArrayLike) -> Any:
    """Trial offsets as int64: any integer array is converted (exactly); lists too."""
    o = np.asarray(offsets)
    if o.dtype.kind in "iu" and o.dtype != np.int64:
        o = o.astype(np.int64)
    elif o.size == 0 and o.dtype.kind == "f":
        o = o.astype(np.int64)
    return o


def butter_sos(order: int, cutoff: float) -> _F64:
    """Low-pass Butterworth filter as second-order sections.

    Equal to ``scipy.signal.butter(order, cutoff, output="sos")`` (within 1e-10; same section
    order and pole/zero pairing, gain in the first section).

    Args:
        order: filter order, an integer >= 1 (the sections number ``(order + 1) // 2``).
        cutoff: normalised cutoff frequency in (0, 1), a fraction of the Nyquist frequency
            (``cutoff_hz / (sample_rate_hz / 2)``).

    Returns:
        ``(n_sections, 6)`` float64 array of rows ``[b0, b1, b2, 1, a1, a2]``.

    Raises:
        ValueError: order < 1 or cutoff outside (0, 1).
    """
    return _visprim.butter_sos(order, cutoff)


def default_padlen(sos: ArrayLike) -> int:
    """scipy's default ``padlen`` of :func:`sosfiltfilt` for ``sos``, in samples:
    ``3 * (2 * n_sections + 1 - min(#{b2 == 0}, #{a2 == 0}))``. Signals must be longer."""
    return _visprim.default_padlen(_f64(sos))


def sosfiltfilt(sos: ArrayLike, x: ArrayLike, padlen: int | None = None) -> _F64:
    """Zero-phase (forward-backward) filtering along the LAST axis.

    Equal to ``scipy.signal.sosfiltfilt(sos, x, padlen=padlen)`` within 1e-10: odd extension of
    ``padlen`` samples at each end, ``sosfilt_zi`` initial conditions scaled by the first
    sample, a forward then a backward pass. The rows of a 2-D ``x`` are filtered together in
    lockstep on all cores.

    Args:
        sos: ``(n_sections, 6)`` float64 second-order sections with ``a0 == 1`` (e.g. from
            :func:`butter_sos`).
        x: 1-D ``(samples,)`` or 2-D ``(signals, samples)`` float64 array.
        padlen: samples of odd extension at each end (>= 0); ``None`` is scipy's default,
            :func:`default_padlen`.

    Returns:
        A new float64 array shaped like ``x``.

    Raises:
        TypeError: ``x`` or ``sos`` is not a float64 ndarray.
        ValueError: wrong ndim or sos shape, NaN/inf, ``a0 != 1``, empty ``x``, or a signal not
            longer than ``padlen`` (the message gives both lengths).
    """
    return _visprim.sosfiltfilt(_f64(sos), _f64(x), padlen)


def sosfiltfilt_ragged(
    sos: ArrayLike, values: ArrayLike, offsets: ArrayLike, padlen: int | None = None
) -> _F64:
    """:func:`sosfiltfilt` of every trial of a concatenated corpus, in one call.

    Trial ``i`` spans frames ``offsets[i]`` to ``offsets[i + 1]`` (the last one to the end);
    each channel of each trial is filtered along time exactly as ``sosfiltfilt`` of that trial
    alone would. Trials of equal length are filtered in lockstep on all cores.

    Args:
        sos: ``(n_sections, 6)`` float64 second-order sections.
        values: ``(total_frames, channels)`` float64 (time along the first axis), or 1-D for
            one channel.
        offsets: first frame of each trial: integers starting at 0, strictly increasing, each
            < total_frames (any integer dtype; converted to int64).
        padlen: as in :func:`sosfiltfilt`; every trial must be longer.

    Returns:
        A new float64 array shaped like ``values``.

    Raises:
        TypeError: non-float64 ``values`` or non-integer ``offsets``.
        ValueError: invalid offsets, NaN/inf, or a trial not longer than ``padlen`` (the
            message names the trial and both lengths).
    """
    return _visprim.sosfiltfilt_ragged(_f64(sos), _f64(values), _offsets(offsets), padlen)


def zero_velocity_crossings(
    velocity: ArrayLike, min_change: float = 0.0, positions: ArrayLike | None = None
) -> tuple[_F64, _I64]:
    """Zero-velocity crossings (ZVCs) per channel, with a significant-movement threshold.

    Rules, per channel (frames in time order):

    * A crossing lies between consecutive NON-ZERO velocity samples ``v[a]``, ``v[b]`` of
      opposite signs (exact zeros carry no sign). If ``b == a + 1`` it is at the fractional
      frame ``a + v[a] / (v[a] - v[b])`` (linear interpolation of the velocity); otherwise
      (a run of exact zeros between them) at the middle of the run, ``(a + b) / 2``. Touching
      zero and coming back, or zeros at the ends, give no crossing.
    * Significant movement: walking the crossings in time order, one is KEPT when
      ``|p(crossing) - p(reference)| > min_change``, with ``p`` the position linearly
      interpolated at the crossing's fractional frame and the reference the last KEPT
      crossing of that channel (frame 0 before any). ``min_change = 0`` keeps all crossings.
    * ``positions`` defaults to ``numpy.cumsum(velocity, axis=0)`` (velocity in position units
      per frame). Pass the angles themselves (radians) to threshold in radians.

    Args:
        velocity: ``(frames, channels)`` float64, or 1-D for one channel.
        min_change: threshold in the units of ``positions`` (>= 0).
        positions: same shape as ``velocity``, or ``None``.

    Returns:
        ``(frames, channels)``: fractional frame indices (float64) and channel indices
        (int64), sorted by channel then frame.
    """
    pos = None if positions is None else _f64(positions)
    return _visprim.zero_velocity_crossings(_f64(velocity), float(min_change), pos)


def zero_velocity_crossings_ragged(
    velocity: ArrayLike,
    offsets: ArrayLike,
    min_change: float = 0.0,
    positions: ArrayLike | None = None,
) -> tuple[_I64, _I64, _F64]:
    """:func:`zero_velocity_crossings` of every trial of a concatenated corpus, in one call.

    Trials are delimited by ``offsets`` as in :func:`sosfiltfilt_ragged`; crossings never span
    two trials, and the significant-movement reference restarts at each trial's frame 0 (with
    default positions, the running sum also restarts at each trial).

    Returns:
        ``(trial, channel, frame)``: int64 trial and channel indices and float64 fractional
        frames RELATIVE to the trial's first frame, sorted by trial, channel, frame.
    """
    pos = None if positions is None else _f64(positions)
    return _visprim.zero_velocity_crossings_ragged(
        _f64(velocity), _offsets(offsets), float(min_change), pos
    )


def resample_segments(values: ArrayLike, starts: ArrayLike, ends: ArrayLike, n: int = 100) -> _F64:
    """Resample segments of a multichannel signal to ``n`` samples per channel.

    Segment ``i`` covers the fractional frame indices ``[starts[i], ends[i]]`` of ``values``;
    it is sampled at ``numpy.linspace(start, end, n)`` and each channel linearly interpolated
    between frames, equal to ``numpy.interp`` per channel within 1e-12. Works on a
    concatenated corpus with global frame indices.

    Args:
        values: ``(frames, channels)`` float64 (1-D: one channel).
        starts, ends: float64 ``(n_segments,)``, ``0 <= start < end <= frames - 1``.
        n: samples per channel, >= 2.

    Returns:
        ``(n_segments, channels * n)`` float64, channel-major (all ``n`` samples of channel 0,
        then channel 1, ...). No segments gives shape ``(0, channels * n)``.
    """
    return _visprim.resample_segments(_f64(values), _f64(starts), _f64(ends), n)


# --- linalg kernels (covariance, eigh, kmeans) ---
