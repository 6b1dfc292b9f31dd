"""Zero-phase low-pass filtering of joint-angle trajectories, a whole corpus per call.

The method low-passes the angles with a zero-phase Butterworth filter (stage 2 of the method):
order 10, normalised cutoff 0.25 by default. The cutoff is a fraction of the **Nyquist
frequency of the frame rate** (scipy's convention): at the generated data's 34 ms sampling
(29.4 Hz) 0.25 is 3.68 Hz. The filter runs on frames, so it assumes near-uniform sampling
(timestamp jitter is ignored, as in the original method).

All trials of a corpus go through **one** call of the Rust kernel
:func:`visprim.kernels.sosfiltfilt_ragged` (forward-backward second-order sections, odd
extension of ``padlen`` frames at both ends with steady-state initial conditions, identical
to :func:`scipy.signal.sosfiltfilt` per trial).

Short trials
------------
A trial must be longer than the padding (:func:`default_padlen`: 33 frames for order 10).
``short="error"`` (default) raises a :class:`ValueError` naming every short trial;
``short="reduce"`` filters each short trial with the padding reduced to its length − 1
frames (one extra kernel call per distinct short length; the ends of such trials are less
well conditioned).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import kernels

__all__ = [
    "DEFAULT_CUTOFF",
    "DEFAULT_ORDER",
    "butterworth",
    "default_padlen",
    "lowpass",
    "lowpass_concatenated",
    "lowpass_corpus",
]

#: Butterworth order of the method.
DEFAULT_ORDER: int = 10
#: Normalised cutoff (fraction of the Nyquist frequency) of the method.
DEFAULT_CUTOFF: float = 0.25

Short = Literal["error", "reduce"]


def butterworth(order: int = DEFAULT_ORDER, cutoff: float = DEFAULT_CUTOFF) -> NDArray[np.float64]:
    """Second-order sections (n_sections, 6) of a digital Butterworth low-pass (``cutoff``
    as a fraction of Nyquist, in (0, 1)), from the Rust :func:`~visprim.kernels.butter_sos`."""
    return np.asarray(kernels.butter_sos(int(order), float(cutoff)))


def default_padlen(sos: ArrayLike) -> int:
    """Padding (frames) that :func:`scipy.signal.sosfiltfilt` uses by default for ``sos``:
    ``3 · (2 · n_sections + 1 − min(#zero b₂, #zero a₂))``."""
    s = np.asarray(sos, dtype=np.float64)
    if s.ndim != 2 or s.shape[1] != 6:
        raise ValueError(f"sos must have shape (n_sections, 6), got {s.shape}")
    zeros = min(int(np.sum(s[:, 2] == 0)), int(np.sum(s[:, 5] == 0)))
    return 3 * (2 * s.shape[0] + 1 - zeros)


def lowpass_concatenated(
    values: ArrayLike,
    offsets: ArrayLike,
    *,
    order: int = DEFAULT_ORDER,
    cutoff: float = DEFAULT_CUTOFF,
    padlen: int | None = None,
    short: Short = "error",
    names: Sequence[str] | None = None,
) -> NDArray[np.float64]:
    """Low-pass every trial of a concatenated corpus along time.

    Parameters
    ----------
    values : (total_frames, channels) float array
        The trials one after another (e.g. angles in radians; any unit is kept).
    offsets : (n_trials,) int array
        First frame of each trial (starts at 0, strictly increasing, < total_frames).
    order, cutoff : int, float
        Butterworth order and normalised cutoff (fraction of Nyquist, in (0, 1)).
    padlen : int, optional
        Frames of odd extension at each end (default :func:`default_padlen`).
    short : {"error", "reduce"}
        What to do with trials not longer than ``padlen`` (see the module docstring).
    names : sequence of str, optional
        Trial names used in error messages (default: the trial's index).

    Returns
    -------
    (total_frames, channels) float64 array, a new array.
    """
    x = np.ascontiguousarray(values, dtype=np.float64)
    if x.ndim != 2:
        raise ValueError(f"values must have shape (total_frames, channels), got {x.shape}")
    off = np.ascontiguousarray(offsets, dtype=np.int64)
    if off.ndim != 1 or off.size == 0 or off[0] != 0:
        raise ValueError("offsets must be a non-empty 1-D array of first frames starting at 0")
    if np.any(np.diff(off) <= 0) or off[-1] >= x.shape[0]:
        raise ValueError(f"offsets must be strictly increasing and < total_frames ({x.shape[0]})")
    if short not in ("error", "reduce"):
        raise ValueError(f"short must be 'error' or 'reduce', got {short!r}")
    sos = butterworth(order, cutoff)
    pad = default_padlen(sos) if padlen is None else int(padlen)
    if pad < 0:
        raise ValueError(f"padlen must be >= 0, got {padlen}")
    lengths = np.diff(np.append(off, x.shape[0]))
    is_short = lengths <= pad
    if not np.any(is_short):
        return np.asarray(kernels.sosfiltfilt_ragged(sos, x, off, padlen=pad))
    if short == "error":
        idx = np.flatnonzero(is_short)
        listed = ", ".join(
            f"{names[i] if names is not None else f'#{i}'} ({lengths[i]} frames)" for i in idx[:5]
        )
        more = f" and {idx.size - 5} more" if idx.size > 5 else ""
        raise ValueError(
            f"{idx.size} trial(s) have no more frames than the filter padding ({pad} frames "
            f"for order {order}): {listed}{more}; drop them, or pass short='reduce' to pad "
            "them less"
        )
    out = np.empty_like(x)
    starts, ends = off, off + lengths
    groups = [(np.flatnonzero(~is_short), pad)]
    for n in np.unique(lengths[is_short]):
        groups.append((np.flatnonzero(lengths == n), int(n) - 1))
    for idx, p in groups:
        if idx.size == 0:
            continue
        rows = np.concatenate([np.arange(starts[i], ends[i]) for i in idx])
        sub_off = np.concatenate([[0], np.cumsum(lengths[idx])[:-1]]).astype(np.int64)
        out[rows] = kernels.sosfiltfilt_ragged(
            sos, np.ascontiguousarray(x[rows]), sub_off, padlen=p
        )
    return out


def lowpass_corpus(
    arrays: Sequence[ArrayLike],
    *,
    order: int = DEFAULT_ORDER,
    cutoff: float = DEFAULT_CUTOFF,
    padlen: int | None = None,
    short: Short = "error",
    names: Sequence[str] | None = None,
) -> list[NDArray[np.float64]]:
    """Low-pass a list of (T_i, channels) trajectories (all with the same channels) in one
    kernel call; returns a list of new arrays (views into one concatenated result).
    Options as :func:`lowpass_concatenated`."""
    if len(arrays) == 0:
        return []
    parts = [np.asarray(a, dtype=np.float64) for a in arrays]
    for i, a in enumerate(parts):
        if a.ndim != 2 or a.shape[1] != parts[0].shape[1] or a.shape[0] == 0:
            who = names[i] if names is not None else f"#{i}"
            raise ValueError(
                f"trial {who}: expected shape (frames, {parts[0].shape[1]}), got {a.shape}"
            )
    lengths = np.array([a.shape[0] for a in parts], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    out = lowpass_concatenated(
        np.concatenate(parts),
        offsets,
        order=order,
        cutoff=cutoff,
        padlen=padlen,
        short=short,
        names=names,
    )
    return np.split(out, offsets[1:])


def lowpass(
    values: ArrayLike,
    *,
    order: int = DEFAULT_ORDER,
    cutoff: float = DEFAULT_CUTOFF,
    padlen: int | None = None,
    short: Short = "error",
) -> NDArray[np.float64]:
    """Low-pass one (T, channels) trajectory (or a (T,) signal) along time."""
    a = np.asarray(values, dtype=np.float64)
    one_d = a.ndim == 1
    if one_d:
        a = a[:, None]
    out = lowpass_corpus([a], order=order, cutoff=cutoff, padlen=padlen, short=short)[0]
    return out[:, 0] if one_d else out
