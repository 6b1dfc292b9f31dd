"""Online SEG-2: the segments of a stream, each closed as soon as its end is known.

Stages, each causal, frame by frame (chunks of any size give the same segments). Stages
1–3 and the adaptive threshold run in Rust (:class:`visprim.kernels.OnlineFrontEnd`), their
state kept between chunks; SEG-2's rules (4–5) in Python, frame by frame:

0. **Missing values**: a pushed frame with a NaN or infinite marker, joint or body-frame
   value (a marker occluded in a live feed) is left out and counted
   (``missing_frames``); the frames around it are interpolated across the gap by the
   model's clock, or differenced across it without the clock. **A gap** longer than
   ``max_gap`` seconds between complete frames (a long occlusion, a stalled feed; default
   0.2 s, the gap at which reading a recording splits it) is not bridged: the stream so
   far ends there as at :meth:`~OnlineSegmenter.flush` (the movement in progress ends at
   the last frame before the gap), and the frames after it are segmented afresh, as a new
   stream (filter, velocity, threshold and SEG-2 start again; frame counts and movement
   numbers go on), counted in ``gaps``.
   **The model's clock** (``clock="model"``, default, for a model with a
   ``frame_period_``): the stream's frames are resampled causally onto the model's frame
   period (:mod:`visprim.online.clock`), so a 60 Hz stream is filtered and cut as the
   34 ms recordings the model learnt from; every frame count below is of these frames,
   and each event's ``emitted`` time is when the input frame that completed its deciding
   frame arrived. ``clock="stream"``: the frames as they come.

1. **Inverse kinematics** of each pushed frame (:func:`visprim.ik.arm_angles_corpus`'s). For
   bone-direction models γ and α come from ``atan2`` on every frame (directions are exact
   for any γ, and offline's interpolation through the singular cones needs later frames),
   so the segments do not depend on how the stream is cut into chunks. Z-Y-Z models keep
   the interpolation within each chunk and the angles continuous across chunks by whole
   turns (their segments may depend on the chunking near the singular cones).
2. **Causal low-pass** (:mod:`visprim.online.lowpass`) of the angles. By default
   (``causal_filter="fir"``) an FIR filter fitted to the model's own zero-phase filter with
   one frame of look-ahead: the filtered frame ``k − 1`` is known at frame ``k``.
   ``causal_filter="butterworth"`` is a causal Butterworth of ``filter_order`` (default 2)
   at the model's normalised ``cutoff``, which delays by 1.7 frames (58 ms) at order 2 and
   by 7.7 frames (262 ms) at the model's order 10 (``filter_order=None``).
3. The model's per-frame channels (:func:`visprim.features.from_angles`) and
   ``z = Σ θ̇ᵢ²`` with numpy's gradient, central differences from the timestamps: the
   velocity of frame ``k`` needs frame ``k + 1`` (**one frame of look-ahead**).
4. **SEG-2 with the fitted constant** ``c = seg2_threshold_`` and the model's rules
   (:mod:`visprim.segment.seg2`): runs of ``z ≥ c`` that travel more than
   ``min_travel_deg``; a boundary between two such runs at the smallest ``z`` of the rest
   between them, emitted as soon as the second run has lasted ``confirm_frames`` frames
   above ``c`` (default 1: the first frame back above ``c``) or its travel passes
   ``min_travel_deg``, whichever comes first (``confirm_frames=None``: the travel only,
   offline's rule; a run confirmed early counts as a movement whatever its travel). The
   first run of a movement still opens it only once its travel passes ``min_travel_deg``;
   the movement's onset and offset where the arm is at rest
   (``z ≤ c / 25``, the robust tuning's rule; the local minima of ``z`` for models tuned
   by repetitions). ``threshold="adaptive"`` lowers ``c`` for slow movers as the robust
   tuning does per trial, from the 95th percentile of ``z`` over the last
   ``speed_window`` seconds instead of the whole trial.

   Models with ``seg2_boundary="first_stop"`` cut after every significant run at its
   first stop, as offline (:mod:`visprim.segment.seg2`): the first frame after the run
   that is a local minimum of ``z`` (known one frame later, when its successor is not
   lower) or at rest (robust tuning), whichever comes first. The segment is closed there
   at once, whether or not another run follows. A run makes a boundary once its travel
   passes ``min_travel_deg``, as offline; one that lasts ``confirm_frames`` frames above
   ``c`` without that travel only postpones the movement's end (stage 5) as a
   significant run does.
5. A movement **ends** when no significant run has begun ``rest_timeout`` seconds after the
   last one ended and its offset has been found (or when the stream ends): its last
   segment is closed at the offset (``"first_stop"``: it was closed at its stop already;
   the movement's end only waits for the timeout).

Each closed segment is resampled like a training segment
(:func:`visprim.vectors.vectors_from_frames`), projected and assigned its nearest primitive
(:meth:`~visprim.model.PrimitiveModel.assign`). With ``segment_filter="zero_phase"``
(default) the segment's values are not the causal filter's: its raw angles, from
``_LEAD`` frames before its start to the frame that decided its end, go through the model's
own zero-phase filter (:func:`visprim.filtering.lowpass`, the offline order), as offline
(filter and channels in one Rust call, :func:`visprim.kernels.segment_channels`).
This look-ahead costs no latency (those frames have arrived when the segment closes) and
gives the segment the offline shape (a causal filter lags, or smooths less);
``"causal"`` uses the causally filtered values.

Latency (stream time from a segment's last frame to its event): the low-pass' latency
+ one frame (velocity) + the time from the slowest point of the gap until the next run
has lasted ``confirm_frames`` frames above ``c`` (inner boundaries: the gap's slowest
point is only known once the arm speeds up again, so a long pause costs its second half)
or ``rest_timeout`` (a movement's last segment). With ``"first_stop"`` it is bounded:
the filter's latency (1 frame for the FIR; the rounded group delay, 2 frames, for the
order-2 Butterworth) + the frame after the stop + its successor, 3 frames (102 ms at 34 ms
frames; 4 frames, 136 ms, with the Butterworth) for every segment not cut by
``max_segment``. Memory: ring buffers of ``max_segment`` seconds of frames (a longer
segment is cut there, ``forced=True``) and of ``speed_window`` seconds of ``z`` (in the
front end, a sorted window), allocated once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim import kernels
from visprim.features import periodic_channels
from visprim.filtering import butterworth
from visprim.ik import DEFAULT_SINGULAR_ANGLE
from visprim.model import PrimitiveModel
from visprim.online.clock import ModelClock
from visprim.online.events import MovementEnded, SegmentClosed
from visprim.online.lowpass import causal_lowpass
from visprim.online.ring import FrameRing
from visprim.params import ONLINE_OPTIONS
from visprim.segment.seg2 import (
    _ROBUST_QUANTILE,
    _STILL,
    ROBUST_FRACTION,
    ROBUST_REST,
    ROBUST_SLOWEST,
)
from visprim.trial import Trial
from visprim.vectors import OFFSETS, amplitude_gains, turn_offsets

__all__ = ["Frames", "OnlineSegmenter", "frames_of"]

#: The defaults (:data:`visprim.params.ONLINE_OPTIONS`).
_O: dict[str, Any] = {o.name: o.default for o in ONLINE_OPTIONS.values()}

#: Frames processed per step of the state machine (a longer chunk is split).
_BLOCK = 256
#: Adaptive threshold: recomputed every this many frames.
_EVERY = 8
#: Zero-phase segment filter: raw frames before a segment's start that it also filters.
_LEAD = 32


@dataclass(frozen=True)
class Frames:
    """A chunk of a stream: times (k,) seconds, markers (k, 4 n_arms, 3) metres, optional
    joints (k, 3 n_arms, 3) and body_frame (k, 3, 3) (as in :class:`~visprim.trial.Trial`)."""

    times: NDArray[np.float64]
    markers: NDArray[np.float64]
    joints: NDArray[np.float64] | None = None
    body_frame: NDArray[np.float64] | None = None

    def __len__(self) -> int:
        return int(self.times.shape[0])

    def part(self, a: int, b: int) -> Frames:
        return Frames(
            self.times[a:b],
            self.markers[a:b],
            None if self.joints is None else self.joints[a:b],
            None if self.body_frame is None else self.body_frame[a:b],
        )

    def complete(self) -> tuple[Frames, int]:
        """The frames whose markers, joints and body frame are all finite (a frame with an
        occluded marker sent as NaN left out), and how many were left out."""
        arrays = [a for a in (self.markers, self.joints, self.body_frame) if a is not None]
        if all(np.isfinite(a).all() for a in arrays):
            return self, 0
        k = len(self)
        ok = np.isfinite(self.markers.reshape(k, -1)).all(axis=1)
        for a in (self.joints, self.body_frame):
            if a is not None:
                ok &= np.isfinite(a.reshape(k, -1)).all(axis=1)
        return (
            Frames(
                self.times[ok],
                self.markers[ok],
                None if self.joints is None else self.joints[ok],
                None if self.body_frame is None else self.body_frame[ok],
            ),
            int(k - ok.sum()),
        )

    def as_trial(self, arms: tuple[str, ...]) -> Trial:
        """The chunk as a Trial (a one-frame chunk is doubled, 1 µs later, and the copy
        dropped by the caller)."""
        if len(self) == 1:
            dup = Frames(
                np.array([self.times[0], self.times[0] + 1e-6]),
                np.repeat(self.markers, 2, axis=0),
                None if self.joints is None else np.repeat(self.joints, 2, axis=0),
                None if self.body_frame is None else np.repeat(self.body_frame, 2, axis=0),
            )
            return dup.as_trial(arms)
        return Trial(
            times=self.times,
            markers=self.markers,
            joints=self.joints,
            body_frame=self.body_frame,
            arms=arms,
            name="stream",
        )


def frames_of(
    chunk: Trial | Frames | None = None,
    *,
    times: Any = None,
    markers: Any = None,
    joints: Any = None,
    body_frame: Any = None,
) -> Frames:
    """A :class:`Frames` chunk from a Trial, a Frames, or arrays (checked)."""
    if isinstance(chunk, Frames):
        return chunk
    if isinstance(chunk, Trial):
        return Frames(chunk.times, chunk.markers, chunk.joints, chunk.body_frame)
    if chunk is not None:
        raise TypeError(f"expected a Trial or Frames chunk, got {type(chunk).__name__}")
    t = np.atleast_1d(np.asarray(times, dtype=np.float64))
    m = np.asarray(markers, dtype=np.float64)
    if t.ndim != 1 or m.ndim != 3 or m.shape[0] != t.shape[0] or m.shape[2] != 3:
        raise ValueError(
            f"need times (k,) and markers (k, 4 n_arms, 3) of equal k, got {t.shape} and {m.shape}"
        )
    j = None if joints is None else np.asarray(joints, dtype=np.float64)
    f = None if body_frame is None else np.asarray(body_frame, dtype=np.float64)
    return Frames(t, m, j, f)


def _checked(name: str, value: Any) -> Any:
    """``value`` of the setting ``name`` checked against its declaration
    (:data:`visprim.params.ONLINE_OPTIONS`): one of its ``choices``, or a positive finite
    number for a setting in seconds."""
    option = ONLINE_OPTIONS[name]
    if option.choices is not None and value not in option.choices:
        allowed = " or ".join(repr(c) for c in option.choices)
        raise ValueError(f"{name} must be {allowed}, got {value!r}")
    if option.unit == "s":
        try:
            ok = math.isfinite(value) and value > 0
        except TypeError:
            ok = False
        if not ok:
            raise ValueError(f"{name} must be a positive number of seconds, got {value!r}")
    return value


class OnlineSegmenter:
    """SEG-2 segments and their primitives, from frames pushed in chunks (module docstring).

    Parameters
    ----------
    model : fitted PrimitiveModel with a SEG-2 constant (``seg2_threshold_``).
    clock : {"model", "stream"}
        Frames resampled onto the model's frame period (default) or taken as they come
        (module docstring, stage 0).
    causal_filter : {"fir", "butterworth"}
        The causal low-pass (module docstring, :mod:`visprim.online.lowpass`; default
        ``"fir"``).
    filter_order : int or None
        Order of the ``"butterworth"`` low-pass (default 2; None: the model's
        ``filter_order``).
    threshold : {"fixed", "adaptive"}
        ``c`` lowered for slow movers as the offline robust tuning does (default), or
        ``c`` as fitted (module docstring).
    rest_timeout : float, seconds
        Rest after a movement's last run that ends the movement (default 1.0).
    max_segment : float, seconds
        Longest segment held (default 10 s; longer ones are cut, ``forced=True``).
    speed_window : float, seconds
        Window of the adaptive threshold's 95th percentile of ``z`` (default 10 s).
    min_travel_deg : float, degrees
        Travel that makes a run of ``z ≥ c`` a movement (SEG-2's, default 5°).
    confirm_frames : int ≥ 1 or None, frames
        Frames above ``c`` of the next run that confirm an inner boundary (default 1;
        None: its travel must pass ``min_travel_deg``, as offline).
    segment_filter : {"zero_phase", "causal"}
        Values a closed segment is described by (module docstring; default
        ``"zero_phase"``).
    max_gap : float, seconds
        Longest gap between complete frames that is bridged; a longer one splits the
        stream (module docstring, stage 0; default 0.2 s).
    """

    def __init__(
        self,
        model: PrimitiveModel,
        *,
        clock: str = _O["clock"],
        causal_filter: str = _O["causal_filter"],
        filter_order: int | None = _O["filter_order"],
        threshold: str = _O["threshold"],
        rest_timeout: float = _O["rest_timeout"],
        max_segment: float = _O["max_segment"],
        speed_window: float = _O["speed_window"],
        min_travel_deg: float = _O["min_travel_deg"],
        segment_filter: str = _O["segment_filter"],
        confirm_frames: int | None = _O["confirm_frames"],
        max_gap: float = _O["max_gap"],
    ) -> None:
        model._check_fitted()
        c = getattr(model, "seg2_threshold_", None)
        if c is None or not (c > 0):
            raise ValueError("the model has no fitted SEG-2 constant (seg2_threshold_)")
        segment_filter = _checked("segment_filter", segment_filter)
        self.clock = _checked("clock", clock)
        #: Longest gap between complete frames that is bridged, seconds (stage 0).
        self.max_gap = float(_checked("max_gap", max_gap))
        period = getattr(model, "frame_period_", None)
        #: The model's clock (stage 0), or None: the frames as they come.
        self._clock = (
            ModelClock(float(period), self.max_gap)
            if self.clock == "model" and period is not None
            else None
        )
        #: The frames of the last push, on the model's clock (the pushed ones without it).
        self.frames: Frames | None = None
        self.segment_filter = segment_filter
        if confirm_frames is not None and not (
            isinstance(confirm_frames, int | np.integer) and confirm_frames >= 1
        ):
            raise ValueError(
                f"confirm_frames must be a number of frames ≥ 1 or None, got {confirm_frames!r}"
            )
        self.confirm_frames = None if confirm_frames is None else int(confirm_frames)
        threshold = _checked("threshold", threshold)
        rest_timeout = _checked("rest_timeout", rest_timeout)
        max_segment = _checked("max_segment", max_segment)
        speed_window = _checked("speed_window", speed_window)
        self.model = model
        self.arms = tuple(getattr(model, "arms_", ("right",)))
        self.features = str(model.features)
        self.c = float(c)
        self.threshold = threshold
        self.robust = str(model.seg2_tuning) == "robust"
        #: The model's SEG-2 boundary rule: "first_stop" closes each segment at its stop.
        self.first_stop = str(getattr(model, "seg2_boundary", "slowest")) == "first_stop"
        self.rest_timeout = float(rest_timeout)
        self.max_segment = float(max_segment)
        self.speed_window = float(speed_window)
        self.min_travel = float(np.deg2rad(min_travel_deg))
        order = int(model.filter_order) if filter_order is None else int(filter_order)
        #: The causal low-pass (:mod:`visprim.online.lowpass`) and, for ``"butterworth"``,
        #: its order.
        self.causal_filter = _checked("causal_filter", causal_filter)
        self.filter_order = order
        sos, shift = causal_lowpass(
            self.causal_filter, order, float(model.cutoff), int(model.filter_order)
        )
        #: Frames by which the filtered angles lag the movement (the FIR's look-ahead, or
        #: the Butterworth filter's group delay, rounded): segment times are reported that
        #: many frames earlier.
        self._shift = shift
        # Bone directions are exact for any γ, so the causal IK takes γ and α from atan2 on
        # every frame (no interpolation through the singular cones, which needs later
        # frames); Z-Y-Z models keep the interpolation within each chunk.
        singular = 0.0 if self.features == "directions" else DEFAULT_SINGULAR_ANGLE
        #: Stages 1–3 and the threshold (module docstring), state kept between chunks.
        self._front = kernels.OnlineFrontEnd(
            sos,
            list(self.arms),
            self.features,
            singular,
            self.c,
            threshold == "adaptive",
            _ROBUST_QUANTILE,
            ROBUST_FRACTION,
            ROBUST_SLOWEST,
            _EVERY,
            self.speed_window,
        )
        #: Unit bone directions in the torso's axes of the frames of the last push
        #: ``(k, 6 n_arms)`` (:func:`visprim.classify.arm_directions`), from the front end.
        self.bone_directions: NDArray[np.float64] = np.zeros((0, 6 * len(self.arms)))
        self._vector_periodic = periodic_channels(self.features, len(self.arms))
        self._n_samples = int(model.n_samples)
        #: offsets="mean": each channel's mean is taken off a segment vector (else turns).
        self._mean_offsets = str(model.offsets) == "mean"
        if str(model.offsets) not in OFFSETS:
            raise ValueError(f"model offsets must be one of {list(OFFSETS)}, got {model.offsets!r}")
        self._n_channels = int(model.n_channels)
        # The fitted projection and centres, taken once: a closed segment is projected and
        # assigned here directly (model.transform's input checks cost more than the product).
        basis = model.basis_
        #: ``E_f`` (d, f) and ``s̄ E_f`` (f,): ``p = s E_f − s̄ E_f`` (:meth:`PCABasis.project`).
        self._components = np.ascontiguousarray(basis.components(int(model.n_components)))
        self._mean_projection = basis.mean @ self._components
        self._centres = np.ascontiguousarray(model.cluster_centers_, dtype=np.float64)
        #: The model's own (zero-phase) filter of a closed segment's raw angles.
        self._segment_sos = butterworth(int(model.filter_order), float(model.cutoff))
        #: Each primitive's rebuilt vector (offsets="mean"'s amplitude), computed once.
        self._rebuilt: dict[int, NDArray[np.float64]] = {}
        self._ring: FrameRing | None = None
        self._raw: FrameRing | None = None
        self._times: FrameRing | None = None
        self._reset_state()

    # ------------------------------------------------------------------ state

    def _reset_state(self) -> None:
        self.n_frames = 0  #: frames received (on the model's clock)
        self.missing_frames = 0  #: frames pushed with a missing value, left out
        self.gaps = 0  #: gaps longer than max_gap that split the stream
        self._next = 0  #: next frame whose z is to be processed
        self._piece = 0  #: first frame after the last gap (0: the stream's first)
        self._last_time = math.nan  #: time of the last frame (clock="stream": gaps)
        self.movement = -1
        self.decided: list[int] = []
        self._reset_seg2()

    def _reset_seg2(self) -> None:
        """SEG-2's state afresh, from frame ``_piece`` on (a new stream, or after a gap)."""
        self._prev_speed = 0.0
        self._prev_t = float("nan")
        self._prev_z = float("nan")
        self._ck = self.c  #: the threshold of the frame being stepped (from the front end)
        # runs
        self._in_run = False
        self._run_start = -1
        self._run_travel = 0.0
        self._run_sig = False
        self._run_confirmed = False
        self._run_min = (math.inf, -1)
        self._run_end = -1
        # movement
        self._open = False
        self._boundary = -1
        self._n_seg = 0
        self._gap_min = (math.inf, -1)
        self._offset = -1
        self._seeking = False  #: first_stop: a significant run ended, its stop not yet seen
        self._last_run_end_t = float("nan")
        self._last_stop = self._piece
        self._movement_start = float("nan")
        self._final = False

    def _allocate(self, period: float) -> None:
        n = max(8, int(math.ceil(self.max_segment / period)) + 4)
        self._ring = FrameRing(n + _BLOCK + 4, self._n_channels)
        if self.segment_filter == "zero_phase":
            self._raw = FrameRing(n + _BLOCK + 4 + _LEAD, 4 * len(self.arms))
        self._times = FrameRing(n + _BLOCK + 4, 1)
        self._max_frames = n

    @property
    def buffer_bytes(self) -> int:
        """Bytes held by the ring buffers and the front end (fixed once the first chunk set
        them up)."""
        rings = (self._ring, self._raw, self._times)
        clock = 0 if self._clock is None else self._clock.memory_bytes
        return sum(r.nbytes for r in rings if r is not None) + int(self._front.memory_bytes) + clock

    # ------------------------------------------------------------------ input

    def push(self, frames: Frames) -> list[SegmentClosed | MovementEnded]:
        """Add a chunk; returns the segments closed and movements ended, in order."""
        out: list[SegmentClosed | MovementEnded] = []
        arrivals = None
        if self._clock is not None:  # it leaves out frames with missing values itself
            missing = self._clock.missing_frames
            frames, arrivals, breaks = self._clock.push(frames)
            self.missing_frames += self._clock.missing_frames - missing
        else:
            frames, missing = frames.complete()
            self.missing_frames += missing
            breaks = self._gaps_in(frames.times)
        self.frames = frames
        n = len(frames)
        directions: list[NDArray[np.float64]] = []
        cuts = sorted({0, n, *breaks})
        for lo, hi in zip(cuts[:-1], cuts[1:], strict=True):
            if lo in breaks and self.n_frames > 0:
                # Decided when the frame after the gap arrived.
                at = frames.times[lo] if arrivals is None else arrivals[lo]
                out.extend(self._restart(float(at)))
            out.extend(self._push_piece(frames, arrivals, lo, hi, directions))
        self.bone_directions = (
            directions[0]
            if len(directions) == 1
            else np.concatenate(directions)
            if directions
            else np.zeros((0, 6 * len(self.arms)))
        )
        return out

    def _gaps_in(self, times: NDArray[np.float64]) -> list[int]:
        """clock="stream": the indices of the frames that follow a gap longer than
        ``max_gap`` (from the previous chunk's last frame too)."""
        if not len(times):
            return []
        last, self._last_time = self._last_time, float(times[-1])
        if len(times) == 1:  # a frame at a time: no array work
            return [0] if times[0] - last > self.max_gap else []
        steps = np.diff(times, prepend=last)
        return np.flatnonzero(steps > self.max_gap).tolist()

    def _restart(self, emitted: float) -> list[SegmentClosed | MovementEnded]:
        """A gap longer than ``max_gap`` (module docstring, stage 0), found at ``emitted``
        (s): the stream so far ends as at :meth:`flush`, and what follows is segmented as a
        new stream from the next frame, with the frame count and the movement numbers going
        on."""
        self._final = True
        rows = self._front.finish()
        rows[:, 2] = emitted
        out = self._process(rows)
        out.extend(self._end_movement(self.n_frames - 1, final=True, emitted=emitted))
        self._front.reset()
        self.gaps += 1
        self._next = self._piece = self.n_frames
        self._reset_seg2()
        return out

    def _push_piece(
        self,
        frames: Frames,
        arrivals: NDArray[np.float64] | None,
        lo: int,
        hi: int,
        directions: list[NDArray[np.float64]],
    ) -> list[SegmentClosed | MovementEnded]:
        """Frames ``lo:hi`` of the push, with no gap among them, through the front end and
        SEG-2, in blocks of ``_BLOCK``."""
        out: list[SegmentClosed | MovementEnded] = []
        n = len(frames)
        for a in range(lo, hi, _BLOCK):
            b = min(hi, a + _BLOCK)
            part = frames if (a == 0 and b == n) else frames.part(a, b)
            times = np.asarray(part.times, dtype=np.float64)
            angles, values, bones, speeds = self._front.push(
                times,
                np.asarray(part.markers, dtype=np.float64),
                None if part.joints is None else np.asarray(part.joints, dtype=np.float64),
                None if part.body_frame is None else np.asarray(part.body_frame, dtype=np.float64),
            )
            directions.append(bones)
            if arrivals is not None and speeds.shape[0]:
                # A frame is decided when the input frame that completed its successor
                # arrived: the decided-at times are this block's clock times.
                late = arrivals[a : a + times.shape[0]]
                i = np.clip(np.searchsorted(times, speeds[:, 2] - 1e-9), 0, times.shape[0] - 1)
                on = np.abs(times[i] - speeds[:, 2]) <= 1e-9
                speeds[on, 2] = late[i[on]]
            out.extend(self._push_block(values, times, speeds, angles))
        return out

    def push_values(
        self, values: NDArray[np.float64], times: NDArray[np.float64]
    ) -> list[SegmentClosed | MovementEnded]:
        """Add already filtered per-frame channels ``(k, C)`` with their times ``(k,)``."""
        out: list[SegmentClosed | MovementEnded] = []
        values = np.ascontiguousarray(values, dtype=np.float64)
        times = np.ascontiguousarray(times, dtype=np.float64)
        for a in range(0, times.shape[0], _BLOCK):
            b = min(times.shape[0], a + _BLOCK)
            speeds = self._front.push_values(times[a:b], values[a:b])
            out.extend(self._push_block(values[a:b], times[a:b], speeds))
        return out

    def _push_block(
        self,
        values: NDArray[np.float64],
        times: NDArray[np.float64],
        speeds: NDArray[np.float64],
        angles: NDArray[np.float64] | None = None,
    ) -> list[SegmentClosed | MovementEnded]:
        """Hold a block the front end has processed (its checks passed) and step SEG-2
        through the frames whose ``z`` became known (``speeds``)."""
        k = times.shape[0]
        if k == 0:
            return []
        if self._ring is None:
            period = self._front.period
            assert period is not None  # set by the front end's first chunk
            self._allocate(period)
        assert self._ring is not None and self._times is not None
        self._ring.extend(values)
        if self._raw is not None:
            if angles is None:  # push_values: no raw angles, the causal values describe
                self._raw = None
            else:
                self._raw.extend(angles)
        self._times.extend(times[:, None])
        self.n_frames += k
        return self._process(speeds)

    def flush(self) -> list[SegmentClosed | MovementEnded]:
        """End of the stream: the last frame's velocity by a backward difference, and the
        open movement closed at its offset (or the last frame)."""
        if self.n_frames == 0:
            return []
        self._final = True
        out = self._process(self._front.finish())
        out.extend(self._end_movement(self.n_frames - 1, final=True))
        return out

    def reset(self) -> None:
        """Forget the stream (buffers kept)."""
        self._front.reset()
        if self._clock is not None:
            self._clock.reset()
        self._reset_state()
        if self._ring is not None:
            self._ring.end = self._times.end = 0  # type: ignore[union-attr]
            if self._raw is not None:
                self._raw.end = 0

    # ------------------------------------------------------------------ SEG-2

    def _is_stop(self, z: float, c: float) -> bool:
        return z <= (ROBUST_REST * c if self.robust else _STILL * c)

    def _process(self, speeds: NDArray[np.float64]) -> list[SegmentClosed | MovementEnded]:
        """SEG-2 steps through the rows ``(z, t, decided at, threshold)`` of the front end,
        frames ``_next, _next + 1, ...``."""
        out: list[SegmentClosed | MovementEnded] = []
        base = self._next
        rows = speeds.tolist()
        for j, (z, t, emitted, c) in enumerate(rows):
            self._ck = c
            self._step(base + j, z, t, emitted, out)
        self._next = base + len(rows)
        return out

    def _threshold(self, f: int) -> float:
        """The threshold of frame ``f`` (the one being stepped): ``c``, or the adaptive
        value the front end computed (module docstring)."""
        return self._ck

    def _step(
        self, f: int, z: float, t: float, emitted: float, out: list[SegmentClosed | MovementEnded]
    ) -> None:
        c = self._threshold(f)
        speed = math.sqrt(z)
        first = f == self._piece  # the first frame of the stream, or after a gap
        step = 0.0 if first else 0.5 * (speed + self._prev_speed) * (t - self._prev_t)
        local_min_back = first or (self._prev_z >= z)
        self._prev_speed, self._prev_t = speed, t
        prev_z, self._prev_z = self._prev_z, z
        at_rest = self._is_stop(z, c) or z <= _STILL * c
        stop = at_rest
        if not self.robust:
            stop = stop or local_min_back
        if z >= c:
            if self._seeking:
                # first_stop: the frame before a new run is a local minimum (z rose to c),
                # the last one's stop if none came before it.
                self._seeking = False
                self._close_at_stop(f - 1, f, emitted, out)
            if not self._in_run:
                self._in_run = True
                self._run_start = f
                self._run_travel = 0.0
                self._run_sig = False
                self._run_confirmed = False
                self._run_min = (z, f)
            else:
                self._run_travel += step
                if z < self._run_min[0]:
                    self._run_min = (z, f)
            if not self._run_sig and self._run_travel > self.min_travel:
                self._run_sig = True
                if not self._run_confirmed or self.first_stop:
                    self._significant(f, t, emitted, out)
            elif (
                self._open
                and not self._run_sig
                and not self._run_confirmed
                and self.confirm_frames is not None
                and f - self._run_start + 1 >= self.confirm_frames
            ):
                # Early confirmation: the run has lasted confirm_frames frames above c; the
                # boundary at the slowest point of the gap is emitted now, and the run
                # counts as a movement whatever its travel (first_stop: it only keeps the
                # movement going, no boundary).
                self._run_confirmed = True
                if not self.first_stop:
                    self._significant(f, t, emitted, out)
        else:
            if self._in_run:
                self._in_run = False
                self._run_end = f - 1
                if self._run_sig or (self._run_confirmed and not self.first_stop):
                    # A significant run ended: the gap starts here.
                    self._gap_min = (math.inf, -1)
                    self._offset = -1
                    self._last_run_end_t = t
                    self._seeking = self.first_stop and self._open
                elif self._open:
                    if self._run_confirmed:
                        # first_stop: a short run above c postpones the movement's end.
                        self._last_run_end_t = t
                    if self._run_min[0] < self._gap_min[0]:
                        self._gap_min = self._run_min
            if self._open and z < self._gap_min[0]:
                self._gap_min = (z, f)
            if self._seeking:
                # first_stop: the run's first stop, a local minimum of z (frame f - 1, its
                # successor f not lower) or rest (frame f), whichever comes first.
                if f - 1 > self._run_end and z >= prev_z:
                    b = f - 1
                elif at_rest:
                    b = f
                else:
                    b = -1
                if b >= 0:
                    self._seeking = False
                    self._close_at_stop(b, f, emitted, out)
            # The movement's offset if no run follows: the first stop after the last run
            # (robust: at rest; by repetitions: the first local minimum of z).
            if self._open and self._offset < 0 and not self.first_stop:
                if self.robust and stop:
                    self._offset = f
                elif not self.robust and (z <= _STILL * c):
                    self._offset = f
                elif not self.robust and z >= prev_z and f - 1 >= 0 and prev_z < c:
                    self._offset = f - 1
        if stop:
            self._last_stop = f
        # Forced cut of an over-long segment.
        if self._open and f - self._boundary >= self._max_frames - 1:
            out.append(self._close(self._boundary, f, emitted, forced=True, upto=f + 2))
            self._boundary = f
            self._gap_min = (math.inf, -1)
        # End of the movement after the rest timeout.
        if (
            self._open
            and not self._in_run
            and self._offset >= 0
            and t - self._last_run_end_t >= self.rest_timeout
        ):
            out.extend(self._end_movement(f, final=False, emitted=emitted))

    def _significant(
        self, f: int, t: float, emitted: float, out: list[SegmentClosed | MovementEnded]
    ) -> None:
        if not self._open:
            self._open = True
            self.movement += 1
            self._n_seg = 0
            assert self._ring is not None
            self._boundary = max(self._last_stop, self._ring.start, f - self._max_frames + 2)
            self._movement_start = self._movement_time(self._boundary)
            return
        if self.first_stop:
            return  # the segment was closed at the last run's stop
        b = self._gap_min[1]
        if b < 0 or b <= self._boundary:
            return
        out.append(self._close(self._boundary, b, emitted, forced=False, upto=f + 2))
        self._boundary = b

    def _close_at_stop(
        self, b: int, f: int, emitted: float, out: list[SegmentClosed | MovementEnded]
    ) -> None:
        """first_stop: close the segment in progress at frame ``b`` (the last run's stop),
        decided at frame ``f``; ``b`` is also the movement's offset if no run follows."""
        if b > self._boundary:
            out.append(self._close(self._boundary, b, emitted, forced=False, upto=f + 2))
            self._boundary = b
        self._offset = max(b, self._boundary)
        self._gap_min = (math.inf, -1)

    def _end_movement(
        self, f: int, *, final: bool, emitted: float | None = None
    ) -> list[SegmentClosed | MovementEnded]:
        """Close the open movement: its last segment, then a MovementEnded (no class)."""
        out: list[SegmentClosed | MovementEnded] = []
        if not self._open:
            return out
        assert self._times is not None
        if emitted is None:
            emitted = float(self._times.frame(self.n_frames - 1)[0])
        end = self._offset if self._offset >= 0 else (self.n_frames - 1 if final else f)
        if self._in_run and final:
            end = self.n_frames - 1
        if end > self._boundary:
            upto = self.n_frames if final else f + 2
            out.append(self._close(self._boundary, end, emitted, forced=False, upto=upto))
        out.append(
            MovementEnded(
                start=self._movement_start,
                end=self._movement_time(end),
                label="",
                confidence=0.0,
                n_segments=self._n_seg,
                movement=self.movement,
                emitted=emitted,
            )
        )
        #: Frames received when each movement end was decided (for the recogniser).
        self.decided.append(self.n_frames if final else min(f + 2, self.n_frames))
        self._open = False
        self._gap_min = (math.inf, -1)
        self._offset = -1
        return out

    def _movement_time(self, f: int) -> float:
        """When the movement was where the filtered frame ``f`` shows it: ``shift`` frames
        earlier, but not before the stream's first frame (or the first after a gap); the
        stream's last frame (an open end at the end of the stream, or before a gap) stays
        itself."""
        if self._final and f == self.n_frames - 1:
            return self._time(f)
        return self._time(max(f - self._shift, self._piece))

    _final = False

    def _time(self, f: int) -> float:
        """Time of frame ``f`` (before the first frame: extrapolated by the frame period)."""
        assert self._times is not None
        first = self._times.start
        if f >= first:
            return float(self._times.frame(f)[0])
        t0 = float(self._times.frame(first)[0])
        t1 = float(self._times.frame(first + 1)[0]) if self._times.end > first + 1 else t0
        return t0 - (first - f) * (t1 - t0)

    def _segment_values(self, a: int, b: int, upto: int) -> NDArray[np.float64]:
        """Values of the segment between the filtered frames ``a`` and ``b``: the causal
        values of ``[a, b]``, or the raw angles of ``[a' − _LEAD, upto)`` through the model's
        zero-phase filter, kept on ``[a', b']``, the raw frames where the segment's reported
        times are (``a − shift``, ``b − shift``: :meth:`_movement_time`; the causal values
        lag the raw frames by the filter's delay, the zero-phase ones do not) (module
        docstring)."""
        assert self._ring is not None
        if self._raw is None:
            return self._ring.window(a, b + 1)
        first = max(self._raw.start, self._piece)  # no frame from before a gap
        ra = max(first, a - self._shift)
        rb = b if self._final and b == self.n_frames - 1 else b - self._shift
        rb = max(rb, ra + 1)
        upto = min(upto, self._raw.end)
        lo = max(first, ra - _LEAD)
        raw = self._raw.window(lo, upto)
        # lowpass(raw, short="reduce") then from_angles, in one Rust call.
        return kernels.segment_channels(
            self._segment_sos, raw, ra - lo, min(rb + 1 - lo, raw.shape[0]), self.features
        )

    def _vectors(self, values: NDArray[np.float64]) -> NDArray[np.float64]:
        """The segment vector ``(1, d)`` of a closed segment's values ``(k, C)``:
        :func:`~visprim.vectors.vectors_from_frames` of the whole of ``values`` (the same
        kernel and arithmetic: resampled to ``n_samples``, less each channel's mean or whole
        turns), without its argument checks and result record (equal to it in
        ``tests/test_online_close.py``)."""
        n = self._n_samples
        vectors = np.asarray(
            kernels.resample_segments(
                values, np.zeros(1), np.array([float(values.shape[0] - 1)]), n=n
            )
        )
        c = values.shape[1]
        if self._mean_offsets:
            # numpy's mean (ndarray.mean: the sum, then divided by the count), without its
            # Python wrapper.
            shift = np.add.reduce(vectors.reshape(1, c, n), axis=2) / n
        else:
            shift = turn_offsets(vectors, n, self._vector_periodic)
        if np.any(shift):
            vectors = (vectors.reshape(-1, c, n) - shift[:, :, None]).reshape(vectors.shape)
        return vectors

    def _project(self, vectors: NDArray[np.float64]) -> NDArray[np.float64]:
        """Projections ``(N, f)`` of segment vectors ``(N, d)`` (radians): ``s E_f − s̄ E_f``,
        :meth:`~visprim.model.PrimitiveModel.transform`'s formula without its input checks
        (the vectors are the resampler's, float64 and C-ordered) or its one-thread BLAS
        context (a vector-matrix product has no thread-dependent summation; equal to
        ``transform`` in ``tests/test_online_close.py``)."""
        return np.asarray(vectors @ self._components - self._mean_projection)

    def _close(self, a: int, b: int, emitted: float, *, forced: bool, upto: int) -> SegmentClosed:
        assert self._ring is not None
        a = max(a, self._ring.start)
        values = self._segment_values(a, b, upto)
        start, end = self._movement_time(a), self._movement_time(b)
        vectors = self._vectors(values)
        labels, dist = kernels.kmeans_predict(self._project(vectors), self._centres)
        amplitude = 1.0
        if self._mean_offsets:
            k = int(labels[0])
            rebuilt = self._rebuilt.get(k)
            if rebuilt is None:
                rebuilt = self.model.cluster_centers_[k] @ self.model.components_.T
                rebuilt = self._rebuilt[k] = rebuilt + self.model.mean_
            amplitude = float(amplitude_gains(vectors, rebuilt[None, :])[0])
        index = self._n_seg
        self._n_seg += 1
        return SegmentClosed(
            start=start,
            end=end,
            primitive=int(labels[0]),
            distance=float(dist[0]),
            amplitude=amplitude,
            movement=self.movement,
            index=index,
            forced=forced,
            emitted=emitted,
        )
