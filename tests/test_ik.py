"""Inverse kinematics (visprim.ik): accuracy against the arm model and generated truth."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from visprim.arm import ArmLengths, forward_kinematics
from visprim.datasets import imitation_experiment
from visprim.ik import arm_angles, arm_angles_corpus, implied_joint_centres
from visprim.trial import Trial

DEG = np.pi / 180


def wrapped(d: np.ndarray) -> np.ndarray:
    """Angle differences with γ and α (columns 0, 2) wrapped to (−π, π]."""
    d = np.array(d, dtype=np.float64)
    d[..., [0, 2]] = (d[..., [0, 2]] + np.pi) % (2 * np.pi) - np.pi
    return d


def markers_from_angles(angles: np.ndarray, lengths: ArmLengths | None = None) -> np.ndarray:
    """Markers exactly on the points IK assumes: mid upper arm, mid forearm, wrist, hand."""
    j = forward_kinematics(angles, lengths)
    return np.stack([(j[:, 0] + j[:, 1]) / 2, (j[:, 1] + j[:, 2]) / 2, j[:, 2], j[:, 3]], axis=1)


def smooth_angles(t: np.ndarray) -> np.ndarray:
    """A wide-ranging continuous trajectory away from the singularities (radians)."""
    return np.stack(
        [
            0.5 + 2.8 * np.sin(0.7 * t),  # γ sweeps past ±π: tests unwrapping
            1.2 + 0.7 * np.sin(1.1 * t),  # β in [0.5, 1.9] rad
            0.4 + 3.5 * np.sin(0.5 * t + 1.0),  # α beyond ±π
            1.3 + 0.9 * np.sin(1.3 * t),  # elbow in [0.4, 2.2] rad
        ],
        axis=1,
    )


@pytest.fixture(scope="module")
def clean_experiment() -> list[Trial]:
    return imitation_experiment(noise=False, skin_offsets=False)


def test_generated_noise_free_accuracy(clean_experiment: list[Trial]) -> None:
    """Target: <= 0.5° RMS against the true angles away from β ≈ 0."""
    est = arm_angles_corpus(clean_experiment)
    diffs, betas = [], []
    for trial, angles in zip(clean_experiment, est, strict=True):
        assert trial.truth is not None
        diffs.append(wrapped(angles - trial.truth.angles))
        betas.append(trial.truth.angles[:, 1])
    d, beta = np.concatenate(diffs), np.concatenate(betas)
    away = beta > 10 * DEG
    assert away.mean() > 0.9  # the check covers (almost) every frame
    rms_deg = np.sqrt(np.mean(d[away] ** 2, axis=0)) / DEG
    assert np.all(rms_deg <= 0.5), rms_deg
    # The geometry is exact here, so the angles are in fact recovered to rounding.
    assert np.abs(d[away]).max() < 1e-8


def test_generated_angles_continuous_and_in_first_turn(clean_experiment: list[Trial]) -> None:
    for angles in arm_angles_corpus(clean_experiment[:40]):
        assert np.all(np.abs(np.diff(angles, axis=0)) < 0.5)  # no 2π jumps at 29 Hz
        assert np.all(np.abs(angles[0, [0, 2]]) <= np.pi)


def test_corpus_equals_per_trial() -> None:
    trials = imitation_experiment(n_subjects=2, n_stimuli=5)
    # Add trials through the singularities and with their own joints / body frame.
    t = np.linspace(0, 4, 150)
    hanging = smooth_angles(t)
    hanging[:, 1] = 0.3 * np.sin(0.9 * t) ** 2
    trials.insert(3, Trial(times=t, markers=markers_from_angles(hanging), name="hanging"))
    straight = smooth_angles(t)
    straight[:, 3] = 0.3 * np.sin(1.2 * t) ** 2
    joints = forward_kinematics(straight)[:, :3]
    trials.append(Trial(times=t, markers=np.ones((t.size, 4, 3)), joints=joints, name="j"))
    trials.append(
        Trial(
            times=t,
            markers=markers_from_angles(straight),
            body_frame=np.tile(np.diag([-1.0, -1.0, 1.0]), (t.size, 1, 1)),
            name="facing back",
        )
    )
    for trial, angles in zip(trials, arm_angles_corpus(trials), strict=True):
        np.testing.assert_allclose(angles, arm_angles(trial), atol=1e-12)


def test_recovers_wrapping_trajectory_and_unwraps() -> None:
    t = np.linspace(0, 12, 600)
    truth = smooth_angles(t)
    est = arm_angles(markers_from_angles(truth), times=t)
    # Continuous (unwrapped) and equal to the truth up to one 2π offset per column.
    offset = np.round((est - truth)[0] / (2 * np.pi)) * 2 * np.pi
    np.testing.assert_allclose(est - offset, truth, atol=1e-9)
    assert np.ptp(est[:, 0]) > 2 * np.pi * 0.8  # γ really travelled past ±π


def test_invariant_to_shoulder_translation_and_uses_body_frame() -> None:
    t = np.linspace(0, 5, 200)
    truth = smooth_angles(t)
    markers = markers_from_angles(truth)
    drift = np.stack([0.3 + 0.01 * np.sin(t), -0.2 + 0.02 * t, 1.4 + 0.005 * np.cos(3 * t)], 1)
    np.testing.assert_allclose(
        arm_angles(markers + drift[:, None, :], times=t), arm_angles(markers, times=t), atol=1e-12
    )
    # A torso turning about z (yaw) and leaning: rotate everything, pass the body frame.
    yaw, lean = 0.8 * np.sin(0.9 * t), 0.2 * np.sin(0.4 * t)
    cz, sz, cy, sy = np.cos(yaw), np.sin(yaw), np.cos(lean), np.sin(lean)
    o, z = np.ones_like(t), np.zeros_like(t)
    rz = np.stack(
        [np.stack([cz, -sz, z], -1), np.stack([sz, cz, z], -1), np.stack([z, z, o], -1)], -2
    )
    ry = np.stack(
        [np.stack([cy, z, sy], -1), np.stack([z, o, z], -1), np.stack([-sy, z, cy], -1)], -2
    )
    frame = rz @ ry  # columns: body axes in the recording frame
    rotated = np.einsum("tij,tkj->tki", frame, markers) + drift[:, None, :]
    est = arm_angles(rotated, body_frame=frame, times=t)
    np.testing.assert_allclose(wrapped(est - truth), 0.0, atol=1e-9)
    trial = Trial(times=t, markers=rotated, body_frame=frame, name="turning")
    np.testing.assert_allclose(arm_angles(trial), est, atol=0)
    # Ignoring the body frame gives different angles (the check above is not vacuous).
    assert np.abs(wrapped(arm_angles(rotated, times=t) - truth)).max() > 0.1


def test_joints_override_markers() -> None:
    t = np.linspace(0, 3, 100)
    truth = smooth_angles(t)
    joints = forward_kinematics(truth)[:, :3] + np.array([0.1, 0.2, 1.3])
    junk = np.random.default_rng(0).normal(size=(t.size, 4, 3))
    trial = Trial(times=t, markers=junk, joints=joints, name="with-joints")
    np.testing.assert_allclose(wrapped(arm_angles(trial) - truth), 0.0, atol=1e-9)
    np.testing.assert_allclose(
        wrapped(arm_angles(junk, joints=joints, times=t) - truth), 0.0, atol=1e-9
    )


def test_implied_joint_centres_invert_marker_placement() -> None:
    truth = smooth_angles(np.linspace(0, 2, 50))
    joints = forward_kinematics(truth)
    np.testing.assert_allclose(
        implied_joint_centres(markers_from_angles(truth)), joints[:, :3], atol=1e-15
    )


def test_singularity_is_crossed_without_jumps() -> None:
    """The upper arm swings through hanging (β = 0): γ is interpolated, α takes the rotation,
    every angle stays continuous and the arm is still rebuilt closely."""
    t = np.linspace(0, 6, 400)
    truth = smooth_angles(t)
    truth[:, 1] = 0.35 * np.sin(0.9 * t) ** 2  # touches β = 0 twice
    markers = markers_from_angles(truth)
    est = arm_angles(markers, times=t)
    assert np.all(np.isfinite(est))
    step = np.abs(np.diff(est, axis=0)).max(axis=0)
    truth_step = np.abs(np.diff(truth, axis=0)).max(axis=0)
    assert np.all(step < 3 * truth_step + 0.02), (step, truth_step)
    rebuilt = forward_kinematics(est)
    # Inside the 5° cone the direction may deviate by up to ~2β (measured: 4.4 mm here).
    assert np.abs(rebuilt - forward_kinematics(truth)).max() < 0.01
    far = truth[:, 1] > 10 * DEG
    np.testing.assert_allclose(rebuilt[far], forward_kinematics(truth)[far], atol=1e-9)


def test_straight_elbow_holds_alpha_continuous() -> None:
    t = np.linspace(0, 4, 300)
    truth = smooth_angles(t)
    truth[:, 3] = 0.3 * np.sin(1.2 * t) ** 2  # elbow straightens twice
    est = arm_angles(markers_from_angles(truth), times=t)
    assert np.abs(np.diff(est[:, 2])).max() < 0.05
    # α is interpolated where it is undefined; positions stay within a few millimetres.
    np.testing.assert_allclose(forward_kinematics(est), forward_kinematics(truth), atol=0.005)


@settings(max_examples=60, deadline=None)
@given(
    gamma=st.floats(-np.pi, np.pi),
    beta=st.floats(0.1, np.pi - 0.1),
    alpha=st.floats(-np.pi, np.pi),
    elbow=st.floats(0.1, np.pi - 0.1),
    upper=st.floats(0.2, 0.4),
    fore=st.floats(0.2, 0.35),
)
def test_property_single_posture_recovered(
    gamma: float, beta: float, alpha: float, elbow: float, upper: float, fore: float
) -> None:
    truth = np.array([[gamma, beta, alpha, elbow]] * 2)
    lengths = ArmLengths(upper_arm=upper, forearm=fore)
    est = arm_angles(markers_from_angles(truth, lengths))
    np.testing.assert_allclose(wrapped(est - truth), 0.0, atol=1e-7)


def test_errors_name_the_problem() -> None:
    with pytest.raises(ValueError, match=r"markers must have shape \(T, 4, 3\)"):
        arm_angles(np.zeros((10, 3, 3)))
    bad = markers_from_angles(smooth_angles(np.linspace(0, 1, 10)))
    bad[3, 1, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        arm_angles(bad)
    still = np.zeros((5, 4, 3))
    with pytest.raises(ValueError, match=r"upper arm .* zero length at frame 0"):
        arm_angles(still)
    good = markers_from_angles(smooth_angles(np.linspace(0, 1, 10)))
    with pytest.raises(ValueError, match=r"body_frame must have shape \(10, 3, 3\)"):
        arm_angles(good, body_frame=np.eye(3))
    with pytest.raises(ValueError, match="singular_angle"):
        arm_angles(good, singular_angle=1.0)
    trial = Trial(times=np.arange(5.0), markers=np.zeros((5, 4, 3)), name="s99_m99")
    with pytest.raises(ValueError, match="s99_m99"):
        arm_angles_corpus([trial])
