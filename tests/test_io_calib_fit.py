"""A video frame of another size than the calibrated image: the calibrated image scaled
uniformly and centred into it (letterbox / pillarbox), as the shared clip's cam01/cam02 are
(1080 × 1920 videos of a 1088 × 1920 calibration, 7 black rows above and below)."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from _keypoint_data import ring_cameras
from visprim.io.calibration import Camera
from visprim.io.video_pose import VideoPoses
from visprim.io.views import triangulate_poses


def _cameras() -> list[Camera]:
    k = np.array([[1681.0, 0.0, 533.0], [0.0, 1681.0, 948.0], [0.0, 0.0, 1.0]])
    dist = np.array([-0.04, 0.13, 0.0006, 0.0007, 0.0])
    return ring_cameras(k, dist)


def _letterbox(pix: np.ndarray) -> np.ndarray:
    """What ffmpeg does to a 1088 × 1920 picture for a 1080 × 1920 frame, written out
    independently of the reader: scale to 1080 × 1906 (the height rounded to an integer),
    pad 7 rows above; pixel centres at integers."""
    sx, sy = 1080 / 1088, 1906 / 1920
    return np.stack([(pix[..., 0] + 0.5) * sx - 0.5, (pix[..., 1] + 0.5) * sy - 0.5 + 7], -1)


def test_fitted_camera_projects_where_the_letterboxed_picture_shows_the_point():
    from visprim.io.calibration import frame_fit

    cam = _cameras()[0]
    pts = np.random.default_rng(0).uniform([-0.5, -0.5, 0.0], [0.5, 0.5, 2.0], (200, 3))
    fitted = cam.fitted_to((1080, 1920))
    assert fitted.size == (1080, 1920)
    # ffmpeg rounds the scaled height to whole pixels: within 0.07 px of the exact fit.
    np.testing.assert_allclose(fitted.project(pts), _letterbox(cam.project(pts)), atol=0.07)
    assert cam.fitted_to((1088, 1920)) is cam
    # Same aspect ratio: a plain scale (half size), no offsets.
    assert frame_fit((1920, 1080), (960, 540)) == (0.5, 0.0, 0.0)
    half = Camera("c", (1920, 1080), cam.K, cam.dist, cam.R, cam.t).fitted_to((960, 540))
    np.testing.assert_allclose(half.project(pts), (cam.project(pts) + 0.5) / 2 - 0.5, atol=1e-9)
    # Pillarbox: a wider frame pads left and right.
    s, ox, oy = frame_fit((1088, 1920), (1200, 1920))
    assert (s, oy) == (1.0, 0.0) and ox == pytest.approx(56.0)
    with pytest.raises(ValueError, match="positive"):
        cam.fitted_to((0, 1920))


def _poses(pix: np.ndarray, size: tuple[int, int]) -> VideoPoses:
    t, k, _ = pix.shape
    return VideoPoses(
        times=np.arange(t) / 60.0,
        world=np.zeros((t, k, 3)),
        image=pix,
        confidence=np.ones((t, k)),
        found=np.ones(t, dtype=bool),
        size=size,
        meta={"layout": "blazepose33", "rate": 60.0},
    )


def test_views_of_another_frame_size_triangulate_through_the_fitted_cameras():
    """Two of four views are letterboxed 1080 × 1920 copies: the triangulation must map the
    calibration into their frames (the points come back, sub-pixel reprojection)."""
    cams = _cameras()
    truth = np.random.default_rng(1).uniform([-0.4, -0.4, 0.3], [0.4, 0.4, 1.8], (8, 33, 3))
    poses = []
    for i, c in enumerate(cams):
        pix = c.project(truth)
        poses.append(_poses(_letterbox(pix), (1080, 1920)) if i < 2 else _poses(pix, (1088, 1920)))
    mv = triangulate_poses(poses, cams, max_reprojection=None)
    assert np.nanmax(mv.reprojection) < 0.1
    np.testing.assert_allclose(mv.points, truth, atol=2e-4)
    assert mv.meta["calibrated_sizes"] == [[1088, 1920]] * 4
    assert mv.meta["frame_sizes"] == [[1080, 1920]] * 2 + [[1088, 1920]] * 2
    assert [c.size for c in mv.cameras] == [(1080, 1920)] * 2 + [(1088, 1920)] * 2


@pytest.mark.skipif(
    importlib.util.find_spec("cv2") is None, reason="the video extra is not installed"
)
def test_the_shared_clips_black_bars_are_the_rules_padding(shared_data):
    """cam01/cam02 (1080 × 1920) carry a 1088 × 1920 calibration: the rule puts the picture
    7.06 px below the top and above the bottom; the videos' black rows say the same (within
    1.5 px: the picture's edge rows are blurred by the scaling and the codec)."""
    import cv2

    folder = shared_data / "video" / "pose2sim_single_person"
    if not folder.is_dir():
        pytest.skip(f"shared video clip not found at {folder}")
    from visprim.io.calibration import frame_fit

    _, _, oy = frame_fit((1088, 1920), (1080, 1920))
    for name in ("cam01", "cam02"):
        cap = cv2.VideoCapture(str(folder / f"{name}.mp4"))
        brightest = None
        for _ in range(10):
            ok, frame = cap.read()
            assert ok
            g = frame.max(axis=2).astype(float)
            brightest = g if brightest is None else np.maximum(brightest, g)
        cap.release()
        assert brightest is not None and brightest.shape == (1920, 1080)
        rows = brightest.mean(axis=1)
        black = rows < 20
        top = int(np.argmin(black))  # first row of picture
        bottom = int(np.argmin(black[::-1]))  # picture-free rows at the bottom
        assert abs(top - oy) <= 1.5 and abs(bottom - oy) <= 1.5, (name, top, bottom, oy)
