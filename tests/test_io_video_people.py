"""Several people in one video: found, numbered largest first, ``person=`` follows another,
and a one-line warning names the file. The two-person clip is built here from two views of
the shared Pose2Sim clip side by side (the left one larger), written to a temporary file."""

from __future__ import annotations

import importlib.util
import warnings
from pathlib import Path

import numpy as np
import pytest
from visprim.io.video import read_video_pieces
from visprim.io.video_pose import video_poses

HAS_MEDIAPIPE = importlib.util.find_spec("mediapipe") is not None
pytestmark = pytest.mark.skipif(
    not HAS_MEDIAPIPE, reason="the video extra is not installed (pip install 'visprim[video]')"
)
FRAMES = 24
HALF = 540  # width of each half of the two-person frame (pixels)
HIPS = [23, 24]


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISPRIM_CACHE_DIR", str(tmp_path / "cache"))


def _frames(path: Path, n: int) -> list[np.ndarray]:
    import cv2

    cap = cv2.VideoCapture(str(path))
    out = []
    while len(out) < n:
        ok, frame = cap.read()
        assert ok, path
        out.append(frame)
    cap.release()
    return out


@pytest.fixture(scope="module")
def two_people(shared_data: Path, tmp_path_factory) -> Path:
    """cam01 on the left at half size, cam02 on the right at 0.8 of that (so the left
    person is the larger), grey around it; 1080 × 960 pixels, 60 fps."""
    import cv2

    folder = shared_data / "video" / "pose2sim_single_person"
    if not (folder / "cam02.mp4").is_file():
        pytest.skip(f"shared video clip not found in {folder}")
    left, right = _frames(folder / "cam01.mp4", FRAMES), _frames(folder / "cam02.mp4", FRAMES)
    out = tmp_path_factory.mktemp("people") / "two_people.mp4"
    writer = cv2.VideoWriter(str(out), cv2.VideoWriter_fourcc(*"mp4v"), 60.0, (2 * HALF, 960))
    small = (round(HALF * 0.8), round(960 * 0.8))
    for a, b in zip(left, right, strict=True):
        frame = np.full((960, 2 * HALF, 3), 128, np.uint8)
        frame[:, :HALF] = cv2.resize(a, (HALF, 960), interpolation=cv2.INTER_AREA)
        y0, x0 = 960 - small[1], HALF + (HALF - small[0]) // 2
        frame[y0:, x0 : x0 + small[0]] = cv2.resize(b, small, interpolation=cv2.INTER_AREA)
        writer.write(frame)
    writer.release()
    assert out.stat().st_size > 0
    return out


def _hips_x(poses) -> np.ndarray:
    return poses.image[poses.found][:, HIPS, 0].mean(axis=1)


def test_two_people_are_found_and_each_can_be_followed(two_people):
    first = video_poses(two_people, cache=False)
    assert first.meta["people"] == 2
    assert first.meta["people_frame"] == 0
    boxes = first.meta["people_boxes"]
    assert (boxes[0][0] + boxes[0][2]) / 2 < HALF < (boxes[1][0] + boxes[1][2]) / 2
    assert first.found.mean() >= 0.95
    assert np.all(_hips_x(first) < HALF)  # person 0: the larger, on the left, every frame
    other = video_poses(two_people, cache=False, person=1)
    assert other.found.mean() >= 0.95
    assert np.all(_hips_x(other) > HALF)  # person 1: on the right, every frame
    with pytest.raises(ValueError, match=r"two_people\.mp4: person=2, but 2 people were found"):
        video_poses(two_people, cache=False, person=2)


def test_several_people_warn_in_one_line_naming_the_file(two_people):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        trials = read_video_pieces(two_people, person=1, min_duration=0.2)
    texts = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    people = [t for t in texts if "people in view" in t]
    assert len(people) == 1 and "\n" not in people[0]
    assert people[0].startswith(f"{two_people}: 2 people in view at 0.00 s; following person 1")
    assert not [t for t in texts if "jumps across the image" in t]
    assert len(trials) == 1 and trials[0].meta["person"] == 1 and trials[0].meta["people"] == 2
