"""Time alignment of the views (``sync=`` of read_views): synthetic cameras filming
visprim's own forward-kinematics skeleton with known frame offsets, and the shared clip
with one view shifted on purpose."""

from __future__ import annotations

import dataclasses
import importlib.util

import numpy as np
import pytest
from _keypoint_data import arm_angles_truth, body_keypoints, to_blazepose
from visprim.io.calibration import Camera
from visprim.io.video_pose import VideoPoses
from visprim.io.views import (
    SIDE_PAIRS,
    epipolar_distance,
    estimate_offsets,
    triangulate_poses,
)

RATE = 60.0
CENTRES = ([3.0, 0.5, 1.6], [-0.5, 3.2, 1.8], [-3.0, -1.0, 2.1], [0.8, -3.1, 1.9])


def _cameras() -> list[Camera]:
    k = np.array([[1700.0, 0.0, 540.0], [0.0, 1700.0, 960.0], [0.0, 0.0, 1.0]])
    dist = np.array([-0.01, 0.02, 0.0005, -0.0003, 0.0])
    cams = []
    for i, c in enumerate(CENTRES):
        f = np.array([0.0, 0.0, 1.0]) - np.array(c)
        f /= np.linalg.norm(f)
        x = np.cross(f, [0.0, 0.0, 1.0])
        x /= np.linalg.norm(x)
        r = np.stack([x, np.cross(f, x), f])
        cams.append(Camera(f"cam{i + 1:02d}", (1088, 1920), k, dist, r, -r @ np.array(c)))
    return cams


#: Still BlazePose points the arms' FK does not give (m, body frame: x forward, y left,
#: z up): left index, right index, and the left one's position (the right one mirrored).
STILL_PAIRS = (
    (1, 4, (0.08, 0.03, 1.62)),  # eyes (inner)
    (2, 5, (0.08, 0.04, 1.63)),
    (3, 6, (0.08, 0.05, 1.63)),
    (7, 8, (0.0, 0.08, 1.60)),  # ears
    (9, 10, (0.09, 0.025, 1.55)),  # mouth
    (25, 26, (0.02, 0.10, 0.50)),  # knees
    (27, 28, (0.0, 0.11, 0.08)),  # ankles
    (29, 30, (-0.05, 0.11, 0.04)),  # heels
    (31, 32, (0.15, 0.12, 0.02)),  # toes
)


def _skeleton(n: int) -> np.ndarray:
    """(n, 33, 3) BlazePose points (m) of both arms moving (visprim's FK), the rest still
    and distinct (every left/right pair is two different points)."""
    kp = body_keypoints(arm_angles_truth(n, RATE / 8), arm_angles_truth(n, RATE / 8, 1.3))
    pts = to_blazepose(kp)
    pts[:, 0] = (0.1, 0.0, 1.58)  # nose
    for left, right, (x, y, z) in STILL_PAIRS:
        pts[:, left] = (x, y, z)
        pts[:, right] = (x, -y, z)
    pts[:, 21] = pts[:, 15] + (pts[:, 15] - pts[:, 13]) * 0.2  # thumbs: along the forearm
    pts[:, 22] = pts[:, 16] + (pts[:, 16] - pts[:, 14]) * 0.2
    return pts


def _poses(
    offsets: list[int], frames: int = 90, noise: float = 0.0, seed: int = 0
) -> tuple[list[Camera], list[VideoPoses], np.ndarray]:
    """Each view films the same motion; view v's frame i + offsets[v] is the instant of the
    first view's frame i (so view v starts offsets[v] frames after the common origin)."""
    cams = _cameras()
    pad = max(abs(o) for o in offsets)
    truth = _skeleton(frames + 2 * pad)  # instants −pad … frames + pad
    rng = np.random.default_rng(seed)
    poses = []
    for cam, o in zip(cams, offsets, strict=True):
        inst = truth[pad - o : pad - o + frames]  # frame j shows instant j − o
        pix = cam.project(inst) + rng.normal(0.0, noise, inst.shape[:2] + (2,))
        poses.append(
            VideoPoses(
                times=np.arange(frames) / RATE,
                world=np.zeros_like(inst),
                image=pix,
                confidence=np.ones(inst.shape[:2]),
                found=np.ones(frames, dtype=bool),
                size=cam.size,
                meta={"layout": "blazepose33", "rate": RATE},
            )
        )
    return cams, poses, truth[pad : pad + frames]


def test_epipolar_distance_is_zero_for_one_point_and_grows_off_it():
    cams = _cameras()
    pts = _skeleton(5)
    na, nb = (c.undistort(c.project(pts)) for c in cams[:2])
    assert np.nanmax(epipolar_distance(cams[0], cams[1], na, nb)) < 1e-6
    moved = cams[1].undistort(cams[1].project(pts + [0.0, 0.0, 0.05]))
    assert np.nanmedian(epipolar_distance(cams[0], cams[1], na, moved)) > 5.0


@pytest.mark.parametrize("noise", [0.0, 2.0])
def test_known_offsets_are_recovered(noise):
    offsets = [0, 3, -5, 7]
    cams, poses, truth = _poses(offsets, noise=noise)
    pairs = SIDE_PAIRS["blazepose33"]
    found, record = estimate_offsets(poses, cams, max_offset=12, pairs=pairs)
    assert found == offsets, record
    assert record["inconsistency_frames"] == 0
    mv = triangulate_poses(poses, cams, sync=True, max_reprojection=None)
    assert mv.meta["offsets"] == offsets
    # the first view's frames that every view has: 5 … 90 − 7
    assert mv.meta["frames"] == 90 - 7 - 5 and mv.times[0] == pytest.approx(5 / RATE)
    err = np.linalg.norm(mv.points - truth[5 : 90 - 7], axis=-1)
    assert np.nanmedian(err) < 0.001 + 0.002 * noise
    plain = triangulate_poses(poses, cams, sync=False, max_reprojection=None)
    arms = slice(13, 23)  # elbows, wrists, hands: the points that move
    synced = np.nanmedian(mv.reprojection[:, arms])
    assert np.nanmedian(plain.reprojection[:, arms]) > 5 * synced + 1.0


def test_offsets_survive_a_left_right_exchange():
    offsets = [0, -4, 2, 0]
    cams, poses, _ = _poses(offsets, noise=1.0, seed=3)
    img = poses[2].image
    for a, b in SIDE_PAIRS["blazepose33"]:  # view 3 mirrored for 30 frames
        img[20:50, [a, b]] = img[20:50, [b, a]]
    found, _ = estimate_offsets(poses, cams, max_offset=12, pairs=SIDE_PAIRS["blazepose33"])
    assert found == offsets


def test_still_scene_keeps_zero_and_given_offsets_are_used():
    cams, poses, _ = _poses([0, 0, 0, 0], frames=40)
    still = [dataclasses.replace(q, image=np.repeat(q.image[:1], 40, axis=0)) for q in poses]
    assert estimate_offsets(still, cams, max_offset=6)[0] == [0, 0, 0, 0]
    cams, poses, truth = _poses([0, 2, 0, -1], frames=40)
    mv = triangulate_poses(poses, cams, sync=[0, 2, 0, -1], max_reprojection=None)
    assert mv.meta["offsets"] == [0, 2, 0, -1] and mv.meta["sync"] is None
    np.testing.assert_allclose(mv.points, truth[1:38], atol=1e-6)
    with pytest.raises(ValueError, match="one whole-frame offset per view"):
        triangulate_poses(poses, cams, sync=[0, 1])
    with pytest.raises(ValueError, match="too few"):
        estimate_offsets(poses, cams, max_offset=25)
    # sync=True on a clip shorter than the declared search: the search shrinks to fit
    cams, poses, _ = _poses([0, 1, 0, -2], frames=12)
    mv = triangulate_poses(poses, cams, sync=True, max_reprojection=None)
    assert mv.meta["offsets"] == [0, 1, 0, -2] and mv.meta["sync"]["max_offset"] == 5


@pytest.mark.skipif(
    importlib.util.find_spec("mediapipe") is None,
    reason="the video extra is not installed (pip install 'visprim[video]')",
)
def test_a_shifted_view_of_the_shared_clip_is_found(shared_data, tmp_path, monkeypatch):
    """The shared clip with cam02's first 3 frames dropped: the estimate moves by exactly 3
    frames for cam02 and by at most one for the others (the clip's own estimate is not 0 everywhere:
    MediaPipe's keypoints disagree between views; see docs/video.rst)."""
    from visprim.io import read_views
    from visprim.io.calibration import read_calibration
    from visprim.io.video_pose import video_poses

    monkeypatch.setenv("VISPRIM_CACHE_DIR", str(tmp_path / "cache"))
    folder = shared_data / "video" / "pose2sim_single_person"
    if not folder.is_dir():
        pytest.skip(f"shared video clip not found at {folder}")
    cams = read_calibration(folder / "Calib.qca.txt")
    poses = [video_poses(folder / f"cam0{i}.mp4", max_frames=60) for i in (1, 2, 3, 4)]
    pairs = SIDE_PAIRS["blazepose33"]
    base, _ = estimate_offsets(poses, cams, max_offset=12, pairs=pairs)
    q = poses[1]
    cut = dataclasses.replace(
        q, times=q.times[3:] - q.times[3], world=q.world[3:], image=q.image[3:],
        confidence=q.confidence[3:], found=q.found[3:],
    )  # fmt: skip
    shifted, _ = estimate_offsets([poses[0], cut, *poses[2:]], cams, max_offset=12, pairs=pairs)
    # cam02 moves by exactly 3; the others may move by one frame: cutting cam02 shortens the
    # window every pair is scored on (57 frames, not 60), and cam03's minimum is shallow
    # (MediaPipe's keypoints disagree between views by more than a frame's motion).
    assert shifted[0] == 0 and shifted[1] == base[1] - 3, (base, shifted)
    assert all(abs(a - b) <= 1 for a, b in zip(shifted[2:], base[2:], strict=True)), (base, shifted)
    views = [folder / f"cam0{i}.mp4" for i in (1, 2, 3, 4)]
    trial = read_views(
        views, folder / "Calib.qca.txt", arm="both", max_frames=60, sync=True, min_duration=0.1
    )  # the poses come from the cache written above
    assert trial.meta["offsets"] == base and trial.meta["sync"]["offsets"] == base


def test_left_right_exchanges_of_the_fk_skeleton_are_put_back():
    """One view mirrored (every left/right pair exchanged) in frames 10-29, another with one
    arm's labels exchanged in frame 40: exactly those are found, and the points come back."""
    cams, poses, truth = _poses([0, 0, 0, 0], frames=50, noise=0.5, seed=4)
    pairs = SIDE_PAIRS["blazepose33"]
    arm = [(11, 12), (13, 14), (15, 16), (17, 18), (19, 20), (21, 22)]
    for view, frames, which in ((3, slice(10, 30), pairs), (1, slice(40, 41), arm)):
        img = poses[view].image
        for a, b in which:
            img[frames, [a, b]] = img[frames, [b, a]]
    mv = triangulate_poses(poses, cams, max_reprojection=None)
    expected = np.zeros((50, 4), dtype=int)
    expected[10:30, 3] = 16
    expected[40, 1] = 6
    np.testing.assert_array_equal(mv.swapped, expected)
    assert np.nanmax(np.linalg.norm(mv.points - truth, axis=-1)) < 0.005
    plain = triangulate_poses(poses, cams, swaps=False, max_reprojection=None)
    assert np.nanmax(np.linalg.norm(plain.points[10:30, 15] - truth[10:30, 15], axis=-1)) > 0.05
