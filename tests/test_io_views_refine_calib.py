"""Self-calibration (:mod:`visprim.io.refine`) on the synthetic four-camera ring: a camera
turned by about 1° is put back, a consistent calibration is left (or kept) as it is, and a
correction that is not small, or too few points, falls back to the calibration.

The bound on the recovered rotation: with σ = 2 px of keypoint noise, f = 1700 px and
N = 100 frames × 33 keypoints × 4 views observations, a rotation is determined to about
σ / (f √N) = 2 / (1700 · 115) rad ≈ 0.0006°. The weakest direction (all cameras of the ring
tilting together, almost the scene moving up or down) is seen only through the parallax of
the scene's depth, spread σ_δ ≈ 0.17 m (uniform over 0.6 m) at Z ≈ 3.1 m, so Z / σ_δ ≈ 18
times worse: ≈ 0.01°. The DLT points, the robust loss and the 3 % outliers make the fit
less efficient than that ideal estimator, so the tests allow ten times it, 0.1°: a tenth
of the 1° error put in.
"""

from __future__ import annotations

import numpy as np
import pytest
from _keypoint_data import ring_cameras
from visprim.io.calibration import Camera, rodrigues
from visprim.io.refine import refine_rotations, robust_cost, rotated
from visprim.io.video_pose import VideoPoses
from visprim.io.views import triangulate_keypoints, triangulate_poses

BOUND_DEG = 0.1
NOISE_PX = 2.0
RATE = 60.0


def _cameras() -> list[Camera]:
    k = np.array([[1700.0, 0.0, 540.0], [0.0, 1700.0, 960.0], [0.0, 0.0, 1.0]])
    dist = np.array([-0.01, 0.02, 0.0005, -0.0003, 0.0])
    return ring_cameras(k, dist)


def _observe(
    cams: list[Camera], t: int, seed: int, outliers: float = 0.03
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A person-sized cloud of 33 points per frame (T, 33, 3) seen by ``cams`` with 2 px noise
    and a fraction ``outliers`` of the observations 30–80 px off; pixels (T, 33, V, 2) and
    confidences (T, 33, V)."""
    rng = np.random.default_rng(seed)
    truth = rng.uniform([-0.3, -0.3, 0.2], [0.3, 0.3, 1.8], (t, 33, 3))
    pix = np.stack([c.project(truth) for c in cams], axis=2)
    pix += rng.normal(0.0, NOISE_PX, pix.shape)
    bad = rng.random(pix.shape[:3]) < outliers
    angle = rng.uniform(0, 2 * np.pi, bad.sum())
    pix[bad] += rng.uniform(30, 80, bad.sum())[:, None] * np.stack(
        [np.cos(angle), np.sin(angle)], axis=1
    )
    return truth, pix, rng.uniform(0.6, 1.0, pix.shape[:3])


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.rad2deg(np.arccos(np.clip((np.trace(a @ b.T) - 1) / 2, -1.0, 1.0))))


def test_a_camera_turned_by_one_degree_is_put_back():
    true = _cameras()
    bump = np.deg2rad([0.6, -0.5, 0.6])  # about 1° (0.99°)
    cams = list(true)
    cams[1] = rotated([true[1]], bump[None])[0]
    assert 0.95 < _angle_deg(cams[1].R, true[1].R) < 1.05
    _, pix, conf = _observe(true, 100, seed=0)
    ref = refine_rotations(cams, pix, conf)
    assert ref.applied, ref.reason
    for c, tc in zip(ref.cameras, true, strict=True):
        assert _angle_deg(c.R, tc.R) < BOUND_DEG
        np.testing.assert_allclose(c.centre, tc.centre, atol=1e-9)  # centres not moved
        np.testing.assert_array_equal(c.K, tc.K)
    # The held-out check saw the improvement in both folds.
    assert all(h["cost_after"] < h["cost_before"] for h in ref.held_out)
    # Fresh frames: the refined cameras reproject as the true ones do.
    _, pix2, conf2 = _observe(true, 40, seed=5, outliers=0.0)
    med = {
        name: np.nanmedian(
            triangulate_keypoints(c, pix2, conf2, max_reprojection=None).reprojection
        )
        for name, c in (("true", true), ("bumped", cams), ("refined", ref.cameras))
    }
    assert med["bumped"] > med["true"] + 1.0
    assert med["refined"] < med["true"] + 0.05


def test_a_consistent_calibration_is_not_made_worse():
    true = _cameras()
    _, pix, conf = _observe(true, 100, seed=1)
    ref = refine_rotations(true, pix, conf)
    assert np.linalg.norm(ref.rotation_deg, axis=1).max() < BOUND_DEG
    _, pix2, conf2 = _observe(true, 40, seed=6)
    w2 = np.where(conf2 >= 0.5, conf2, 0.0).reshape(-1, 4)
    before = robust_cost(true, pix2.reshape(-1, 4, 2), w2)
    after = robust_cost(ref.cameras, pix2.reshape(-1, 4, 2), w2)
    assert after <= before * 1.001
    if not ref.applied:
        assert ref.cameras == true and "other half" in ref.reason


def test_a_large_error_or_too_few_points_falls_back():
    true = _cameras()
    _, pix, conf = _observe(true, 60, seed=2)
    wrong = list(true)
    wrong[2] = rotated([true[2]], np.deg2rad([[12.0, 0.0, 0.0]]))[0]
    ref = refine_rotations(wrong, pix, conf)
    assert not ref.applied and ref.cameras == wrong
    assert "not a small correction" in ref.reason or "other half" in ref.reason
    few = conf.copy()
    few[:, :, 1:] = 0.0  # one view only: nothing to fit
    few[:2, :, 1] = 1.0
    ref = refine_rotations(true, pix, few)
    assert not ref.applied and "too few points" in ref.reason and ref.cameras == true


def test_triangulate_poses_refines_and_records():
    true = _cameras()
    cams = list(true)
    cams[3] = rotated([true[3]], np.deg2rad([[-0.5, 0.7, 0.3]]))[0]
    truth, pix, conf = _observe(true, 80, seed=3, outliers=0.0)
    poses = [
        VideoPoses(
            times=np.arange(80) / RATE,
            world=np.zeros_like(truth),
            image=pix[:, :, v],
            confidence=conf[:, :, v],
            found=np.ones(80, dtype=bool),
            size=true[v].size,
            meta={"layout": "blazepose33", "rate": RATE},
        )
        for v in range(4)
    ]
    plain = triangulate_poses(poses, cams, refine_calibration=False)
    assert plain.meta["refine_calibration"] is None
    mv = triangulate_poses(poses, cams, refine_calibration=True)
    rec = mv.meta["refine_calibration"]
    assert rec["applied"] and len(rec["rotation_deg"]) == 4
    assert _angle_deg(mv.cameras[3].R, true[3].R) < BOUND_DEG
    err = {
        name: float(np.nanmedian(np.linalg.norm(m.points - truth, axis=-1)))
        for name, m in (("plain", plain), ("refined", mv))
    }
    assert err["refined"] < err["plain"]


def test_rotated_keeps_the_centre():
    c = _cameras()[0]
    r = rotated([c], np.array([[0.01, -0.02, 0.03]]))[0]
    np.testing.assert_allclose(r.centre, c.centre, atol=1e-12)
    np.testing.assert_allclose(r.R, rodrigues(np.array([0.01, -0.02, 0.03])) @ c.R)


def _poses(pix: np.ndarray, conf: np.ndarray, cams: list[Camera], people: list[int]):
    t = pix.shape[0]
    return [
        VideoPoses(
            times=np.arange(t) / RATE,
            world=np.zeros(pix.shape[:2] + (3,)),
            image=pix[:, :, v],
            confidence=conf[:, :, v],
            found=np.ones(t, dtype=bool),
            size=cams[v].size,
            meta={"layout": "blazepose33", "rate": RATE, "people": people[v]},
        )
        for v in range(len(cams))
    ]


def test_someone_behind_in_one_view_is_not_seen_by_the_check_so_auto_skips_crowded_views():
    """Documented limitation (visprim.io.refine): view 3 follows a person 0.3 m behind the
    subject along x (mostly in depth for that camera). Every camera turning by 1–2° explains
    it nearly as well, so the held-out check passes and the points move by centimetres, while
    the calibration as given, with the outlier rule, has them within a centimetre. Hence
    ``"auto"`` does not refine when a view found several people."""
    true = _cameras()
    rng = np.random.default_rng(0)
    truth = rng.uniform([-0.3, -0.3, 0.2], [0.3, 0.3, 1.8], (100, 33, 3))
    behind = truth + np.array([0.3, 0.0, 0.0])
    pix = np.stack([c.project(behind if v == 2 else truth) for v, c in enumerate(true)], axis=2)
    pix += rng.normal(0.0, NOISE_PX, pix.shape)
    conf = np.ones(pix.shape[:3])
    forced = refine_rotations(true, pix, conf)
    assert forced.applied  # the check cannot see it
    err = {
        name: float(
            np.nanmedian(
                np.linalg.norm(triangulate_keypoints(c, pix, conf).points - truth, axis=-1)
            )
        )
        for name, c in (("as given", true), ("refined", forced.cameras))
    }
    assert err["as given"] < 0.01 and err["refined"] > 0.04, err
    poses = _poses(pix, conf, true, [1, 1, 2, 1])
    auto = triangulate_poses(poses, true)
    rec = auto.meta["refine_calibration"]
    assert not rec["applied"] and "several people" in rec["reason"] and "cam03" in rec["reason"]
    assert auto.cameras == true
    assert triangulate_poses(poses, true, refine_calibration=True).meta["refine_calibration"][
        "applied"
    ]


def test_refine_calibration_values_are_checked():
    true = _cameras()
    _, pix, conf = _observe(true, 8, seed=4)
    with pytest.raises(ValueError, match="refine_calibration"):
        triangulate_poses(_poses(pix, conf, true, [1] * 4), true, refine_calibration="yes")
