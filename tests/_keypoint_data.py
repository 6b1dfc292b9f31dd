"""Synthetic whole-body keypoints from visprim's own forward kinematics (for the keypoint,
TRC and triangulation tests)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from visprim.arm import ArmLengths, forward_kinematics
from visprim.io.calibration import Camera

#: Body-frame positions (m): shoulders 0.36 m apart, hips 0.20 m apart and 0.5 m lower.
RIGHT_SHOULDER = np.array([0.0, -0.18, 1.45])
LEFT_SHOULDER = np.array([0.0, 0.18, 1.45])
RIGHT_HIP = np.array([0.0, -0.10, 0.95])
LEFT_HIP = np.array([0.0, 0.10, 0.95])
SHOULDER_WIDTH = 0.36
TORSO_HEIGHT = 0.50
LENGTHS = ArmLengths()


def arm_angles_truth(n: int, rate: float, phase: float = 0.0) -> NDArray[np.float64]:
    """(n, 4) smooth angles (radians) away from the Z-Y-Z singularities."""
    t = np.arange(n) / rate
    return np.stack(
        [
            0.6 + 0.5 * np.sin(2 * np.pi * 0.31 * t + phase),
            1.0 + 0.5 * np.sin(2 * np.pi * 0.23 * t + 1.0 + phase),
            0.3 + 0.4 * np.sin(2 * np.pi * 0.17 * t + 2.0 + phase),
            1.0 + 0.6 * np.sin(2 * np.pi * 0.41 * t + 0.5 + phase),
        ],
        axis=1,
    )


def body_keypoints(
    right: NDArray[np.float64], left: NDArray[np.float64]
) -> dict[str, NDArray[np.float64]]:
    """Body-frame (x forward, y left, z up) keypoints of both arms and the torso, (T, 3)
    each, from the two arms' angles (the left arm mirrored, as IK mirrors it back)."""
    r = forward_kinematics(right, LENGTHS) + RIGHT_SHOULDER
    left_fk = forward_kinematics(left, LENGTHS) * np.array([1.0, -1.0, 1.0])
    lf = left_fk + LEFT_SHOULDER
    n = right.shape[0]
    out = {}
    for side, pts in (("right", r), ("left", lf)):
        for k, part in enumerate(("shoulder", "elbow", "wrist", "hand")):
            out[f"{side}_{part}"] = pts[:, k]
    out["right_hip"] = np.tile(RIGHT_HIP, (n, 1))
    out["left_hip"] = np.tile(LEFT_HIP, (n, 1))
    return out


def scale_bones(
    kp: dict[str, NDArray[np.float64]], rng: np.random.Generator, spread: float
) -> dict[str, NDArray[np.float64]]:
    """Each arm segment's length times an independent uniform factor in
    [1 - spread, 1 + spread] per frame (directions kept), distal points carried along."""
    out = dict(kp)
    for side in ("right", "left"):
        chain = [f"{side}_{p}" for p in ("shoulder", "elbow", "wrist", "hand")]
        new = [kp[chain[0]]]
        for a, b in zip(chain[:-1], chain[1:], strict=True):
            f = rng.uniform(1 - spread, 1 + spread, size=(kp[a].shape[0], 1))
            new.append(new[-1] + f * (kp[b] - kp[a]))
        for name, pts in zip(chain, new, strict=True):
            out[name] = pts
    return out


def to_blazepose(kp: dict[str, NDArray[np.float64]]) -> NDArray[np.float64]:
    """(T, 33, 3) in the BlazePose order; the points no role uses are the hips' centre."""
    n = kp["right_hip"].shape[0]
    centre = (kp["right_hip"] + kp["left_hip"]) / 2
    out = np.repeat(centre[:, None], 33, axis=1)
    index = {
        "right_shoulder": [12],
        "right_elbow": [14],
        "right_wrist": [16],
        "right_hand": [18, 20],
        "right_hip": [24],
        "left_shoulder": [11],
        "left_elbow": [13],
        "left_wrist": [15],
        "left_hand": [17, 19],
        "left_hip": [23],
    }
    for role, ks in index.items():
        for k in ks:
            out[:, k] = kp[role]
    assert out.shape == (n, 33, 3)
    return out


#: Body frame (x forward, y left, z up) → MediaPipe-like camera axes (x image right, y image
#: down, z away from the camera) for a subject facing the camera: forward → −z, the
#: subject's left → +x (the image's right), up → −y. A proper rotation.
BODY_TO_CAMERA = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])


#: Centres (m) of four cameras around the origin, for the triangulation tests.
CAMERA_CENTRES = ([3.0, 0.5, 1.6], [-0.5, 3.2, 1.8], [-3.0, -1.0, 2.1], [0.8, -3.1, 1.9])


def look_at(centre: NDArray[np.float64]) -> NDArray[np.float64]:
    """World → OpenCV camera rotation for a camera at ``centre`` looking at (0, 0, 1)."""
    f = np.array([0.0, 0.0, 1.0]) - centre
    f /= np.linalg.norm(f)
    x = np.cross(f, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(f, x), f])


def ring_cameras(
    k: NDArray[np.float64], dist: NDArray[np.float64], size: tuple[int, int] = (1088, 1920)
) -> list[Camera]:
    """Cameras ``cam01`` … ``cam04`` at :data:`CAMERA_CENTRES`, each looking at (0, 0, 1),
    with intrinsics ``k``, distortion ``dist`` and image ``size`` (width, height px)."""
    out = []
    for i, c in enumerate(CAMERA_CENTRES):
        r = look_at(np.array(c))
        out.append(Camera(f"cam{i + 1:02d}", size, k, dist, r, -r @ np.array(c)))
    return out
