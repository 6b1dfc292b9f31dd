"""The causal low-pass of the online segmenter, and its latency.

The offline method filters forward and backward (zero phase) with the model's Butterworth
filter (order 10, normalised cutoff 0.25 in the paper), which needs the whole recording.
Online, the angles go once through a causal filter (Rust,
:class:`visprim.kernels.OnlineFrontEnd`, with :func:`scipy.signal.sosfilt`'s recursion and
its state kept between chunks, started in the steady state of the first frame; the filter
alone is :class:`visprim.kernels.CausalSos`). Two designs (:func:`causal_lowpass`):

* ``"fir"`` (default): a finite impulse response that approximates the model's own
  zero-phase filter with :data:`FIR_LOOKAHEAD` frame of look-ahead (:func:`fir_taps`). Its
  output for frame ``k − 1`` is known at frame ``k``: the latency is that one frame,
  exactly.
* ``"butterworth"``: a causal Butterworth filter of ``filter_order`` at the model's cutoff,
  whose group delay at low frequencies is its latency: about 1.7 frames for order 2 at the
  normalised cutoff 0.25 (58 ms at 34 ms frames), 7.7 frames for order 10 (262 ms).
  :func:`group_delay_frames` gives it for any order and cutoff.

The output of a chunk does not depend on how the stream was cut into chunks.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy import signal

from visprim.filtering import butterworth
from visprim.params import ONLINE_OPTIONS

__all__ = [
    "CAUSAL_FILTERS",
    "FIR_LOOKAHEAD",
    "FIR_PAST",
    "FIR_STOPBAND_WEIGHT",
    "causal_lowpass",
    "fir_taps",
    "group_delay_frames",
]

#: Names of the causal designs (:func:`causal_lowpass`).
CAUSAL_FILTERS: tuple[str, ...] = tuple(ONLINE_OPTIONS["causal_filter"].choices or ())
#: Look-ahead of the FIR design (frames): its output for a frame is known one frame later.
FIR_LOOKAHEAD: int = 1
#: How many past frames the FIR design reads (32, 1.1 s at 34 ms frames: the zero-phase
#: order-10 filter's response has decayed to below 1 % of its peak by then).
FIR_PAST: int = 32
#: Weight of the frequencies where movement has little power, against the first-order
#: spectrum of movement that weights the fit (:func:`fir_taps`): keeps the stop band from
#: being ignored, so that noise is not passed on to the velocity.
FIR_STOPBAND_WEIGHT: float = 0.1
#: Frequencies of the least-squares design (rad/sample, 0 … π).
_GRID = 4096


def fir_taps(
    order: int,
    cutoff: float,
    *,
    lookahead: int = FIR_LOOKAHEAD,
    past: int = FIR_PAST,
    stopband_weight: float = FIR_STOPBAND_WEIGHT,
) -> NDArray[np.float64]:
    """Taps ``h`` (``lookahead + past``,) of a causal FIR filter whose output ``Σ_i h[i] x[k − i]``
    estimates, at frame ``k``, the zero-phase Butterworth filter (``order``, normalised
    ``cutoff``, forward and backward, response ``|H(ω)|²``) at frame ``k − lookahead``.

    Weighted least squares over the frequencies ``ω`` (rad/sample) of
    ``|Σ_n h_n e^{−iωn} − |H(ω)|²|²`` with ``n`` from ``−lookahead`` to ``past − 1``, weighted
    by ``1 / (1 + (ω / ω_c)²) + stopband_weight`` (``ω_c = π · cutoff``: the first-order
    spectrum of a smooth movement, whose power falls with frequency past the cutoff, plus a
    floor for the stop band); the taps sum to 1 (constant angles pass unchanged). Each design
    is computed once (it takes tens of milliseconds); the array returned is a copy.
    """
    if lookahead < 0 or past < 1:
        raise ValueError(f"need lookahead ≥ 0 and past ≥ 1 frames, got {lookahead}, {past}")
    if not (0.0 < cutoff < 1.0):
        raise ValueError(f"cutoff must be in (0, 1) (normalised), got {cutoff!r}")
    if not (stopband_weight >= 0.0 and np.isfinite(stopband_weight)):
        raise ValueError(f"stopband_weight must be ≥ 0 and finite, got {stopband_weight!r}")
    return _fir_taps(
        int(order), float(cutoff), int(lookahead), int(past), float(stopband_weight)
    ).copy()


@lru_cache(maxsize=32)
def _fir_taps(
    order: int, cutoff: float, lookahead: int, past: int, stopband_weight: float
) -> NDArray[np.float64]:
    w = np.linspace(0.0, np.pi, _GRID)
    _, h = signal.sosfreqz(butterworth(order, cutoff), worN=w)
    target = np.abs(h) ** 2
    n = np.arange(-lookahead, past)
    basis = np.exp(-1j * np.outer(w, n))
    weight = 1.0 / (1.0 + (w / (np.pi * cutoff)) ** 2) + stopband_weight
    # The sum-to-one constraint by elimination: h = e_0 + N g, with N's columns summing to 0.
    k = n.size
    base = np.zeros(k)
    base[lookahead] = 1.0
    null = np.eye(k)[:, 1:] - np.eye(k)[:, :1]
    design = basis @ null
    rhs = target - basis @ base
    a = np.vstack([design.real, design.imag]) * np.concatenate([weight, weight])[:, None]
    b = np.concatenate([rhs.real, rhs.imag]) * np.concatenate([weight, weight])
    g, *_ = np.linalg.lstsq(a, b, rcond=None)
    # Index i of the causal filter reads x[k - i]: n = i - lookahead.
    return base + null @ g


def group_delay_frames(order: int, cutoff: float) -> float:
    """Group delay (frames) of the causal Butterworth filter of ``order`` at the normalised
    ``cutoff`` near 0 Hz."""
    b, a = signal.sos2tf(butterworth(order, cutoff))
    _, gd = signal.group_delay((b, a), w=[1e-3])
    return float(gd[0])


def causal_lowpass(
    kind: str, order: int, cutoff: float, model_order: int
) -> tuple[NDArray[np.float64], int]:
    """Second-order sections ``(n, 6)`` of the causal low-pass ``kind`` (module docstring)
    and its latency in whole frames, by which segment times are reported earlier.

    ``"fir"`` approximates the zero-phase filter of ``model_order`` at ``cutoff`` (its taps
    factored into sections, :func:`scipy.signal.tf2sos`); ``"butterworth"`` is the causal
    filter of ``order`` at ``cutoff``, its latency the rounded group delay. Each design is
    computed once; the sections returned are a copy.
    """
    sos, shift = _causal_lowpass(kind, int(order), float(cutoff), int(model_order))
    return sos.copy(), shift


@lru_cache(maxsize=32)
def _causal_lowpass(
    kind: str, order: int, cutoff: float, model_order: int
) -> tuple[NDArray[np.float64], int]:
    if kind == "fir":
        sos = np.ascontiguousarray(signal.tf2sos(fir_taps(model_order, cutoff), [1.0]))
        shift = FIR_LOOKAHEAD
    elif kind == "butterworth":
        sos = butterworth(order, cutoff)
        shift = int(round(group_delay_frames(order, cutoff)))
    else:
        raise ValueError(f"causal_filter must be one of {list(CAUSAL_FILTERS)}, got {kind!r}")
    return sos, shift
