"""The two halves of a video at once (``workers=2``): the same clock as one pass, the first
half the same poses, the second half close to them (MediaPipe tracks between frames, so a
fresh start at the split gives slightly different landmarks), and the people rule."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from visprim.io.video_pose import OVERLAP, SPLIT_MIN_FRAMES, FramePose, order_people, video_poses

HAS_MEDIAPIPE = importlib.util.find_spec("mediapipe") is not None
NO_EXTRA = "the video extra is not installed (pip install 'visprim[video]')"
ARM_HIPS = [11, 12, 13, 14, 15, 16, 23, 24]


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISPRIM_CACHE_DIR", str(tmp_path / "cache"))


def _pose(x0: float, y0: float, x1: float, y1: float) -> FramePose:
    image = np.array([[x0, y0], [x1, y1]] * 3, dtype=float)
    return FramePose(world=np.zeros((6, 3)), image=image, confidence=np.ones(6))


def test_people_are_numbered_largest_first_then_leftmost():
    small, big, big_right = _pose(0, 0, 10, 20), _pose(50, 0, 80, 60), _pose(90, 0, 120, 60)
    ordered = order_people([small, big_right, big], (200, 100))
    assert ordered == [big, big_right, small]


@pytest.mark.skipif(not HAS_MEDIAPIPE, reason=NO_EXTRA)
def test_two_halves_match_one_pass(shared_data: Path):
    clip = shared_data / "video" / "pose2sim_single_person" / "cam03.mp4"
    if not clip.is_file():
        pytest.skip(f"shared video clip not found at {clip}")
    n = SPLIT_MIN_FRAMES + 12
    one = video_poses(clip, cache=False, workers=1, max_frames=n)
    two = video_poses(clip, cache=False, workers=2, max_frames=n)
    assert one.meta["passes"] == "one pass"
    assert two.meta["passes"].startswith("two halves at frame"), two.meta["passes"]
    split = int(two.meta["passes"].split("frame ")[1].split(",")[0])
    assert OVERLAP < split < n - OVERLAP
    np.testing.assert_array_equal(two.times, one.times)
    assert two.found.all() and one.found.all()
    np.testing.assert_array_equal(two.image[:split], one.image[:split])
    after = np.linalg.norm(two.image[split:] - one.image[split:], axis=2)[:, ARM_HIPS]
    assert np.median(after) < 5.0, np.median(after)  # pixels of a 1080 × 1920 frame
