"""Robust triangulation on synthetic cameras (injected left/right exchanges and outliers)
and the Pose2Sim/OpenCV TOML calibration reader (against Pose2Sim's QCA → TOML formulas)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _keypoint_data import CAMERA_CENTRES, look_at, ring_cameras
from scipy.spatial.transform import Rotation
from visprim.io.calibration import Camera, read_calibration, read_qca, read_toml, rodrigues
from visprim.io.errors import MalformedFileError
from visprim.io.views import SIDE_PAIRS, _swap_combos, triangulate_keypoints

RX_PI = np.diag([1.0, -1.0, -1.0])


def _cameras() -> list[Camera]:
    k = np.array([[1700.0, 0.0, 540.0], [0.0, 1700.0, 960.0], [0.0, 0.0, 1.0]])
    dist = np.array([-0.01, 0.02, 0.0005, -0.0003, 0.0])
    return ring_cameras(k, dist)


def _scene(t: int = 12, seed: int = 0) -> tuple[list[Camera], np.ndarray, np.ndarray]:
    cams = _cameras()
    truth = np.random.default_rng(seed).uniform([-0.4, -0.4, 0.3], [0.4, 0.4, 1.8], (t, 33, 3))
    pix = np.stack([c.project(truth) for c in cams], axis=2)  # (T, 33, 4, 2)
    return cams, truth, pix


def _exchange(pix: np.ndarray, frames: slice | int, view: int, pairs) -> None:
    for a, b in pairs:
        pix[frames, [a, b], view] = pix[frames, [b, a], view]


def test_hypotheses_are_one_per_complement_pair():
    combos = _swap_combos(4)
    assert combos.shape == (8, 4) and not combos[0].any()
    rows = {tuple(r) for r in combos}
    assert all(tuple(~r) not in rows for r in combos)
    assert list(combos.sum(axis=1)) == sorted(combos.sum(axis=1))


def test_left_right_exchanges_are_found_and_put_back():
    cams, truth, pix = _scene()
    pairs = SIDE_PAIRS["blazepose33"]
    assert len(pairs) == 16 and (11, 12) in pairs and (23, 24) in pairs
    bad = pix.copy()
    _exchange(bad, slice(3, 8), 2, pairs)  # view 3: the whole body, frames 3-7
    _exchange(bad, 10, 1, [(11, 12), (13, 14)])  # view 2: one arm pair each, frame 10
    conf = np.ones(bad.shape[:3])
    plain = triangulate_keypoints(cams, bad, conf, max_reprojection=None)
    assert np.abs(plain.points[3:8, 11] - truth[3:8, 11]).max() > 0.01
    tri = triangulate_keypoints(cams, bad, conf, pairs=pairs, max_reprojection=None)
    np.testing.assert_allclose(tri.points, truth, atol=1e-6)
    expected = np.zeros((12, 4), dtype=int)
    expected[3:8, 2] = 16
    expected[10, 1] = 2
    np.testing.assert_array_equal(tri.swapped, expected)
    assert np.nanmax(tri.reprojection) < 1e-4


def test_an_exchange_in_every_view_cannot_be_seen():
    """All views exchanged: consistent geometry with the labels exchanged (documented)."""
    cams, truth, pix = _scene(t=3)
    pairs = SIDE_PAIRS["blazepose33"]
    for v in range(4):
        _exchange(pix, slice(None), v, pairs)
    tri = triangulate_keypoints(cams, pix, np.ones(pix.shape[:3]), pairs=pairs)
    assert (tri.swapped == 0).all()
    np.testing.assert_allclose(tri.points[:, 11], truth[:, 12], atol=1e-6)


def test_outlier_views_are_left_out():
    cams, truth, pix = _scene(seed=1)
    noisy = pix + np.random.default_rng(2).normal(0.0, 1.0, pix.shape)  # 1 px noise
    noisy[0:5, 5, 0] += [80.0, -30.0]  # one view of one keypoint far off in 5 frames
    conf = np.ones(noisy.shape[:3])
    keep = triangulate_keypoints(cams, noisy, conf, max_reprojection=None)
    tri = triangulate_keypoints(cams, noisy, conf, max_reprojection=15.0)
    err_keep = np.linalg.norm(keep.points[0:5, 5] - truth[0:5, 5], axis=-1)
    err_tri = np.linalg.norm(tri.points[0:5, 5] - truth[0:5, 5], axis=-1)
    # 1 px at ~3 m with f = 1700 px is ~2 mm: 3 good views land within 5 mm.
    assert err_keep.min() > 0.02 and err_tri.max() < 0.005
    expected = np.zeros(noisy.shape[:3], dtype=bool)
    expected[0:5, 5, 0] = True
    np.testing.assert_array_equal(tri.rejected, expected)
    assert (tri.views_used[0:5, 5] == 3).all() and np.isnan(tri.reprojection[0:5, 5, 0]).all()


def test_two_inconsistent_views_give_no_point():
    cams, _, pix = _scene(t=2)
    conf = np.zeros(pix.shape[:3])
    conf[:, :, :2] = 1.0  # two views only
    pix[:, 7, 1] += 100.0
    tri = triangulate_keypoints(cams, pix, conf, max_reprojection=15.0)
    assert np.isnan(tri.points[:, 7]).all() and np.isfinite(tri.points[:, 6]).all()
    with pytest.raises(ValueError, match="max_reprojection"):
        triangulate_keypoints(cams, pix, conf, max_reprojection=0.0)


# ----------------------------------------------------------------------------- TOML

QCA_CAMERA = """<camera active="1" avg-residual="0.4" serial="{name}">
  <fov_video bottom="1919" left="0" right="1087" top="0"/>
  <transform r11="{m[0][0]!r}" r12="{m[0][1]!r}" r13="{m[0][2]!r}" r21="{m[1][0]!r}"
    r22="{m[1][1]!r}" r23="{m[1][2]!r}" r31="{m[2][0]!r}" r32="{m[2][1]!r}" r33="{m[2][2]!r}"
    x="{c[0]!r}" y="{c[1]!r}" z="{c[2]!r}"/>
  <intrinsic centerPointU="34110.3" centerPointV="60680.8" focalLengthU="107599.7"
    focalLengthV="107588.8" radialDistortion1="-0.046" radialDistortion2="0.14"
    radialDistortion3="0" tangentalDistortion1="0.0006" tangentalDistortion2="0.0007"/>
</camera>"""


def _qca(tmp_path: Path) -> Path:
    blocks = []
    for i, c in enumerate(CAMERA_CENTRES):
        m = RX_PI @ look_at(np.array(c))
        blocks.append(
            QCA_CAMERA.format(name=f"cam{i + 1:02d}", m=m.tolist(), c=(np.array(c) * 1000).tolist())
        )
    f = tmp_path / "Calib.qca.txt"
    f.write_text("<calibration><cameras>" + "".join(blocks) + "</cameras></calibration>")
    return f


def _pose2sim_toml(qca: Path, out: Path) -> None:
    """Pose2Sim's QCA → TOML conversion (``read_qca`` + ``calib_qca_fun``), reimplemented from
    its formulas: rotation read by column (transposed), world → camera (r = Rᵀ, t = −r·T),
    rotated by π about x, Rodrigues vector; focal lengths, principal point and distortion ÷ 64."""
    import xml.etree.ElementTree as ET

    lines = []
    for cam in ET.parse(qca).getroot().findall("cameras/camera"):
        tr, it, fov = cam.find("transform"), cam.find("intrinsic"), cam.find("fov_video")
        g = lambda el, k: float(el.get(k))  # noqa: E731
        r = np.array([g(tr, f"r{i}{j}") for i in (1, 2, 3) for j in (1, 2, 3)]).reshape(3, 3).T
        t = np.array([g(tr, k) for k in "xyz"]) / 1000
        r, t = r.T, -(r.T) @ t
        r, t = RX_PI @ r, RX_PI @ t
        rvec = Rotation.from_matrix(r).as_rotvec()
        w = g(fov, "right") - g(fov, "left") + 1
        h = g(fov, "bottom") - g(fov, "top") + 1
        fu, fv = g(it, "focalLengthU") / 64, g(it, "focalLengthV") / 64
        cu = g(it, "centerPointU") / 64 - g(fov, "left")
        cv = g(it, "centerPointV") / 64 - g(fov, "top")
        d = [g(it, k) / 64 for k in ("radialDistortion1", "radialDistortion2")]
        d += [g(it, k) / 64 for k in ("tangentalDistortion1", "tangentalDistortion2")]
        lines += [
            f"[{cam.get('serial')}]",
            f'name = "{cam.get("serial")}"',
            f"size = [ {w}, {h},]",
            f"matrix = [ [ {fu!r}, 0.0, {cu!r},], [ 0.0, {fv!r}, {cv!r},], [ 0.0, 0.0, 1.0,],]",
            f"distortions = [ {', '.join(repr(x) for x in d)},]",
            f"rotation = [ {', '.join(repr(float(x)) for x in rvec)},]",
            f"translation = [ {', '.join(repr(float(x)) for x in t)},]",
            "fisheye = false",
            "",
        ]
    lines += ["[metadata]", "adjusted = false", "error = 0.0", ""]
    out.write_text("\n".join(lines))


def test_toml_reader_matches_pose2sims_conversion_of_the_qca(tmp_path):
    qca = _qca(tmp_path)
    toml = tmp_path / "Calib.toml"
    _pose2sim_toml(qca, toml)
    from_qca, from_toml = read_qca(qca), read_calibration(toml)
    assert [c.name for c in from_toml] == ["cam01", "cam02", "cam03", "cam04"]
    pts = np.random.default_rng(3).uniform([-0.5, -0.5, 0.2], [0.5, 0.5, 1.9], (300, 3))
    for a, b in zip(from_qca, from_toml, strict=True):
        assert a.size == b.size == (1088, 1920)
        np.testing.assert_allclose(b.project(pts), a.project(pts), atol=1e-6)
        np.testing.assert_allclose(b.centre, a.centre, atol=1e-9)
        np.testing.assert_allclose(a.dist[:4], [-0.046 / 64, 0.14 / 64, 0.0006 / 64, 0.0007 / 64])


def test_projection_agrees_with_opencv(tmp_path):
    cv2 = pytest.importorskip("cv2")
    toml = tmp_path / "Calib.toml"
    _pose2sim_toml(_qca(tmp_path), toml)
    pts = np.random.default_rng(4).uniform([-0.5, -0.5, 0.2], [0.5, 0.5, 1.9], (100, 3))
    import tomllib

    data = tomllib.loads(toml.read_text())
    for cam in read_toml(toml):
        d = data[cam.name]
        ref, _ = cv2.projectPoints(
            pts,
            np.array(d["rotation"]),
            np.array(d["translation"]),
            np.array(d["matrix"]),
            np.array(d["distortions"]),
        )
        np.testing.assert_allclose(cam.project(pts), ref[:, 0], atol=1e-6)
        np.testing.assert_allclose(rodrigues(np.array(d["rotation"])), cam.R, atol=1e-12)


def test_toml_errors_name_the_file(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text('[cam01]\nname = "cam01"\nmatrix = [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1]]\n')
    with pytest.raises(MalformedFileError, match=r"bad\.toml: camera cam01 has no size"):
        read_toml(f)
    f.write_text("[metadata]\nerror = 0.0\n")
    with pytest.raises(MalformedFileError, match=r"bad\.toml: no camera tables"):
        read_toml(f)
    f.write_text("[cam01\n")
    with pytest.raises(MalformedFileError, match=r"bad\.toml: not TOML"):
        read_toml(f)
    good = tmp_path / "g.toml"
    _pose2sim_toml(_qca(tmp_path), good)
    f.write_text(good.read_text().replace("fisheye = false", "fisheye = true", 1))
    with pytest.raises(MalformedFileError, match="fisheye"):
        read_toml(f)


# ----------------------------------------------------------------------------- smoothing


def test_keypoint_lowpass_keeps_slow_motion_and_removes_jitter():
    from visprim.io.keypoints import smooth_keypoints, trial_pieces_from_keypoints

    t = np.arange(240) / 60.0
    slow = np.sin(2 * np.pi * 0.5 * t)
    fast = 0.1 * np.sin(2 * np.pi * 20.0 * t)  # 20 Hz, far above a 4 Hz cutoff
    out = smooth_keypoints(t, (slow + fast)[:, None, None], 4.0)[:, 0, 0]
    mid = slice(30, -30)
    # 4th-order Butterworth forward-backward: gain (1 + (f/fc)^8)^-1 ≈ 2.6e-6 at 20 Hz.
    assert np.abs(out - slow)[mid].max() < 0.01
    with pytest.raises(ValueError, match=r"lowpass_hz=40.0 must be in \(0, 30\) Hz"):
        smooth_keypoints(t, slow[:, None], 40.0)
    _, truth, _ = _scene(t=240, seed=5)
    truth = truth[:1].repeat(240, axis=0) + slow[:, None, None] * 0.05
    (tr,) = trial_pieces_from_keypoints(truth, "blazepose33", times=t, lowpass_hz=4.0)
    assert tr.meta["lowpass_hz"] == 4.0


def test_many_views_try_single_view_exchanges():
    combos = _swap_combos(10)
    assert combos.shape == (11, 10) and (combos.sum(axis=1) == [0] + [1] * 10).all()
