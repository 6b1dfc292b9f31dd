"""A playback frame redraws only the box that changed since the last one: any order of
frames, and poses between frames, give the pixels a drawer drawing its first (whole) frame
gives."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.sim.playback import play
from visprim.sim.render import Camera, PlaybackDrawer
from visprim.sim.trajectories import minimum_jerk

SIZE = (120, 100)


@pytest.fixture(scope="module")
def playback():
    postures = np.array([[0.0, 0.3, 0.0, 0.3], [0.5, 1.6, 0.3, 1.2], [-0.2, 0.8, 0.6, 0.4]])
    times, angles = minimum_jerk(postures, [0.5, 0.5])
    return play(times, angles, render_fps=10.0)


def _whole(playback, index, **kw):
    return np.asarray(PlaybackDrawer(playback, Camera(), SIZE, "t").draw(index, **kw))


def test_frames_in_any_order_equal_whole_frames(playback) -> None:
    n = playback.frames.shape[0]
    drawer = PlaybackDrawer(playback, Camera(), SIZE, "t")
    order = [*range(n), n // 2, 0, n - 1, 2, 2]
    drawn = [np.asarray(drawer.draw(i)) for i in order]
    for i, image in zip(order, drawn, strict=True):
        np.testing.assert_array_equal(image, _whole(playback, i))
    assert not np.array_equal(drawn[0], drawn[n - 1])  # the body moved


def test_poses_between_frames_equal_whole_frames(playback) -> None:
    n = playback.frames.shape[0]
    drawer = PlaybackDrawer(playback, Camera(), SIZE, "t")
    for i in range(n):
        tfs = np.asarray(playback.frames[(i * 3) % n])  # another frame's pose
        image = np.asarray(drawer.draw(i, transforms=tfs, time=float(i) / 10.0))
        np.testing.assert_array_equal(
            image, _whole(playback, i, transforms=tfs, time=float(i) / 10.0)
        )
