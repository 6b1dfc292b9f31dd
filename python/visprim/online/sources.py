"""Where a watched stream comes from: a recording replayed on its own clock, or a Lab
Streaming Layer (LSL) stream.

Each source is an iterable of :class:`~visprim.online.segmenter.Frames` chunks, ready for
:meth:`OnlinePipeline.push <visprim.online.pipeline.OnlinePipeline.push>`:

* :class:`RecordingSource` — a :class:`~visprim.trial.Trial` (any file
  :func:`visprim.io.read` reads: BVH, AMC, C3D, TRC, marker CSV, or a video through the
  pose reader) cut into chunks of ``chunk`` frames, each given when its last frame is due on
  the recording's clock (``fast=True``: at once);
* :class:`LslSource` — an LSL stream found by name, read through the optional extra
  ``visprim[lsl]`` (mne-lsl, which bundles liblsl; imported only here, when a stream is
  opened). :func:`publish` is the other end: it pushes a recording to a new LSL outlet.

LSL stream layout (:func:`lsl_layout`): ``float32`` or ``float64`` channels, one sample per
frame, metres: the markers (shoulder, elbow, wrist and hand marker of each arm, as in
:class:`~visprim.trial.Trial`: ``4 n_arms × (x, y, z)``), then optionally the joint centres
(``3 n_arms × (x, y, z)``), then optionally the torso frame (its 3 × 3 rotation, row by
row). The channel count tells which: ``12 n_arms``, ``21 n_arms``, ``12 n_arms + 9`` or
``21 n_arms + 9`` (for one arm, 21 channels are markers and joints). Times are the LSL
timestamps, in seconds since the first sample received. A sample whose timestamp does not
come after the last one taken (a sender's clock stepping back, a repeated sample) is left
out and counted (``LslSource.out_of_order``), rather than ending the stream.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.online.segmenter import Frames
from visprim.trial import Trial

__all__ = [
    "LSL_EXTRA",
    "LslSource",
    "RecordingSource",
    "lsl_layout",
    "open_lsl",
    "publish",
]

#: The line printed when the LSL extra is missing.
LSL_EXTRA = (
    "reading or writing Lab Streaming Layer streams needs the optional extra visprim[lsl] "
    "(mne-lsl, which bundles liblsl): pip install 'visprim[lsl]'"
)
#: LSL stream type given to :func:`publish`'s outlet.
STREAM_TYPE = "MoCap"


class RecordingSource:
    """A recording replayed as a stream.

    Parameters
    ----------
    trial : the recording.
    chunk : frames per chunk (default 1).
    fast : give every chunk at once (default False: when its last frame is due, on the
        recording's clock from the first frame; the wall clock is ``clock``).
    clock, sleep : the wall clock (s) and the sleep function (for tests).
    """

    def __init__(
        self,
        trial: Trial,
        *,
        chunk: int = 1,
        fast: bool = False,
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], Any] = time.sleep,
    ) -> None:
        if int(chunk) < 1:
            raise ValueError(f"chunk must be at least one frame, got {chunk!r}")
        self.trial = trial
        self.chunk = int(chunk)
        self.fast = bool(fast)
        self.clock = clock
        self.sleep = sleep
        self.name = trial.name or str(trial.source or "recording")
        #: Largest lateness of a chunk behind its due time, seconds (0 with ``fast``).
        self.max_late = 0.0

    def __iter__(self) -> Iterator[Frames]:
        t = self.trial
        start_wall = self.clock()
        t0 = float(t.times[0]) if t.n_frames else 0.0
        for a in range(0, t.n_frames, self.chunk):
            b = min(t.n_frames, a + self.chunk)
            if not self.fast:
                due = start_wall + float(t.times[b - 1]) - t0
                wait = due - self.clock()
                if wait > 0:
                    self.sleep(wait)
                else:
                    self.max_late = max(self.max_late, -wait)
            yield Frames(
                t.times[a:b],
                t.markers[a:b],
                None if t.joints is None else t.joints[a:b],
                None if t.body_frame is None else t.body_frame[a:b],
            )


@dataclass(frozen=True)
class LslLayout:
    """Which channels of an LSL sample hold what (see the module docstring)."""

    n_arms: int
    joints: bool
    body_frame: bool

    @property
    def n_channels(self) -> int:
        return 12 * self.n_arms + (9 * self.n_arms if self.joints else 0) + (9 * self.body_frame)

    def frames(self, samples: NDArray[Any], times: NDArray[np.float64]) -> Frames:
        """A chunk from ``samples`` (k, n_channels) and ``times`` (k,) seconds."""
        x = np.asarray(samples, dtype=np.float64)
        k, a = x.shape[0], self.n_arms
        markers = x[:, : 12 * a].reshape(k, 4 * a, 3)
        at = 12 * a
        joints = None
        if self.joints:
            joints = x[:, at : at + 9 * a].reshape(k, 3 * a, 3)
            at += 9 * a
        frame = x[:, at : at + 9].reshape(k, 3, 3) if self.body_frame else None
        return Frames(np.asarray(times, dtype=np.float64), markers, joints, frame)


def lsl_layout(n_channels: int, n_arms: int) -> LslLayout:
    """The layout of a stream of ``n_channels`` for ``n_arms`` arms; a ValueError naming
    the counts accepted otherwise."""
    for joints in (True, False):
        for frame in (False, True):
            lay = LslLayout(n_arms, joints, frame)
            if lay.n_channels == n_channels:
                return lay
    a = n_arms
    raise ValueError(
        f"an LSL stream for {a} arm(s) needs {12 * a} channels (markers), {21 * a} (markers "
        f"and joints), {12 * a + 9} or {21 * a + 9} (with the torso frame); it has "
        f"{n_channels}"
    )


_configured = False


def _lsl() -> Any:
    """The mne_lsl.lsl module, or an ImportError whose message is :data:`LSL_EXTRA`.

    Unless ``LSLAPICFG`` names a configuration file, liblsl's own log is limited to fatal
    errors (its info lines, and the error line every outlet's normal end prints, would mix
    with the events)."""
    global _configured
    try:
        lsl = importlib.import_module("mne_lsl.lsl")
    except ImportError as exc:
        err = ImportError(LSL_EXTRA)
        err.name = "mne_lsl"
        raise err from exc
    if not _configured:
        _configured = True
        if not os.environ.get("LSLAPICFG"):
            with contextlib.suppress(Exception):  # an older liblsl: keep its defaults
                lsl.set_config_content("[log]\nlevel = -3\n")
    return lsl


def _lost_error() -> type[BaseException]:
    """liblsl's "stream lost" exception (RuntimeError if mne-lsl moves it)."""
    try:
        utils = importlib.import_module("mne_lsl.lsl._utils")
    except ImportError:
        return RuntimeError
    lost: type[BaseException] = getattr(utils, "LostError", RuntimeError)
    return lost


class LslSource:
    """An LSL stream of motion-capture frames (layout: module docstring).

    Parameters
    ----------
    name : the stream's name.
    n_arms : arms of the model the stream feeds.
    resolve_timeout : seconds to look for the stream before giving up.
    idle : end the stream after this many seconds without a sample (default None: wait
        until interrupted).
    poll : seconds each pull waits for samples.
    """

    def __init__(
        self,
        name: str,
        n_arms: int,
        *,
        resolve_timeout: float = 10.0,
        idle: float | None = None,
        poll: float = 0.02,
    ) -> None:
        if not name:
            raise ValueError("an LSL source needs a stream name: lsl:NAME")
        self.name = name
        self.n_arms = int(n_arms)
        self.resolve_timeout = float(resolve_timeout)
        self.idle = None if idle is None else float(idle)
        self.poll = float(poll)
        self._inlet: Any = None
        self.layout: LslLayout | None = None
        #: Samples left out because their timestamp did not come after the last one taken.
        self.out_of_order = 0

    def open(self) -> None:
        """Find the stream and subscribe to it (a ValueError naming the stream if it cannot
        be found or its layout does not fit)."""
        lsl = _lsl()
        found = lsl.resolve_streams(timeout=self.resolve_timeout, name=self.name)
        if not found:
            raise ValueError(
                f"lsl:{self.name}: no Lab Streaming Layer stream of that name found within "
                f"{self.resolve_timeout:g} s; start its outlet first, or check the name"
            )
        info = found[0]
        self.layout = lsl_layout(int(info.n_channels), self.n_arms)
        inlet = lsl.StreamInlet(info, recover=False)
        inlet.open_stream(timeout=self.resolve_timeout)
        self._inlet = inlet

    def close(self) -> None:
        if self._inlet is not None:
            inlet, self._inlet = self._inlet, None
            inlet.close_stream()

    def __iter__(self) -> Iterator[Frames]:
        if self._inlet is None:
            self.open()
        assert self.layout is not None
        lost = _lost_error()
        first: float | None = None
        newest = -np.inf  # the last timestamp taken
        last_sample = time.perf_counter()
        try:
            while True:
                try:
                    samples, stamps = self._inlet.pull_chunk(timeout=self.poll, max_samples=1024)
                except lost:
                    return
                now = time.perf_counter()
                if len(stamps) == 0:
                    if self.idle is not None and now - last_sample >= self.idle:
                        return
                    continue
                last_sample = now
                stamps = np.asarray(stamps, dtype=np.float64)
                keep = _increasing(stamps, newest)
                if not keep.all():
                    self.out_of_order += int(np.count_nonzero(~keep))
                    if not keep.any():
                        continue
                    samples, stamps = np.asarray(samples)[keep], stamps[keep]
                newest = float(stamps[-1])
                if first is None:
                    first = float(stamps[0])
                yield self.layout.frames(samples, stamps - first)
        finally:
            self.close()


def _increasing(stamps: NDArray[np.float64], newest: float) -> NDArray[np.bool_]:
    """Which of ``stamps`` come after ``newest`` and after every stamp kept before them
    (a running maximum: each kept stamp is later than all earlier ones; NaN is never)."""
    before = np.fmax.accumulate(np.concatenate(([newest], stamps)))[:-1]
    return np.asarray(stamps > before)


def open_lsl(name: str, n_arms: int, **options: Any) -> LslSource:
    """An opened :class:`LslSource` (the stream found and subscribed to)."""
    source = LslSource(name, n_arms, **options)
    source.open()
    return source


def _samples(trial: Trial) -> NDArray[np.float64]:
    parts = [trial.markers.reshape(trial.n_frames, -1)]
    if trial.joints is not None:
        parts.append(trial.joints.reshape(trial.n_frames, -1))
    if trial.body_frame is not None:
        parts.append(trial.body_frame.reshape(trial.n_frames, -1))
    return np.ascontiguousarray(np.concatenate(parts, axis=1))


def publish(
    trial: Trial,
    name: str,
    *,
    fast: bool = False,
    chunk: int = 1,
    wait_for_consumer: float | None = 10.0,
    settle: float = 1.0,
    linger: float = 0.5,
) -> int:
    """Push ``trial`` to a new LSL outlet named ``name`` (``float64`` channels, the layout of
    the module docstring), ``chunk`` frames at a time on the recording's clock (``fast``: as
    fast as the consumer reads), timestamped ``now + (times - times[0])``. Waits up to
    ``wait_for_consumer`` seconds for an inlet, then ``settle`` seconds (liblsl reports the
    consumer before its feed is open, and samples pushed meanwhile are lost), and
    ``linger`` seconds after the last sample; returns the number of frames pushed."""
    lsl = _lsl()
    x = _samples(trial)
    rate = 1.0 / trial.frame_period if trial.n_frames > 1 and trial.frame_period > 0 else 0.0
    info = lsl.StreamInfo(name, STREAM_TYPE, int(x.shape[1]), float(rate), "float64", name)
    outlet = lsl.StreamOutlet(info, chunk_size=1, max_buffered=360)
    if wait_for_consumer is not None:
        if outlet.wait_for_consumers(timeout=wait_for_consumer):
            time.sleep(settle)
    t = trial.times - trial.times[0]
    base = lsl.local_clock()
    wall = time.perf_counter()
    for a, b in ((a, min(trial.n_frames, a + chunk)) for a in range(0, trial.n_frames, chunk)):
        if not fast:
            wait = wall + float(t[b - 1]) - time.perf_counter()
            if wait > 0:
                time.sleep(wait)
        if b - a == 1:
            outlet.push_sample(x[a], timestamp=float(base + t[a]))
        else:
            outlet.push_chunk(x[a:b], timestamp=base + t[a:b])
    time.sleep(linger)
    del outlet
    return int(trial.n_frames)
