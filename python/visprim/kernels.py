"""visprim's numeric kernels (implemented in Rust, :mod:`visprim._visprim`).

Thin, documented re-exports: every function validates its input (dtype, shape, NaN/inf,
empty input) and raises :class:`ValueError` or :class:`TypeError` with a readable message;
the computation runs with the GIL released and results come back as numpy arrays without a
copy. Signals are laid out with time along the first axis of ``(frames, channels)`` for the
ragged forms and along the last axis for ``sosfiltfilt``.

Conventions of every function here:

* Value arrays accept any real dtype (bool, integers, floats) and lists; they are converted
  to float64 as ``numpy.asarray(x).astype(numpy.float64)`` does (float64 arrays pass without
  a copy). Complex, string or object arrays raise :class:`TypeError`.
* Index arrays (``offsets``, ``trial``, ``channel``) accept any integer dtype and lists of
  integers, converted to int64 exactly (a uint64 value above ``2**63 - 1`` raises
  :class:`ValueError`); floats raise :class:`TypeError` (as numpy refuses float indices),
  except an empty array.
* Integer arguments (``n``, ``k``, ``padlen``, ``n_threads``, ...) accept any Python or numpy
  integer; a value outside the argument's range, however large or negative, raises
  :class:`ValueError` naming the argument (never :class:`OverflowError`).
* An output or workspace too large for this machine's memory (or whose size overflows)
  raises :class:`MemoryError` naming the sizes, before anything large is allocated.

The compiled functions in :mod:`visprim._visprim` are strict (float64 / int64 arrays only);
the conversions live here.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import _visprim

# --- signal kernels (filter, zvc, resample) ---

_F64 = NDArray[np.float64]
_I64 = NDArray[np.int64]


_REAL_KINDS = "biuf"


def _f64(x: ArrayLike, name: str = "x") -> Any:
    """``x`` as a float64 array: float64 arrays pass unchanged, any other real dtype (bool,
    integers, other floats) and lists are converted as ``astype(numpy.float64)`` does."""
    a = x if isinstance(x, np.ndarray) else np.asarray(x)
    if a.dtype == np.float64:
        return a
    if a.dtype.kind not in _REAL_KINDS:
        raise TypeError(f"{name} must hold real numbers, got dtype {a.dtype}")
    return a.astype(np.float64)


_I64_MAX = np.iinfo(np.int64).max


def _index(x: ArrayLike, name: str = "offsets") -> Any:
    """``x`` as an int64 array: any integer dtype is converted exactly (uint64 values above
    ``2**63 - 1`` raise ValueError); floats raise TypeError, except an empty array."""
    a = x if isinstance(x, np.ndarray) else np.asarray(x)
    if a.dtype == np.int64:
        return a
    if a.dtype.kind == "u":
        if a.size and a.max() > _I64_MAX:
            raise ValueError(f"{name} holds {a.max()}, beyond the int64 range of indices")
        return a.astype(np.int64)
    if a.dtype.kind == "i" or (a.size == 0 and a.dtype.kind in "fb"):
        return a.astype(np.int64)
    raise TypeError(f"{name} must hold integers (indices), got dtype {a.dtype}")


_offsets = _index


# --- SIMD levels ---

SIMD_ENV = "VISPRIM_SIMD"
"""The environment variable that caps the SIMD level: ``portable``, ``avx2`` or ``avx512``
(read once, at the first kernel call; unset or empty: the best level this CPU runs)."""


def instruction_set() -> str:
    """The SIMD level the kernels run at: this CPU's best, capped by ``VISPRIM_SIMD``.

    The kernels choose their code at run time (the extension is built for baseline x86-64).
    ``VISPRIM_SIMD=portable|avx2|avx512`` caps the level, e.g. to test the lower levels on a
    wider CPU; see :func:`instruction_sets` for what each kernel runs at that level.

    Returns:
        ``"avx512f"`` (the CPU has AVX-512F, AVX-512VL, AVX2, FMA and F16C: 8 doubles per
        vector), ``"avx2+fma"`` (AVX2 and FMA: 4 doubles per vector) or ``"portable"``
        (plain Rust, any CPU).

    Raises:
        ValueError: ``VISPRIM_SIMD`` is not one of ``portable``, ``avx2``, ``avx512``, or names
            a level this CPU lacks; the message names the variable, its value, the missing CPU
            features and the CPU's best level. The kernels listed by :func:`instruction_sets`
            (except ``eigh`` and ``dtw_distances``) raise the same error.
    """
    return _visprim.instruction_set()


def instruction_sets() -> dict[str, str]:
    """What each kernel runs at the level of :func:`instruction_set`, by function name.

    The first word of each value is the instruction set: ``"portable"``, ``"avx2+fma"``,
    ``"avx512f"``, or ``"faer's"`` (faer's own run-time choice, which ``VISPRIM_SIMD`` does not
    cap); the rest says where a kernel departs from the level, e.g. the covariance of rows of
    fewer than 16 values is faer's product at every level, and ``kmeans_plusplus`` has no
    AVX-512 code. Kernels not listed (filter design, crossings, gradients, SEG-1, clocks) are
    portable code at every level.

    Results across levels (tested in child processes at every level the CPU runs):

    * ``kmeans``, ``kmeans_predict``, ``kmeans_plusplus``, ``resample_segments``: the same bits
      at every level;
    * ``covariance``: the same bits at ``avx2+fma`` and ``avx512f``; at ``portable`` (faer's
      product) within ``1e-12`` of them, relative to the largest variance;
    * ``sosfiltfilt``: ``portable`` follows scipy's arithmetic (no fused multiply-adds); the
      SIMD levels use fused multiply-adds and agree with it within ``1e-12``, relative to the
      largest input magnitude.

    Returns:
        ``{kernel name: description}``, e.g.
        ``{"sosfiltfilt": "avx2+fma (16 signals in lockstep)", ...}``.

    Raises:
        ValueError: as :func:`instruction_set`.
    """
    return dict(_visprim.instruction_sets())


def simd_levels() -> list[str]:
    """The ``VISPRIM_SIMD`` values this CPU runs, lowest first, e.g. ``["portable", "avx2"]``.

    Independent of ``VISPRIM_SIMD`` itself (never raises): ``make test`` uses it to run the
    kernel tests at every level.
    """
    return _visprim.simd_levels()


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
    return _visprim.default_padlen(_f64(sos, "sos"))


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
    return _visprim.sosfiltfilt(_f64(sos, "sos"), _f64(x, "x"), padlen)


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
    return _visprim.sosfiltfilt_ragged(
        _f64(sos, "sos"), _f64(values, "values"), _index(offsets), padlen
    )


def gradient_ragged(times: ArrayLike, values: ArrayLike, offsets: ArrayLike) -> _F64:
    """Time derivative of every trial of a concatenated corpus on its own timestamps.

    Per trial, equal (bit for bit) to ``numpy.gradient(values_i, times_i, axis=0)``:
    second-order central differences for uneven steps inside, one-sided first-order
    differences at the first and last frame. NaN or infinity in ``values`` propagates (as in
    numpy).

    Args:
        times: ``(total_frames,)`` float64 seconds, each trial's clock, strictly increasing
            within a trial.
        values: ``(total_frames, channels)`` float64 (1-D: one channel), e.g. radians.
        offsets: first frame of each trial (as in :func:`sosfiltfilt_ragged`); every trial
            needs at least 2 frames.

    Returns:
        Array of the shape of ``values``, in units of ``values`` per second.

    Raises:
        ValueError: shapes that do not match, invalid offsets, a trial of fewer than 2 frames,
            timestamps that are not finite or not strictly increasing in a trial.
    """
    return _visprim.gradient_ragged(_f64(times, "times"), _f64(values, "values"), _index(offsets))


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
    pos = None if positions is None else _f64(positions, "positions")
    return _visprim.zero_velocity_crossings(_f64(velocity, "velocity"), min_change, pos)


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
    pos = None if positions is None else _f64(positions, "positions")
    return _visprim.zero_velocity_crossings_ragged(
        _f64(velocity, "velocity"), _index(offsets), min_change, pos
    )


def zero_velocity_crossings_of_positions(
    times: ArrayLike, positions: ArrayLike, offsets: ArrayLike, min_change: float = 0.0
) -> tuple[_I64, _I64, _F64]:
    """:func:`zero_velocity_crossings_ragged` of the velocity of ``positions``, computed trial
    by trial (no corpus-sized velocity array).

    The velocity is :func:`gradient_ragged` of ``positions`` on ``times`` and the crossings are
    interpolated on ``positions``: the result is identical to
    ``zero_velocity_crossings_ragged(gradient_ragged(times, positions, offsets), offsets,
    min_change, positions)``.

    Args:
        times: ``(total_frames,)`` float64 seconds, strictly increasing within each trial.
        positions: ``(total_frames, channels)`` float64 (1-D: one channel), e.g. radians.
        offsets: first frame of each trial (each trial has >= 2 frames).
        min_change: significant-movement threshold, in the unit of ``positions``.

    Returns:
        ``(trial, channel, frame)`` as :func:`zero_velocity_crossings_ragged`.
    """
    return _visprim.zero_velocity_crossings_of_positions(
        _f64(times, "times"), _f64(positions, "positions"), _index(offsets), min_change
    )


def seg1_events(
    trial: ArrayLike, channel: ArrayLike, time: ArrayLike, window: float
) -> tuple[_I64, _F64, _I64]:
    """Group zero-velocity crossings of all channels into SEG-1 events, per trial.

    Within a trial the crossings are taken in time order (ties keep their input order); a
    crossing less than ``window`` seconds after the previous one joins its event (single
    linkage), a gap ``>= window`` starts a new event. Events never span two trials.

    Args:
        trial: int64 ``(n,)`` trial of each crossing, non-decreasing (grouped by trial).
        channel: int64 ``(n,)`` channel (DOF) of each crossing, ``>= 0``.
        time: float64 ``(n,)`` seconds on the trial's clock (finite).
        window: seconds, > 0.

    Returns:
        ``(trial, time, n_channels)`` per event, sorted by trial then time: int64 trial, the
        float64 median time (seconds) of the event's crossings (mean of the two middle ones
        for an even count) and the int64 number of distinct channels among them.
    """
    return _visprim.seg1_events(
        _index(trial, "trial"), _index(channel, "channel"), _f64(time, "time"), window
    )


def times_to_frames(times: ArrayLike, offsets: ArrayLike, trial: ArrayLike, t: ArrayLike) -> _F64:
    """Fractional frame indices of times on a concatenated corpus's own timestamps.

    ``t[i]`` (seconds on the clock of trial ``trial[i]``) is clamped to that trial's first and
    last timestamps and located by linear interpolation between the two frames around it.

    Args:
        times: ``(total_frames,)`` float64 seconds, strictly increasing within each queried
            trial.
        offsets: first frame of each trial (as in :func:`sosfiltfilt_ragged`).
        trial: int64 ``(m,)`` trial index of each query.
        t: float64 ``(m,)`` seconds.

    Returns:
        float64 ``(m,)`` fractional frames relative to each trial's first frame, in
        ``[0, n_frames_of_trial - 1]``.
    """
    return _visprim.times_to_frames(
        _f64(times, "times"), _index(offsets), _index(trial, "trial"), _f64(t, "t")
    )


def frames_to_times(
    times: ArrayLike, offsets: ArrayLike, trial: ArrayLike, frame: ArrayLike
) -> _F64:
    """Seconds of fractional frame indices on a concatenated corpus's own timestamps (the
    converse of :func:`times_to_frames`).

    ``frame[i]`` (relative to the first frame of trial ``trial[i]``) is placed by linear
    interpolation between the two timestamps around it; frames before the first or after the
    last one are extrapolated from the trial's first or last interval.

    Args:
        times: ``(total_frames,)`` float64 seconds.
        offsets: first frame of each trial (as in :func:`sosfiltfilt_ragged`).
        trial: int64 ``(m,)`` trial index of each query; each queried trial has >= 2 frames.
        frame: float64 ``(m,)`` fractional frames.

    Returns:
        float64 ``(m,)`` seconds on each trial's clock.
    """
    return _visprim.frames_to_times(
        _f64(times, "times"), _index(offsets), _index(trial, "trial"), _f64(frame, "frame")
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
    return _visprim.resample_segments(
        _f64(values, "values"), _f64(starts, "starts"), _f64(ends, "ends"), n
    )


# --- linalg kernels (covariance, eigh, kmeans) ---


def _matrix(x: ArrayLike, name: str = "X") -> Any:
    """Arrays of any real dtype and nested lists/tuples become float64 arrays (see
    :func:`_f64`); other objects go to the kernel unchanged (it raises TypeError)."""
    if isinstance(x, (np.ndarray, list, tuple)):
        return _f64(x, name)
    return x


def covariance(x: ArrayLike, *, n_threads: int | None = None) -> tuple[_F64, _F64]:
    """Mean and covariance, with divisor N (the paper's ``K``), of the rows of ``x``.

    Rows are centred by a shift in blocks before the product (no ``XᵀX - N μμᵀ``
    cancellation), and only the lower half of ``Σ (x - μ)(x - μ)ᵀ`` is formed (a packed
    AVX2+FMA kernel where the CPU has it, else faer's triangular matrix product); the result
    is exactly symmetric and does not depend on the number of threads.

    Args:
        x: ``(N, d)`` float64, one observation per row (units kept: the covariance is in
            squared units of ``x``). Non-contiguous arrays are copied.
        n_threads: threads to use (``None``: all cores).

    Returns:
        ``(mean (d,), covariance (d, d))``, equal to ``x.mean(0)`` and
        ``numpy.cov(x, rowvar=False, bias=True)`` up to rounding.

    Raises:
        TypeError: ``x`` is not a float64 ndarray.
        ValueError: ``x`` is not 2-D, is empty, or contains NaN/inf.
    """
    return _visprim.covariance(_matrix(x), n_threads=n_threads)


CovarianceAccumulator = _visprim.CovarianceAccumulator
#: Open-end DTW of a growing query against fixed references (:mod:`visprim.online`).
OnlineDtw = _visprim.OnlineDtw
#: Causal ``sosfilt`` of a multichannel stream, state kept between chunks
#: (:mod:`visprim.online.lowpass`).
CausalSos = _visprim.CausalSos
#: The online segmenter's front end (inverse kinematics, causal low-pass, channels, squared
#: speed and adaptive threshold), state kept between chunks (:mod:`visprim.online.segmenter`).
OnlineFrontEnd = _visprim.OnlineFrontEnd
#: A stream's frames onto a uniform clock, causally (linear interpolation; rotations kept
#: rotations), state kept between chunks (:mod:`visprim.online.segmenter`).
StreamResampler = _visprim.StreamResampler


def segment_channels(sos: ArrayLike, raw: ArrayLike, start: int, stop: int, features: str) -> _F64:
    """Channels ``(stop − start, C)`` of frames ``start:stop`` of raw arm angles ``raw``
    ``(n, 4 n_arms)`` radians, after the zero-phase filter ``sos`` of the whole window: the
    same as ``from_angles(lowpass(raw, short="reduce")[start:stop], features)``
    (:func:`visprim.filtering.lowpass` with ``sos``'s order and cutoff, its bits;
    :func:`visprim.features.from_angles`, within an ulp) in one call. ``features``:
    ``"zyz"`` or ``"directions"``. Used for the closed segments of
    :mod:`visprim.online.segmenter`."""
    return _visprim.segment_channels(_f64(sos, "sos"), _f64(raw, "raw"), start, stop, features)


def eigh(a: ArrayLike, *, k: int | None = None) -> tuple[_F64, _F64]:
    """Eigendecomposition of a symmetric matrix (faer), eigenvalues in DESCENDING order.

    Sign convention: in every eigenvector, the component of largest absolute value is
    positive (the first such component on exact ties). The eigenvectors of a repeated
    eigenvalue span its eigenspace in no particular basis. Only the lower triangle is used,
    like ``numpy.linalg.eigh`` (``UPLO='L'``), once symmetry is checked.

    Args:
        a: ``(d, d)`` float64 symmetric matrix (e.g. a covariance).
        k: return only the ``k`` leading pairs (``1 <= k <= d``); ``None``: all ``d``.

    Returns:
        ``(eigenvalues (k,), eigenvectors (d, k))``: column ``j`` is the unit eigenvector of
        ``eigenvalues[j]``; equal to ``numpy.linalg.eigh`` up to order and sign.

    Raises:
        TypeError: ``a`` is not a float64 ndarray.
        ValueError: not square, empty, NaN/inf, asymmetric beyond ``1e-10 * max|a|``, or ``k``
            out of range.
        RuntimeError: the eigensolver did not converge.
    """
    return _visprim.eigh(_matrix(a, "K"), k=k)


KMeansResult = _visprim.KMeansResult


def kmeans(
    x: ArrayLike,
    k: int,
    *,
    n_init: int = 1,
    max_iter: int = 300,
    tol: float = 1e-4,
    seed: int = 0,
    init: ArrayLike | None = None,
    n_local_trials: int | None = None,
    n_threads: int | None = None,
) -> Any:
    """k-means clustering: greedy k-means++ seeding, Lloyd iterations, best of ``n_init``.

    Semantics of scikit-learn's ``KMeans(algorithm="lloyd")``: one iteration assigns each row
    to its nearest centre (ties: lowest index) then moves every centre to the mean of its
    rows; iterations stop when no label changes, when the total squared centre shift is
    ``<= tol * mean(var(X, axis=0))``, or after ``max_iter`` (then the rows are relabelled
    with the final centres). From the same ``init`` it gives scikit-learn's labels and
    centres up to rounding. A cluster left empty is re-seeded with the row farthest from its
    centre (the i-th empty cluster, by index, takes the i-th farthest row; the row's old
    cluster loses it); if all rows sit on their centres it keeps its centre.

    Seeding: the first centre is a uniformly drawn row; each next one is the best (lowest
    potential) of ``n_local_trials`` rows drawn with probability proportional to the squared
    distance to the nearest centre so far (scikit-learn's greedy k-means++). The seeding
    computes its distances in single precision (rows shifted by the first row; relative error
    ~1e-7), which halves its memory traffic; Lloyd's iterations are in double precision.

    Exact acceleration (results equal plain Lloyd's, except for rows whose two nearest
    centres tie within ~1e-11 of the data diameter): triangle-inequality bounds skip most
    distance computations. The result for a given ``seed`` is identical for any number of
    threads (fixed work split, ordered sums).

    Args:
        x: ``(N, d)`` float64, one observation per row.
        k: number of clusters, ``1 <= k <= N``.
        n_init: independent seedings; the run with the lowest inertia is kept (must be 1
            when ``init`` is given).
        max_iter: maximum Lloyd iterations per run (>= 1).
        tol: relative tolerance on the centre shift (>= 0; scaled as above).
        seed: seed of the random draws, an integer in ``[0, 2**64)``; run ``r`` of
            ``n_init`` uses a seed derived from ``seed`` and ``r`` (run 0 uses ``seed``).
        init: ``(k, d)`` float64 initial centres instead of k-means++.
        n_local_trials: candidates per seeding step, 1..64 (``None``: ``2 + floor(ln k)``).
        n_threads: threads to use (``None``: all cores).

    Returns:
        :class:`KMeansResult` with ``centers``, ``labels``, ``inertia``, ``n_iter``.

    Raises:
        TypeError: ``x`` or ``init`` is not a float64 ndarray.
        ValueError: bad shapes, empty input, NaN/inf, ``k`` outside ``1..N``, ``n_init``,
            ``max_iter``, ``n_local_trials``, ``n_threads`` < 1, negative ``tol``, or
            ``init`` with ``n_init > 1``.
    """
    return _visprim.kmeans(
        _matrix(x),
        k,
        n_init=n_init,
        max_iter=max_iter,
        tol=tol,
        seed=seed,
        init=None if init is None else _matrix(init, "init"),
        n_local_trials=n_local_trials,
        n_threads=n_threads,
    )


def kmeans_predict(
    x: ArrayLike, centers: ArrayLike, *, n_threads: int | None = None
) -> tuple[_I64, _F64]:
    """Assign rows to their nearest centre (e.g. new segments to learned primitives).

    Args:
        x: ``(N, d)`` float64 rows.
        centers: ``(k, d)`` float64 centres (e.g. ``kmeans(...).centers``).
        n_threads: threads to use (``None``: all cores).

    Returns:
        ``(labels (N,) int64, distances (N,) float64)``: index of the nearest centre (lowest
        index on ties) and the Euclidean distance to it, in the units of ``x``.

    Raises:
        TypeError: an argument is not a float64 ndarray.
        ValueError: not 2-D, empty, column counts differ, or NaN/inf.
    """
    return _visprim.kmeans_predict(_matrix(x), _matrix(centers, "centers"), n_threads=n_threads)


def kmeans_plusplus(
    x: ArrayLike,
    k: int,
    *,
    seed: int = 0,
    n_local_trials: int | None = None,
    n_threads: int | None = None,
) -> tuple[_F64, _I64]:
    """Greedy k-means++ seeds (the initialisation :func:`kmeans` uses for ``n_init=1``).

    Returns:
        ``(centers (k, d), indices (k,) int64)`` with ``centers == x[indices]``.

    Raises:
        TypeError / ValueError: as :func:`kmeans`.
    """
    return _visprim.kmeans_plusplus(
        _matrix(x), k, seed=seed, n_local_trials=n_local_trials, n_threads=n_threads
    )


# --- dynamic time warping ---


def dtw_distances(
    queries: ArrayLike,
    query_offsets: ArrayLike,
    references: ArrayLike | None = None,
    reference_offsets: ArrayLike | None = None,
    *,
    band: float | None = None,
    normalize: bool = True,
    n_threads: int | None = None,
) -> _F64:
    """Dynamic time warping costs between ragged sets of multichannel sequences.

    The local cost of matching frame ``a_i`` with frame ``b_j`` is their Euclidean distance
    ``‖a_i − b_j‖`` (in the units of the values); the DTW cost of two sequences is the least
    sum of local costs along a warping path from the first frames to the last (steps
    (1, 0), (0, 1), (1, 1)). Pairs are computed in parallel; results do not depend on the
    number of threads.

    Args:
        queries: ``(total_frames, dim)`` float64, the query sequences concatenated in time.
        query_offsets: first frame of each query sequence (integers from 0, strictly
            increasing, as in :func:`sosfiltfilt_ragged`).
        references, reference_offsets: the reference set, laid out the same way (same
            ``dim``). Omit both for the symmetric costs among the queries (each pair computed
            once, zeros on the diagonal).
        band: Sakoe–Chiba band half-width as a fraction of the longer sequence's length, in
            [0, 1], around the diagonal scaled to the two lengths (widened where needed so
            that a path always exists); ``None`` (default): no band.
        normalize: divide each cost by the sum of the two lengths (default ``True``), so
            sequences of different lengths compare on the scale of one frame's distance.
        n_threads: threads to use (default: all cores).

    Returns:
        ``(n_queries, n_references)`` float64 costs.

    Raises:
        TypeError: values not float64 or offsets not integer arrays.
        ValueError: not 2-D, channel counts differ, invalid offsets, NaN/inf, band outside
            [0, 1], or only one of ``references`` / ``reference_offsets`` given.
    """
    refs = None if references is None else _f64(references)
    ref_off = None if reference_offsets is None else _offsets(reference_offsets)
    return _visprim.dtw_distances(
        _f64(queries),
        _offsets(query_offsets),
        refs,
        ref_off,
        band=None if band is None else float(band),
        normalize=bool(normalize),
        n_threads=n_threads,
    )
