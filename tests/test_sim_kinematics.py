"""The numpy forward kinematics puts every body where DART does, and the playback's frames
are DART's body transforms at the recorded joint positions."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.sim import play
from visprim.sim.kinematics import BatchKinematics
from visprim.sim.model import build_adonis
from visprim.sim.playback import body_transforms
from visprim.sim.trajectories import minimum_jerk


def test_batch_kinematics_matches_dart_for_random_poses() -> None:
    _, skel = build_adonis()
    kin = BatchKinematics(skel)
    rng = np.random.default_rng(7)
    positions = rng.normal(scale=1.5, size=(40, skel.getNumDofs()))
    positions[0] = 0.0
    positions[1, 6:9] = [np.pi - 1e-9, 0.0, 0.0]  # a shoulder turned by almost half a turn
    frames = kin.transforms(positions)
    assert frames.shape == (40, skel.getNumBodyNodes(), 4, 4)
    for q, tf in zip(positions, frames, strict=True):
        skel.setPositions(q)
        np.testing.assert_allclose(tf, body_transforms(skel), atol=1e-12)
    with pytest.raises(ValueError, match=r"\(N, 20\)"):
        kin.transforms(np.zeros((3, 19)))


def test_playback_frames_are_the_bodies_at_the_recorded_positions() -> None:
    world, skel = build_adonis()
    ends = np.array([[0.0, 0.4, 0.0, 0.4], [0.9, 1.4, 0.5, 1.3]])
    times, angles = minimum_jerk(ends, [0.6])
    pb = play(times, angles, model=(world, skel), render_fps=10.0)
    steps = np.rint(pb.frame_times / 0.001).astype(int)
    for i in (0, len(steps) // 2, len(steps) - 1):
        skel.setPositions(pb.q_actual[steps[i]])
        np.testing.assert_allclose(pb.frames[i], body_transforms(skel), atol=1e-12)
