"""Video → Trial: the optional extra, the pose cache, no-person handling, and the real
estimator (MediaPipe) on a short piece of the shared Pose2Sim clip."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from visprim.io import ReadError, read
from visprim.io.video import read_video_pieces
from visprim.io.video_pose import FramePose, video_poses

HAS_CV2 = importlib.util.find_spec("cv2") is not None
HAS_MEDIAPIPE = importlib.util.find_spec("mediapipe") is not None
NO_EXTRA = "the video extra is not installed (pip install 'visprim[video]')"
FRAMES = 24


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    """Every test gets its own pose cache (nothing written to the user's or the repo's)."""
    monkeypatch.setenv("VISPRIM_CACHE_DIR", str(tmp_path / "cache"))


@pytest.fixture
def clip(shared_data: Path) -> Path:
    path = shared_data / "video" / "pose2sim_single_person" / "cam01.mp4"
    if not path.is_file():
        pytest.skip(f"shared video clip not found at {path}")
    return path


def test_core_io_never_imports_the_estimator():
    code = (
        "import sys, visprim.io, visprim.io.keypoints, visprim.io.trc, visprim.io.video;"
        "print(sorted(m for m in ('mediapipe', 'cv2') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_without_the_extra_one_line_names_it(tmp_path, monkeypatch):
    f = tmp_path / "clip.mp4"
    f.write_bytes(b"\x00" * 64)
    monkeypatch.setitem(sys.modules, "cv2", None)  # import cv2 -> ImportError
    monkeypatch.setitem(sys.modules, "mediapipe", None)
    with pytest.raises(ReadError) as err:
        read(f)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(str(f))
    assert "pip install 'visprim[video]'" in msg


class _Scripted:
    """A fake estimator: a fixed pose, or no person, or a person jumping across the image."""

    layout = "blazepose33"
    up_axis = "-y"

    def __init__(self, mode: str) -> None:
        self.mode = mode
        self.calls = 0

    @property
    def settings(self) -> dict[str, object]:
        return {"estimator": "scripted", "mode": self.mode}

    def reset(self) -> None:
        self.calls = 0

    def estimate(self, rgb: np.ndarray) -> FramePose | None:
        self.calls += 1
        if self.mode == "nobody":
            return None
        from _keypoint_data import BODY_TO_CAMERA, arm_angles_truth, body_keypoints, to_blazepose

        a = arm_angles_truth(1, 60.0)
        world = to_blazepose(body_keypoints(a, a))[0] @ BODY_TO_CAMERA.T
        image = np.tile([100.0, 400.0], (33, 1))
        if self.mode == "jump" and self.calls > 10:
            image = image + [900.0, 0.0]
        return FramePose(world=world, image=image, confidence=np.ones(33))


@pytest.mark.skipif(not HAS_CV2, reason=NO_EXTRA)
def test_no_person_and_a_jumping_person(clip):
    with pytest.raises(ReadError, match=r"cam01\.mp4: no person found in any of the 20 frames"):
        read_video_pieces(clip, estimator=_Scripted("nobody"), max_frames=20, cache=False)
    with pytest.warns(UserWarning, match="jumps across the image at frame 10"):
        read_video_pieces(
            clip, estimator=_Scripted("jump"), max_frames=20, cache=False, min_duration=0.1
        )
    with pytest.raises(ValueError, match=r"cam01\.mp4: person=1, but 1 person was found"):
        read_video_pieces(clip, estimator=_Scripted("still"), person=1, max_frames=20, cache=False)


@pytest.mark.skipif(not HAS_CV2, reason=NO_EXTRA)
def test_pose_cache_is_keyed_by_content_and_settings(clip, tmp_path):
    est = _Scripted("still")
    first = video_poses(clip, est, max_frames=12)
    assert first.meta["cache"] == "written" and est.calls == 12
    est.calls = 0
    again = video_poses(clip, est, max_frames=12)
    assert again.meta["cache"] == "hit" and est.calls == 0
    np.testing.assert_array_equal(again.world, first.world)
    np.testing.assert_array_equal(again.times, first.times)
    other = _Scripted("jump")
    assert video_poses(clip, other, max_frames=12).meta["cache"] == "written"
    copy = tmp_path / "renamed.mp4"
    copy.write_bytes(clip.read_bytes())  # same content, other name: a hit
    assert video_poses(copy, _Scripted("still"), max_frames=12).meta["cache"] == "hit"
    files = sorted(p.name for p in (tmp_path / "cache" / "pose").iterdir())
    assert len(files) == 2 and all(f.endswith(".npz") and not f.startswith(".tmp") for f in files)


@pytest.mark.skipif(not HAS_MEDIAPIPE, reason=NO_EXTRA)
def test_mediapipe_on_the_shared_clip(clip):
    """The real estimator on the first frames of one view: a person in every frame, the
    video's own clock (60 fps), metric arm segments, and the second read from the cache."""
    trials = read_video_pieces(clip, arm="both", max_frames=FRAMES, min_duration=0.2)
    assert len(trials) == 1
    trial = trials[0]
    assert trial.meta["person_found"] == 1.0
    assert trial.meta["times_from"] == "container timestamps"
    np.testing.assert_allclose(np.diff(trial.times), 1 / 60, atol=1e-6)
    assert trial.times.shape == (FRAMES,)
    j = trial.joints
    for s in (0, 3):  # right, left
        upper = np.median(np.linalg.norm(j[:, s + 1] - j[:, s], axis=1))
        fore = np.median(np.linalg.norm(j[:, s + 2] - j[:, s + 1], axis=1))
        assert 0.20 < upper < 0.40 and 0.18 < fore < 0.35, (upper, fore)
    # Subject standing: the torso's z axis within 45° of the camera's up axis (the lab
    # cameras look down at him, about 25° here, and he leans), and a rotation every frame.
    b = trial.body_frame
    assert b is not None
    assert np.all(b[:, 2, 2] > np.cos(np.deg2rad(45)))
    np.testing.assert_allclose(np.linalg.det(b), 1.0, atol=1e-9)
    again = read_video_pieces(clip, arm="both", max_frames=FRAMES, min_duration=0.2)
    assert again[0].meta["pose_cache"] == "hit"
    np.testing.assert_array_equal(again[0].markers, trial.markers)
