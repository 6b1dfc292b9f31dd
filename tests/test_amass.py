"""AMASS reader: synthetic SMPL-H / SMPL-X files of known arm poses, checked against the
arm's forward kinematics (visprim.arm) and inverse kinematics (visprim.ik).

AMASS files may not be redistributed: every file here is built by the test from rotations
chosen so that the arm takes known angles in the torso frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from visprim.arm import forward_kinematics, shoulder_rotation_body
from visprim.ik import arm_angles
from visprim.io import ReadError, read
from visprim.io.amass import JOINTS

# Body axes (columns forward, left, up) in SMPL's canonical axes (x left, y up, z forward).
P = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
# Takes the method's rest arm (hanging along -z, elbow axis -y) to SMPL's (along -y, +z),
# in body axes: a rotation of -90 degrees about x.
Q = Rotation.from_euler("x", -90, degrees=True).as_matrix()


def known_angles(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [
            rng.uniform(-1.0, 2.0, n),  # gamma
            rng.uniform(0.4, 2.4, n),  # beta, away from the Z-Y-Z singularity
            rng.uniform(-1.2, 1.2, n),  # alpha
            rng.uniform(0.3, 2.0, n),  # elbow
        ]
    )


def smpl_pose(angles: np.ndarray, seed: int = 1) -> np.ndarray:
    """(T, 52, 3) axis-angle: random root, spine and collar rotations, and the shoulder and
    elbow rotations that give the right arm ``angles`` in the torso frame."""
    n = angles.shape[0]
    rng = np.random.default_rng(seed)
    pose = np.zeros((n, 52, 3))
    pose[:, 0] = Rotation.random(n, random_state=rng).as_rotvec()
    for j in (3, 6, 9):
        pose[:, j] = rng.normal(scale=0.2, size=(n, 3))
    collar = Rotation.from_rotvec(rng.normal(scale=0.15, size=(n, 3)))
    pose[:, JOINTS["right_collar"]] = collar.as_rotvec()
    upper = shoulder_rotation_body(angles) @ Q.T  # the arm's rotation in body axes
    arm_smpl = P @ upper @ P.T
    shoulder = collar.inv().as_matrix() @ arm_smpl
    pose[:, JOINTS["right_shoulder"]] = Rotation.from_matrix(shoulder).as_rotvec()
    elbow = Rotation.from_euler("z", angles[:, 3:4]).as_matrix()  # flexion about body z
    pose[:, JOINTS["right_elbow"]] = Rotation.from_matrix(P @ elbow @ P.T).as_rotvec()
    pose[:, 40:43] = rng.normal(scale=0.3, size=(n, 3, 3))  # finger joints: ignored
    return pose


def write_smplh(path: Path, pose: np.ndarray, rate: float = 120.0) -> Path:
    n = pose.shape[0]
    np.savez(
        path,
        poses=pose.reshape(n, 156),
        trans=np.random.default_rng(2).normal(size=(n, 3)),
        betas=np.arange(16) * 0.1,
        mocap_framerate=np.array(rate),
        gender=np.array("neutral"),
    )
    return path


def write_smplx(path: Path, pose: np.ndarray, rate: float = 120.0) -> Path:
    n = pose.shape[0]
    np.savez(
        path,
        root_orient=pose[:, 0],
        pose_body=pose[:, 1:22].reshape(n, 63),
        pose_hand=np.zeros((n, 90)),
        trans=np.zeros((n, 3)),
        betas=np.zeros(16),
        mocap_frame_rate=np.array(rate),
    )
    return path


def wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def test_smplh_arm_angles_match_the_known_pose(tmp_path):
    angles = known_angles(40)
    trial = read(write_smplh(tmp_path / "walk_poses.npz", smpl_pose(angles)))
    assert trial.n_frames == 40
    np.testing.assert_allclose(np.diff(trial.times), 1 / 120.0)
    got = arm_angles(trial)
    np.testing.assert_allclose(got[:, [1, 3]], angles[:, [1, 3]], atol=1e-9)
    np.testing.assert_allclose(wrap(got[:, [0, 2]] - angles[:, [0, 2]]), 0.0, atol=1e-9)


def test_joint_directions_match_forward_kinematics(tmp_path):
    angles = known_angles(25, seed=3)
    trial = read(write_smplh(tmp_path / "a_poses.npz", smpl_pose(angles, seed=4)))
    assert trial.joints is not None and trial.body_frame is not None
    # Joint centres in the torso frame, relative to the shoulder.
    rel = trial.joints - trial.joints[:, :1]
    body = np.einsum("tji,tkj->tki", trial.body_frame, rel)
    fk = forward_kinematics(angles)
    for j in (1, 2):  # elbow, wrist: directions of upper arm and forearm
        seg_got = body[:, j] - body[:, j - 1]
        seg_fk = fk[:, j] - fk[:, j - 1]
        np.testing.assert_allclose(
            seg_got / np.linalg.norm(seg_got, axis=1, keepdims=True),
            seg_fk / np.linalg.norm(seg_fk, axis=1, keepdims=True),
            atol=1e-9,
        )
    # The torso frame is a rotation (AMASS is +Z up; the heading is aligned to +x).
    np.testing.assert_allclose(
        trial.body_frame @ np.swapaxes(trial.body_frame, 1, 2),
        np.broadcast_to(np.eye(3), (25, 3, 3)),
        atol=1e-12,
    )
    assert trial.meta["format"] == "amass" and trial.meta["layout"] == "SMPL-H"


def test_smplx_layout_reads_like_smplh(tmp_path):
    pose = smpl_pose(known_angles(30, seed=5), seed=6)
    a = read(write_smplh(tmp_path / "m_poses.npz", pose, rate=60.0))
    b = read(write_smplx(tmp_path / "m_stageii.npz", pose, rate=60.0))
    assert b.meta["layout"] == "SMPL-X"
    np.testing.assert_allclose(arm_angles(a), arm_angles(b), atol=1e-9)
    np.testing.assert_allclose(b.times, a.times)


def test_joint_positions_in_the_file_are_used(tmp_path):
    angles = known_angles(20, seed=7)
    n = angles.shape[0]
    fk = forward_kinematics(angles)  # body frame = SMPL frame rotated; shoulder at origin
    joints = np.zeros((n, 52, 3))
    # Place the file's joints in AMASS world axes (+z up, facing +x: body axes).
    joints[:, JOINTS["right_shoulder"]] = fk[:, 0] + 1.0
    joints[:, JOINTS["right_elbow"]] = fk[:, 1] + 1.0
    joints[:, JOINTS["right_wrist"]] = fk[:, 2] + 1.0
    joints[:, 40] = fk[:, 3] + 1.0
    path = tmp_path / "j_poses.npz"
    # Rotations: the root turns SMPL's axes onto the body axes (facing +x, +z up), so the
    # torso frame is the identity; the arm's rotations are unrelated to the file's joints.
    pose = np.zeros((n, 52, 3))
    pose[:, 0] = Rotation.from_matrix(P.T).as_rotvec()
    pose[:, JOINTS["right_shoulder"]] = [0.3, 0.2, 0.1]
    np.savez(path, poses=pose.reshape(n, 156), mocap_framerate=50.0, joints=joints)
    trial = read(path)
    assert trial.meta["joints_from"] == "file joint positions"
    got = arm_angles(trial)
    np.testing.assert_allclose(got[:, [1, 3]], angles[:, [1, 3]], atol=1e-9)
    np.testing.assert_allclose(wrap(got[:, [0, 2]] - angles[:, [0, 2]]), 0.0, atol=1e-9)


def test_left_arm_is_the_mirror_of_a_right_arm(tmp_path):
    angles = known_angles(15, seed=8)
    pose = smpl_pose(angles, seed=9)
    # Mirror the whole body about SMPL's sagittal plane (x -> -x): axis-angle (x, y, z)
    # becomes (x, -y, -z), and left and right joints swap.
    mirrored = pose * np.array([1.0, -1.0, -1.0])
    for left, right in ((13, 14), (16, 17), (18, 19), (20, 21)):
        mirrored[:, [left, right]] = mirrored[:, [right, left]]
    path = write_smplh(tmp_path / "l_poses.npz", mirrored)
    trial = read(path, arm="left", mirror=True)
    got = arm_angles(trial)
    np.testing.assert_allclose(got[:, [1, 3]], angles[:, [1, 3]], atol=1e-9)
    np.testing.assert_allclose(wrap(got[:, [0, 2]] - angles[:, [0, 2]]), 0.0, atol=1e-9)


@pytest.mark.parametrize(
    ("arrays", "message"),
    [
        ({"betas": np.zeros(16), "gender": np.array("male")}, "body shape"),
        ({"poses": np.zeros((10, 156))}, "frame rate"),
        ({"poses": np.zeros((10, 50)), "mocap_framerate": 60.0}, "poses must be"),
        ({"poses": np.full((10, 156), np.nan), "mocap_framerate": 60.0}, "NaN"),
        ({"poses": np.zeros((1, 156)), "mocap_framerate": 60.0}, "at least 2 frames"),
        ({"something": np.zeros(3)}, "not an AMASS motion"),
        (
            {"poses": np.zeros((10, 156)), "mocap_framerate": 60.0, "trans": np.zeros((9, 3))},
            "trans must be",
        ),
    ],
)
def test_bad_files_raise_one_line_errors_naming_the_file(tmp_path, arrays, message):
    path = tmp_path / "bad.npz"
    np.savez(path, **arrays)
    with pytest.raises(ReadError, match=message) as info:
        read(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_not_an_npz_archive(tmp_path):
    path = tmp_path / "junk.npz"
    path.write_bytes(b"not a zip file at all")
    with pytest.raises(ReadError, match="not a readable .npz"):
        read(path)
