"""Adonis imitating a stream while it runs: each closed segment's primitive, rebuilt and
played on the DART model (:class:`LiveAdonis`).

For every :class:`~visprim.online.events.SegmentClosed` the segment is rebuilt from its
primitive as :func:`visprim.imitate.imitate` rebuilds it offline: the primitive's centre
in the model's description (``cluster_centers_ @ components_.T + mean_``, as curves of
``n_samples`` samples), scaled by the event's amplitude for models fitted with
``amplitude=True``, plus the segment's own mean posture for ``offsets="mean"`` models (the
mean of the stream's channels over the segment, from the frames :meth:`LiveAdonis.observe`
was given), turned into arm angles (:func:`visprim.features.to_angles`) and brought to the
whole turns of γ and α nearest Adonis' current set point.

Each rebuilt segment is queued and played for the segment's own duration, starting when the
previous one ends or, when Adonis is idle, at once; its first ``bridge`` seconds (at most a
third of it) are a C¹ Hermite bridge from the set point held before
(:class:`visprim.sim.joining.JoinedTrajectory`), so Adonis never jumps. Adonis is held
still between movements.

The servo is :class:`visprim.sim.servo.StablePD` with gravity compensation at the current
posture and the set point's velocity as feedforward, stepped at ``dt`` (default 2 ms) by
:meth:`LiveAdonis.advance` up to the stream's time: the caller advances it after each
chunk, so the simulation follows the stream's clock (the wall clock when the stream is
live). :meth:`LiveAdonis.report` says whether it kept up: the wall time the stepping took
against the simulated time, and the delay between a segment's start in the stream and
Adonis starting to play it.
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.features import from_angles, periodic_channels, to_angles
from visprim.ik import arm_angles_corpus
from visprim.online.events import SegmentClosed
from visprim.online.segmenter import Frames
from visprim.vectors import to_curves

__all__ = ["AdonisReport", "LiveAdonis"]


@dataclass(frozen=True)
class AdonisReport:
    """How Adonis kept up with the stream.

    simulated : seconds simulated; wall : seconds of wall-clock time the stepping took;
    real_time_factor : simulated / wall (above 1: faster than real time); steps : simulation
    steps; segments : segments played (or queued); delay_median, delay_max : seconds from a
    segment's start in the stream to Adonis starting to play it; tracking_rms_deg : RMS of
    the servo's joint error against the set point over the driven joints; behind_max :
    largest lag of the simulation behind the stream when a chunk arrived, seconds.
    """

    simulated: float
    wall: float
    real_time_factor: float
    steps: int
    segments: int
    delay_median: float
    delay_max: float
    tracking_rms_deg: float
    behind_max: float

    @property
    def kept_up(self) -> bool:
        """Stepping took less wall time than it simulated (real time is sustainable)."""
        return self.real_time_factor > 1.0

    def summary(self) -> str:
        """One line."""
        verdict = "kept up" if self.kept_up else "did NOT keep up"
        delay = (
            f"; a segment started playing {self.delay_median:.2f} s (median, max "
            f"{self.delay_max:.2f} s) after it started in the stream"
            if self.segments
            else ""
        )
        return (
            f"Adonis {verdict}: {self.simulated:.2f} s simulated in {self.wall:.2f} s of "
            f"stepping ({self.real_time_factor:.1f}x real time, {self.steps} steps); "
            f"{self.segments} segments played{delay}; tracking {self.tracking_rms_deg:.2f} "
            "deg RMS"
        )


class LiveAdonis:
    """Adonis driven by the primitives of the segments of a stream (module docstring).

    Parameters
    ----------
    model : the fitted PrimitiveModel of the stream's pipeline.
    dt : simulation step, seconds (default 0.002).
    bridge : seconds of the bridge into each segment (default 0.15).
    keep : seconds of stream channels kept for the segments' mean postures (default 30;
        at least the pipeline's longest segment).
    """

    def __init__(
        self, model: Any, *, dt: float = 0.002, bridge: float = 0.15, keep: float = 30.0
    ) -> None:
        from visprim.sim.model import build_adonis
        from visprim.sim.sequencer import positions_to_angles
        from visprim.sim.servo import StablePD

        self.model = model
        self.arms = tuple(getattr(model, "arms_", ("right",)))
        self.features = str(model.features)
        self.n_channels = int(model.n_channels)
        self.dt = float(dt)
        self.bridge = float(bridge)
        self.keep = float(keep)
        self.world, self.skel = build_adonis(self.dt)
        self.servo = StablePD(self.skel, self.dt)
        self.hold = positions_to_angles(self.skel, self.skel.getPositions(), len(self.arms))[0]
        #: Queued set points: (first step, positions (k, n_dofs), velocities (k, n_dofs)).
        self._queue: deque[tuple[int, NDArray[np.float64], NDArray[np.float64]]] = deque()
        self._end_step = 0  # step at which the last queued piece ends
        self._target = self.skel.getPositions().copy()
        self._target_v = np.zeros_like(self._target)
        self._history: deque[tuple[NDArray[np.float64], NDArray[np.float64]]] = deque()
        self._origin: float | None = None  # stream time of simulation time 0
        self.steps = 0
        self._wall = 0.0
        self._delays: list[float] = []
        self._err_sq = 0.0
        self._err_n = 0
        self._behind = 0.0
        self._periodic = [c for c in periodic_channels("zyz", len(self.arms)) if c % 4 in (0, 2)]

    # ------------------------------------------------------------------ input

    def observe(self, frames: Frames) -> None:
        """Keep the stream's channels of ``frames`` (for the segments' mean postures)."""
        if len(frames) == 0:
            return
        if self._origin is None:
            self._origin = float(frames.times[0])
        angles = arm_angles_corpus([frames.as_trial(self.arms)])[0][: len(frames)]
        self._history.append((np.asarray(frames.times), from_angles(angles, self.features)))
        newest = float(frames.times[-1])
        while self._history and float(self._history[0][0][-1]) < newest - self.keep:
            self._history.popleft()

    def _segment_mean(self, start: float, end: float) -> NDArray[np.float64]:
        times = np.concatenate([t for t, _ in self._history])
        values = np.concatenate([v for _, v in self._history])
        inside = (times >= start - 1e-9) & (times <= end + 1e-9)
        if not np.any(inside):  # older than what is kept: the nearest frame
            inside = np.zeros(times.shape[0], dtype=bool)
            inside[int(np.argmin(np.abs(times - start)))] = True
        return np.asarray(values[inside].mean(axis=0))

    def rebuild(self, event: SegmentClosed) -> NDArray[np.float64]:
        """The segment's arm angles (n_samples, 4 n_arms) rebuilt from its primitive."""
        m = self.model
        centre = m.cluster_centers_[event.primitive] @ m.components_.T + m.mean_
        curve = to_curves(centre[None, :], self.n_channels)[0]
        if bool(getattr(m, "amplitude", False)):
            curve = curve * float(event.amplitude)
        if str(m.offsets) == "mean":
            curve = curve + self._segment_mean(event.start, event.end)
        angles = to_angles(curve, self.features)
        for c in self._periodic:  # the whole turns nearest the held set point
            turns = np.round((self.hold[c] - angles[0, c]) / (2 * np.pi))
            angles[:, c] += 2 * np.pi * turns
        return np.asarray(angles)

    def add(self, event: SegmentClosed) -> None:
        """Queue the segment of ``event`` (module docstring)."""
        from visprim.sim.joining import JoinedTrajectory
        from visprim.sim.sequencer import angles_to_positions

        angles = self.rebuild(event)
        duration = max(float(event.end - event.start), 4 * self.dt)
        first = max(self.steps, self._end_step)
        n = max(2, int(round(duration / self.dt)))
        b = min(self.bridge, duration / 3.0)
        t0 = first * self.dt
        bounds = [[t0 - self.dt, t0], [t0 + b, t0 + duration]]
        joined = JoinedTrajectory([np.stack([self.hold, self.hold]), angles], bounds)
        grid = t0 + self.dt * np.arange(1, n + 1)
        a, _ = joined(grid)
        q = angles_to_positions(self.skel, a)
        v = np.empty_like(q)
        prev = angles_to_positions(self.skel, self.hold[None, :])[0]
        for k in range(q.shape[0]):
            v[k] = self.skel.getPositionDifferences(q[k], prev) / self.dt
            prev = q[k]
        self._queue.append((first, q, v))
        self._end_step = first + n
        self.hold = a[-1].copy()
        origin = self._origin if self._origin is not None else 0.0
        self._delays.append(origin + t0 - float(event.start))

    # ------------------------------------------------------------------ simulation

    def advance(self, stream_time: float) -> None:
        """Step the simulation up to ``stream_time`` (seconds on the stream's clock)."""
        if self._origin is None:
            return
        target_steps = int(np.floor((stream_time - self._origin) / self.dt + 1e-9))
        self._behind = max(self._behind, (target_steps - self.steps) * self.dt)
        if target_steps <= self.steps:
            return
        skel, world, servo = self.skel, self.world, self.servo
        kp, kp_dt, kd = servo.kp, servo.kp * self.dt, servo.kd
        start = time.perf_counter()
        while self.steps < target_steps:
            target, velocity = self._set_point(self.steps)
            q = skel.getPositions()
            dq = skel.getVelocities()
            error = skel.getPositionDifferences(target, q)
            self._err_sq += float(error @ error)
            self._err_n += error.size
            tau = kp * error - kp_dt * dq + kd * velocity + skel.getGravityForces()
            skel.setForces(tau)
            world.step()
            self.steps += 1
        self._wall += time.perf_counter() - start

    def drain(self, *, pace: bool = False) -> None:
        """After the stream: step until every queued segment has been played (``pace``:
        on the wall clock, as the stream would have gone on)."""
        if self._origin is None:
            return
        end = self._origin + self._end_step * self.dt
        if not pace:
            self.advance(end)
            return
        now = self._origin + self.steps * self.dt
        wall = time.perf_counter()
        while now < end:
            now = min(end, now + 0.02)
            self.advance(now)
            wait = 0.02 - (time.perf_counter() - wall)
            if wait > 0:
                time.sleep(wait)
            wall = time.perf_counter()

    def _set_point(self, step: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        while self._queue:
            first, q, v = self._queue[0]
            k = step - first
            if k < 0:
                break
            if k < q.shape[0]:
                self._target, self._target_v = q[k], v[k]
                return self._target, self._target_v
            self._queue.popleft()
            self._target, self._target_v = q[-1], np.zeros_like(q[-1])
        return self._target, np.zeros_like(self._target)

    def report(self) -> AdonisReport:
        """How it kept up (see :class:`AdonisReport`)."""
        sim = self.steps * self.dt
        d = np.asarray(self._delays)
        rms = float(np.degrees(np.sqrt(self._err_sq / self._err_n))) if self._err_n else 0.0
        return AdonisReport(
            simulated=sim,
            wall=self._wall,
            real_time_factor=sim / self._wall if self._wall > 0 else float("inf"),
            steps=self.steps,
            segments=len(self._delays),
            delay_median=float(np.median(d)) if d.size else float("nan"),
            delay_max=float(np.max(d)) if d.size else float("nan"),
            tracking_rms_deg=rms,
            behind_max=self._behind,
        )
