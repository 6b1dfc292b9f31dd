"""Keypoints from any estimator → Trial → inverse kinematics, on synthetic keypoints made by
visprim's own forward kinematics."""

from __future__ import annotations

import numpy as np
import pytest
from _keypoint_data import (
    BODY_TO_CAMERA,
    LENGTHS,
    SHOULDER_WIDTH,
    TORSO_HEIGHT,
    arm_angles_truth,
    body_keypoints,
    scale_bones,
    to_blazepose,
)
from visprim.arm import forward_kinematics
from visprim.ik import arm_angles
from visprim.io import GapError, MissingPointError
from visprim.io.keypoints import LAYOUTS, trial_from_keypoints, trial_pieces_from_keypoints

RATE = 60.0
#: Noise of monocular estimators (published single-camera MediaPipe vs marker mocap): image
#: plane 5 mm, depth 50 mm, bone lengths ±14 % from frame to frame.
SIGMA_XY = 0.005
SIGMA_Z = 0.050
BONE_SPREAD = 0.14


def _directions(angles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    pts = forward_kinematics(angles, LENGTHS)
    u = pts[:, 1] - pts[:, 0]
    f = pts[:, 2] - pts[:, 1]
    return (
        u / np.linalg.norm(u, axis=1, keepdims=True),
        f / np.linalg.norm(f, axis=1, keepdims=True),
        angles[:, 3],
    )


def _rms_angle(a: np.ndarray, b: np.ndarray) -> float:
    cos = np.clip(np.sum(a * b, axis=1), -1.0, 1.0)
    return float(np.sqrt(np.mean(np.arccos(cos) ** 2)))


def _camera_points(n: int, rng: np.random.Generator | None) -> tuple[np.ndarray, ...]:
    right = arm_angles_truth(n, RATE)
    left = arm_angles_truth(n, RATE, phase=1.3)
    kp = body_keypoints(right, left)
    if rng is not None:
        kp = scale_bones(kp, rng, BONE_SPREAD)
    pts = to_blazepose(kp)
    pts = pts - pts[:, [23, 24]].mean(axis=1, keepdims=True)  # hip-centred, as MediaPipe
    cam = pts @ BODY_TO_CAMERA.T
    if rng is not None:
        cam = cam + rng.normal(size=cam.shape) * np.array([SIGMA_XY, SIGMA_XY, SIGMA_Z])
    return cam, right, left


def test_noiseless_keypoints_give_the_exact_angles():
    cam, right, left = _camera_points(200, None)
    trial = trial_from_keypoints(cam, "blazepose33", rate=RATE, up_axis="-y", arm="both")
    assert trial.arms == ("right", "left")
    ik = arm_angles(trial)
    # Two-arm IK returns (T, 8): right then left (mirrored to the right arm's convention).
    np.testing.assert_allclose(ik[:, :4], right, atol=1e-9)
    np.testing.assert_allclose(ik[:, 4:], left, atol=1e-9)
    # The subject faced the camera (−z); the trial is turned to face +x.
    assert trial.body_frame is not None
    np.testing.assert_allclose(trial.body_frame[0], np.eye(3), atol=1e-9)
    # The hand (finger sensor) is the centroid of the estimator's index/pinky points.
    assert trial.meta["finger_from"] == "the estimator's hand point(s)"


def test_ik_on_noisy_keypoints_stays_within_the_derived_bound():
    """Noise of a monocular estimator: σ_xy = 5 mm in the image plane, σ_z = 50 mm in depth,
    independent per keypoint and frame; each bone's length × U(0.86, 1.14) per frame.

    Derivation (small angles). A segment of length L between two noisy points: the noise of
    their difference has covariance 2Σ, Σ = diag(σ_xy², σ_xy², σ_z²); only its part
    perpendicular to the segment turns it, so the mean squared direction error is
    2 (tr Σ − dᵀΣd) / L² ≤ 2 (σ_xy² + σ_z²) / L², worst when the segment lies in the image
    plane. Bone scaling changes lengths, not directions, so L ≥ 0.86 × the bone. The torso
    frame (z: mid-hip → mid-shoulder, height H; y: right side → left side, each side the mean
    of a shoulder and a hip, width W) adds a rotation error with, per axis, the variance of a
    difference of two 2-point means (σ² per axis): yaw σ_z / W (subject facing the camera:
    the forward axis is the depth axis), pitch σ_z / H, roll σ_xy / H. A torso rotation δφ
    moves a direction by |δφ × d| ≤ |δφ|. So the RMS direction error of a bone is at most

        E = sqrt(2 (σ_xy² + σ_z²) / L_min² + σ_z² / W² + σ_z² / H² + σ_xy² / H²),

    18.6° for the upper arm and 20.7° for the forearm here. Elbow flexion θ = angle(u, f) does
    not see the torso; its error is at most the root sum of the two segment terms.
    Small-angle error at 0.3 rad is below 2 %; the test allows 10 % over E for the finite
    sample (2 × 3000 frames).
    """
    rng = np.random.default_rng(7)
    n = 3000
    cam, right, left = _camera_points(n, rng)
    trial = trial_from_keypoints(cam, "blazepose33", rate=RATE, up_axis="-y", arm="both")
    ik = arm_angles(trial)
    seg = {
        name: 2 * (SIGMA_XY**2 + SIGMA_Z**2) / ((1 - BONE_SPREAD) * length) ** 2
        for name, length in (("upper", LENGTHS.upper_arm), ("fore", LENGTHS.forearm))
    }
    torso = (
        SIGMA_Z**2 / SHOULDER_WIDTH**2
        + SIGMA_Z**2 / TORSO_HEIGHT**2
        + SIGMA_XY**2 / TORSO_HEIGHT**2
    )
    bound_u = np.sqrt(seg["upper"] + torso)
    bound_f = np.sqrt(seg["fore"] + torso)
    bound_theta = np.sqrt(seg["upper"] + seg["fore"])
    assert np.rad2deg(bound_u) == pytest.approx(18.6, abs=0.1)
    for truth, est in ((right, ik[:, :4]), (left, ik[:, 4:])):
        u0, f0, th0 = _directions(truth)
        u1, f1, th1 = _directions(est)
        assert _rms_angle(u0, u1) <= 1.1 * bound_u
        assert _rms_angle(f0, f1) <= 1.1 * bound_f
        assert np.sqrt(np.mean((th1 - th0) ** 2)) <= 1.1 * bound_theta
        # And the bound is not vacuous: the error is of the noise's order, not ~0 nor ~90°.
        assert _rms_angle(u0, u1) > 0.3 * bound_u


def test_low_confidence_frames_are_gaps_with_the_c3d_policy():
    cam, right, _ = _camera_points(240, None)
    conf = np.ones(cam.shape[:2])
    conf[50:53, 16] = 0.2  # right wrist unsure for 3 frames (0.05 s): filled
    trial = trial_from_keypoints(cam, "blazepose33", rate=RATE, up_axis="-y", confidence=conf)
    assert trial.times.shape == (240,)
    assert trial.meta["gaps"]["filled_frames"] == 3
    np.testing.assert_allclose(arm_angles(trial), right, atol=2e-3)
    conf[100:130, 14] = 0.1  # right elbow lost for 0.5 s > max_gap: split
    pieces = trial_pieces_from_keypoints(
        cam, "blazepose33", rate=RATE, up_axis="-y", confidence=conf, min_duration=0.3
    )
    assert [p.meta["frame_range"] for p in pieces] == [[0, 100], [130, 240]]
    assert [p.name for p in pieces] == ["keypoints_part1", "keypoints_part2"]
    with pytest.raises(GapError, match="right_elbow missing in frames 100–129"):
        trial_from_keypoints(
            cam, "blazepose33", rate=RATE, up_axis="-y", confidence=conf, on_gap="raise"
        )
    # The left arm alone does not see the right elbow's gap.
    left = trial_from_keypoints(
        cam, "blazepose33", rate=RATE, up_axis="-y", confidence=conf, arm="left"
    )
    assert left.times.shape == (240,)


@pytest.mark.parametrize("layout", ["coco17", "h36m17"])
def test_layouts_without_hands_extrapolate_the_hand(layout):
    cam, right, _ = _camera_points(120, None)
    blaze = {r: ks[0] if isinstance(ks, tuple) else ks for r, ks in LAYOUTS["blazepose33"].items()}
    pts = np.zeros((120, 17, 3))
    for role, k in LAYOUTS[layout].items():
        pts[:, k] = cam[:, blaze[role]]  # type: ignore[index]
    trial = trial_from_keypoints(pts, layout, rate=RATE, up_axis="-y")
    np.testing.assert_allclose(arm_angles(trial), right, atol=1e-9)
    assert trial.meta["finger_from"].startswith("extrapolated along the forearm")
    wrist, elbow = trial.joints[:, 2], trial.joints[:, 1]
    np.testing.assert_allclose(
        np.linalg.norm(trial.markers[:, 3] - wrist, axis=1),
        0.45 * np.linalg.norm(wrist - elbow, axis=1),
    )


def test_name_mapping_and_errors():
    cam, right, _ = _camera_points(60, None)
    blaze = LAYOUTS["blazepose33"]
    named = {
        "RS": cam[:, 12],
        "RE": cam[:, 14],
        "RW": cam[:, 16],
        "RH": cam[:, 24],
        "LS": cam[:, 11],
        "LH": cam[:, 23],
    }
    mapping = {
        "right_shoulder": "RS",
        "right_elbow": "RE",
        "right_wrist": "RW",
        "right_hip": "RH",
        "left_shoulder": "LS",
        "left_hip": "LH",
    }
    trial = trial_from_keypoints(named, mapping, rate=RATE, up_axis="-y")
    np.testing.assert_allclose(arm_angles(trial), right, atol=1e-9)
    assert blaze["right_hand"] == (18, 20)
    with pytest.raises(
        MissingPointError, match="the layout has no left_elbow, left_wrist keypoint"
    ):
        trial_from_keypoints(named, mapping, rate=RATE, arm="both")
    with pytest.raises(ValueError, match="layout 'coco17' has 17 keypoints, the points have 33"):
        trial_from_keypoints(cam, "coco17", rate=RATE)
    with pytest.raises(ValueError, match="no keypoint named 'XX'"):
        trial_from_keypoints(named, {**mapping, "right_wrist": "XX"}, rate=RATE)
    with pytest.raises(ValueError, match="give times= .* or rate="):
        trial_from_keypoints(cam, "blazepose33")
    with pytest.raises(ValueError, match=r"shape \(T, K, 3\)"):
        trial_from_keypoints(cam[:, :, :2], "blazepose33", rate=RATE)
    # Without hips: no torso frame, the recording axes are the body axes.
    no_torso = {k: v for k, v in mapping.items() if "hip" not in k}
    trial = trial_from_keypoints(named, no_torso, rate=RATE, up_axis="-y")
    assert trial.body_frame is None and trial.meta["body_frame_from"] is None
