"""Synthetic two-arm movements of three kinds (raise, wave, sweep of the right arm; the
left arm rests), built from arm angles by forward kinematics."""

from __future__ import annotations

import numpy as np
from visprim.arm import forward_kinematics
from visprim.trial import Trial

PERIOD = 0.034


def _points(angles: np.ndarray, left: bool) -> tuple[np.ndarray, np.ndarray]:
    """Markers (T, 4, 3) and joints (T, 3, 3) of one arm; a left arm is the mirror image
    (y → −y) of a right arm with these angles, its shoulder 0.4 m to the left."""
    pts = forward_kinematics(angles)  # shoulder, elbow, wrist, hand (body frame, metres)
    if left:
        pts = pts * np.array([1.0, -1.0, 1.0]) + np.array([0.0, 0.4, 0.0])
    markers = np.stack(
        [(pts[:, 0] + pts[:, 1]) / 2, (pts[:, 1] + pts[:, 2]) / 2, pts[:, 2], pts[:, 3]], axis=1
    )
    return markers, pts[:, :3]


def _two_arms(right: np.ndarray, left: np.ndarray, name: str) -> Trial:
    mr, jr = _points(right, left=False)
    ml, jl = _points(left, left=True)
    times = np.arange(len(right)) * PERIOD
    return Trial(
        times=times,
        markers=np.concatenate([mr, ml], axis=1),
        joints=np.concatenate([jr, jl], axis=1),
        name=name,
        arms=("right", "left"),
    )


def two_arm_strokes() -> Trial:
    """One stroke of each arm, 90 frames, the right and the left arm moving differently."""
    s = np.linspace(0.0, 1.0, 90)
    right = np.stack(
        [0.4 + 0.8 * s, 0.5 + np.sin(np.pi * s), 0.2 * s, 0.4 + 0.6 * np.sin(2 * np.pi * s)], 1
    )
    left = np.stack([0.3 + 0 * s, 0.4 + 0.9 * np.sin(2 * np.pi * s) ** 2, 0 * s, 1.0 - 0.5 * s], 1)
    return _two_arms(right, left, "both")


def _movement(kind: str, rng: np.random.Generator, i: int) -> Trial:
    duration = rng.uniform(1.6, 2.6)
    s = np.linspace(0.0, 1.0, int(duration / PERIOD))
    a = np.zeros((s.size, 4))
    a[:, 0] = 0.4 + rng.normal(0, 0.05)
    if kind == "raise":
        a[:, 1] = 0.4 + 1.0 * np.sin(np.pi * s)
        a[:, 3] = 0.3
    elif kind == "wave":
        a[:, 1] = 1.3
        a[:, 3] = 0.8 + 0.5 * np.sin(2 * np.pi * 3 * s)
    else:  # "sweep": the raised arm swings from front to side
        a[:, 0] = 0.2 + 1.2 * s
        a[:, 1] = 1.2
        a[:, 3] = 0.5
    a += rng.normal(0, 0.01, a.shape)
    rest = np.tile([0.3, 0.4, 0.0, 0.3], (s.size, 1)) + rng.normal(0, 0.01, a.shape)
    return _two_arms(a, rest, f"{kind}{i}")


def movements(n: int, seed: int) -> tuple[list[Trial], list[str]]:
    rng = np.random.default_rng(seed)
    kinds = ["raise", "wave", "sweep"] * n
    return [_movement(k, rng, i) for i, k in enumerate(kinds)], kinds
