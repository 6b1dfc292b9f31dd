"""The causal low-pass of the online segmenter: its latency.

The offline method filters forward and backward (zero phase), which needs the whole
recording. Online, the angles go once through a causal Butterworth filter (Rust,
:class:`visprim.kernels.OnlineFrontEnd`, with :func:`scipy.signal.sosfilt`'s recursion and its
state kept between chunks, started in the steady state of the first frame; the filter alone
is :class:`visprim.kernels.CausalSos`), whose group delay at low frequencies is the filter's
latency: about 1.7 frames for order 2 at the normalised cutoff 0.25 (58 ms at 34 ms frames),
7.7 frames for order 10 (262 ms). :func:`group_delay_frames` gives it for any order/cutoff.
The output of a chunk does not depend on how the stream was cut into chunks.
"""

from __future__ import annotations

from scipy import signal

from visprim.filtering import butterworth

__all__ = ["group_delay_frames"]


def group_delay_frames(order: int, cutoff: float) -> float:
    """Group delay (frames) of the causal Butterworth filter of ``order`` at the normalised
    ``cutoff`` near 0 Hz."""
    b, a = signal.sos2tf(butterworth(order, cutoff))
    _, gd = signal.group_delay((b, a), w=[1e-3])
    return float(gd[0])
