"""Calibrated cameras: the QCA reader, undistortion, weighted DLT (Rust kernel) and
read_views on the shared four-camera clip."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from visprim import _visprim
from visprim.io.calibration import Camera, read_qca
from visprim.io.errors import MalformedFileError
from visprim.io.views import read_views, triangulate_keypoints

QCA_CAMERA = """<camera active="1" serial="{name}">
  <fov_video bottom="1919" left="0" right="1087" top="0"/>
  <transform r11="{m[0][0]}" r12="{m[0][1]}" r13="{m[0][2]}" r21="{m[1][0]}" r22="{m[1][1]}"
    r23="{m[1][2]}" r31="{m[2][0]}" r32="{m[2][1]}" r33="{m[2][2]}" x="{c[0]}" y="{c[1]}"
    z="{c[2]}"/>
  <intrinsic centerPointU="34560" centerPointV="61440" focalLengthU="108800"
    focalLengthV="108800" radialDistortion1="-0.05" radialDistortion2="0.14"
    radialDistortion3="0" tangentalDistortion1="0.0006" tangentalDistortion2="0.0007"/>
</camera>"""


def _look_at(centre: np.ndarray) -> np.ndarray:
    """World → OpenCV camera rotation for a camera at ``centre`` looking at (0, 0, 1)."""
    f = np.array([0.0, 0.0, 1.0]) - centre
    f /= np.linalg.norm(f)
    x = np.cross(f, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    y = np.cross(f, x)
    return np.stack([x, y, f])


def _rig(tmp_path: Path) -> tuple[Path, list[np.ndarray]]:
    centres = [np.array(c) for c in ([3.0, 0.5, 1.6], [-0.5, 3.2, 1.8], [-3.0, -1.0, 2.1])]
    blocks = []
    for i, c in enumerate(centres):
        r = _look_at(c)
        m = np.diag([1.0, -1.0, -1.0]) @ r  # Qualisys axes (see visprim.io.calibration)
        blocks.append(
            QCA_CAMERA.format(name=f"cam{i + 1:02d}", m=m.tolist(), c=(c * 1000).tolist())
        )
    f = tmp_path / "Calib.qca.txt"
    f.write_text(
        "<?xml version='1.0'?>\n<calibration><cameras>"
        + "".join(blocks)
        + "</cameras></calibration>"
    )
    return f, centres


def test_qca_conventions_and_undistortion(tmp_path):
    f, centres = _rig(tmp_path)
    cams = read_qca(f)
    assert [c.name for c in cams] == ["cam01", "cam02", "cam03"]
    for cam, c in zip(cams, centres, strict=True):
        np.testing.assert_allclose(cam.centre, c, atol=1e-12)
        assert cam.size == (1088, 1920)
        np.testing.assert_allclose(cam.K, [[1700, 0, 540], [0, 1700, 960], [0, 0, 1]])
        # The point the camera looks at lands on the principal point, in front of it.
        np.testing.assert_allclose(cam.project(np.array([0.0, 0.0, 1.0])), [540, 960], atol=1e-9)
        assert (cam.R @ [0.0, 0.0, 1.0] + cam.t)[2] > 0
        # Undistortion inverts the lens model across the image.
        pts = np.random.default_rng(0).uniform([-0.3, -0.5, 0.3], [0.3, 0.5, 1.8], (200, 3))
        pix = cam.project(pts)
        cam_pts = pts @ cam.R.T + cam.t
        np.testing.assert_allclose(cam.undistort(pix), cam_pts[:, :2] / cam_pts[:, 2:], atol=1e-9)


def test_weighted_dlt_recovers_points_through_distortion(tmp_path):
    f, _ = _rig(tmp_path)
    cams = read_qca(f)
    rng = np.random.default_rng(1)
    truth = rng.uniform([-0.4, -0.4, 0.5], [0.4, 0.4, 1.7], (30, 5, 3))
    pix = np.stack([c.project(truth) for c in cams], axis=2)  # (30, 5, 3 views, 2)
    conf = np.ones(pix.shape[:3])
    tri = triangulate_keypoints(cams, pix, conf)
    np.testing.assert_allclose(tri.points, truth, atol=1e-7)
    assert np.nanmax(tri.reprojection) < 1e-5 and (tri.views_used == 3).all()
    # A view below min_confidence is left out; one view alone is not enough.
    pix_bad = pix.copy()
    pix_bad[:, :, 0] += 40.0
    conf[:, :, 0] = 0.3
    tri = triangulate_keypoints(cams, pix_bad, conf)
    np.testing.assert_allclose(tri.points, truth, atol=1e-7)
    assert (tri.views_used == 2).all() and np.isnan(tri.reprojection[:, :, 0]).all()
    conf[:, :, 1] = 0.0
    tri = triangulate_keypoints(cams, pix, conf)
    assert np.isnan(tri.points).all() and (tri.views_used == 1).all()


def test_kernel_arguments_are_checked():
    p = np.zeros((2, 3, 4))
    with pytest.raises(ValueError, match=r"points .* do not fit 2 views"):
        _visprim.triangulate_points(p, np.zeros((5, 3, 2)), np.zeros((5, 3)))
    with pytest.raises(TypeError, match="float64"):
        _visprim.triangulate_points(p, np.zeros((5, 2, 2), dtype=np.float32), np.zeros((5, 2)))
    with pytest.raises(ValueError, match="weights must be finite and ≥ 0"):
        _visprim.triangulate_points(p, np.zeros((1, 2, 2)), np.array([[1.0, -1.0]]))


def test_qca_errors_name_the_file(tmp_path):
    f = tmp_path / "c.qca.txt"
    f.write_text(
        "<calibration><cameras><camera serial='a'><transform r11='1'/></camera>"
        "</cameras></calibration>"
    )
    with pytest.raises(MalformedFileError, match=r"c\.qca\.txt: camera a lacks"):
        read_qca(f)
    f.write_text("not xml <")
    with pytest.raises(MalformedFileError, match=r"c\.qca\.txt: not XML"):
        read_qca(f)


@pytest.mark.skipif(
    importlib.util.find_spec("mediapipe") is None,
    reason="the video extra is not installed (pip install 'visprim[video]')",
)
def test_read_views_on_the_shared_clip(shared_data, tmp_path, monkeypatch):
    """Four views, the first 16 frames: a person in every view, a standing subject in the
    lab's frame (+z up, metres), a reprojection error of the order the benchmark measures
    (MediaPipe's 2-D keypoints disagree between views by ~13 px; outliers above 15 px are left
    out; see docs/video.rst), and the same trial from the calibration converted to TOML."""
    monkeypatch.setenv("VISPRIM_CACHE_DIR", str(tmp_path / "cache"))
    folder = shared_data / "video" / "pose2sim_single_person"
    if not folder.is_dir():
        pytest.skip(f"shared video clip not found at {folder}")
    views = [folder / f"cam0{i}.mp4" for i in (1, 2, 3, 4)]
    trial = read_views(views, folder / "Calib.qca.txt", arm="both", max_frames=16, min_duration=0.1)
    assert trial.meta["person_found"] == [1.0] * 4
    assert trial.meta["reprojection_px_median"] < 15.0
    shoulder_z = trial.joints[:, [0, 3], 2]
    assert np.all((shoulder_z > 1.1) & (shoulder_z < 1.7)), shoulder_z
    upper = np.linalg.norm(trial.joints[:, 1] - trial.joints[:, 0], axis=1)
    assert np.all((upper > 0.2) & (upper < 0.4))
    assert isinstance(trial.meta["cameras"], list) and trial.meta["cameras"][0] == "cam01"
    assert all(isinstance(c, Camera) for c in read_qca(folder / "Calib.qca.txt"))
    toml = tmp_path / "Calib.toml"
    lines = []
    for c in read_qca(folder / "Calib.qca.txt"):
        rvec = Rotation.from_matrix(c.R).as_rotvec()
        lines += [
            f"[{c.name}]",
            f"size = {list(c.size)}",
            f"matrix = {c.K.tolist()}",
            f"distortions = {c.dist[:4].tolist()}",
            f"rotation = {rvec.tolist()}",
            f"translation = {c.t.tolist()}",
        ]
    toml.write_text("\n".join(lines) + "\n")
    again = read_views(views, toml, arm="both", max_frames=16, min_duration=0.1)
    np.testing.assert_allclose(again.joints, trial.joints, atol=1e-6)
