"""How much of the movement the segments hold: coverage of moving time.

A frame is *moving* when some wrist moves faster than ``speed`` (default 0.1 m/s, about a
tenth of a brisk reach) relative to its shoulder, in the torso's frame (turning or walking
with a still arm is not arm movement); the shoulder-relative position is
low-passed like the angles before it is differentiated, so marker noise does not count as
movement. Coverage is the fraction of the moving frames that fall inside a segment: a
segmentation that drops the slow return stroke of a movement, or a whole slow trial, loses
coverage; one that keeps a rest inside a segment does not gain any.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from visprim.filtering import lowpass_concatenated
from visprim.ik import implied_joint_centres
from visprim.trial import Trial

#: Wrist speed relative to the shoulder above which a frame is moving, m/s.
DEFAULT_MOVING_SPEED: float = 0.1

__all__ = ["DEFAULT_MOVING_SPEED", "moving_frames", "segment_coverage"]


def moving_frames(
    trials: Sequence[Trial],
    *,
    speed: float = DEFAULT_MOVING_SPEED,
    order: int = 10,
    cutoff: float = 0.25,
) -> list[NDArray[np.bool_]]:
    """Per trial, (T,) booleans: frames where some wrist moves faster than ``speed`` (m/s)
    relative to its shoulder in the torso frame (positions low-passed with
    ``order``/``cutoff`` first)."""
    if not trials:
        return []
    rel = []
    for t in trials:
        arms = []
        for a in range(t.n_arms):
            if t.joints is not None:
                centres = t.joints[:, 3 * a : 3 * a + 3]
            else:
                centres = implied_joint_centres(t.markers[:, 4 * a : 4 * a + 4])
            r = centres[:, 2] - centres[:, 0]
            if t.body_frame is not None:  # recording axes -> body axes: v_B = Fᵀ v
                r = np.einsum("tji,tj->ti", t.body_frame, r)
            arms.append(r)
        rel.append(np.concatenate(arms, axis=1))
    lengths = np.array([t.n_frames for t in trials], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    smooth = lowpass_concatenated(
        np.concatenate(rel), offsets, order=order, cutoff=cutoff, short="reduce"
    )
    out = []
    for t, part in zip(trials, np.split(smooth, offsets[1:]), strict=True):
        v = np.gradient(part, t.times, axis=0)
        per_arm = np.linalg.norm(v.reshape(t.n_frames, t.n_arms, 3), axis=2)
        out.append(per_arm.max(axis=1) > float(speed))
    return out


def segment_coverage(
    trials: Sequence[Trial],
    segments: Sequence[NDArray[np.float64]],
    *,
    speed: float = DEFAULT_MOVING_SPEED,
) -> NDArray[np.float64]:
    """Per trial, the fraction of moving frames inside one of its segments ((n_i, 2)
    seconds each); NaN for a trial that never moves."""
    if len(trials) != len(segments):
        raise ValueError(f"{len(trials)} trials but {len(segments)} segment lists")
    out = np.full(len(trials), np.nan)
    for i, (t, moving, seg) in enumerate(
        zip(trials, moving_frames(trials, speed=speed), segments, strict=True)
    ):
        if not moving.any():
            continue
        inside = np.zeros(t.n_frames, dtype=bool)
        for start, end in np.asarray(seg, dtype=np.float64).reshape(-1, 2):
            inside |= (t.times >= start) & (t.times <= end)
        out[i] = float(np.mean(inside[moving]))
    return out
