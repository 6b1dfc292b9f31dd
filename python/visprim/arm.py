"""The arm model and the angle convention shared by the generator, IK and the simulation.

Frames
------
*Body frame* B (see :mod:`visprim.trial`): +x forward, +y left, +z up, metres.

*Shoulder frame* S: origin at the right shoulder's joint centre, axes
``x_S = forward``, ``y_S = right``, ``z_S = down`` (a rotation of B by π about x;
``v_S = BODY_TO_SHOULDER @ v_B``). In S the hanging arm points along +z_S.

Angles (the method's 4 DOF, radians, column order of every (T, 4) angle array)
------------------------------------------------------------------------------
0. ``gamma`` γ — first rotation, about z_S: the azimuth of the plane of elevation
   (0 = forward flexion, +π/2 = sideways abduction of the right arm).
1. ``beta``  β — second rotation, about the new y: the elevation of the upper arm away from
   hanging down (0 = hanging, π/2 = horizontal). β ≈ 0 is the Z-Y-Z singularity.
2. ``alpha`` α — third rotation, about the upper arm's own axis: humeral rotation.
3. ``elbow`` θ — elbow flexion (0 = straight arm), about the upper arm's local y axis, so
   that at α = 0 the forearm flexes towards the local +x.

The shoulder rotation is ``R = Rz(γ) @ Ry(β) @ Rz(α)`` (in S). The upper arm points along
``R @ e_z`` and the forearm along ``R @ (sin θ, 0, cos θ)``; the hand continues the forearm
(no wrist DOF in the method).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

ANGLE_NAMES: tuple[str, ...] = ("gamma", "beta", "alpha", "elbow")
#: Maps body-frame vectors to shoulder-frame vectors (and back: it is its own inverse).
BODY_TO_SHOULDER: NDArray[np.float64] = np.diag([1.0, -1.0, -1.0])
#: Elbow flexion axis in the upper arm's body-aligned rest frame (B axes): flexion about
#: y_S = -y_B brings the forearm forward.
ELBOW_AXIS_BODY: NDArray[np.float64] = np.array([0.0, -1.0, 0.0])


@dataclass(frozen=True)
class ArmLengths:
    """Segment lengths of one arm, metres.

    ``hand_marker`` is the distance from the wrist joint centre to the finger sensor (on the
    middle finger's proximal phalanx), measured along the forearm axis.
    """

    upper_arm: float = 0.30
    forearm: float = 0.26
    hand: float = 0.19
    hand_marker: float = 0.13


def rot_z(angle: ArrayLike) -> NDArray[np.float64]:
    """Rotations about z, shape ``(*angle.shape, 3, 3)``; angle in radians."""
    a = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    rows = [np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)]
    return np.stack(rows, -2)


def rot_y(angle: ArrayLike) -> NDArray[np.float64]:
    """Rotations about y, shape ``(*angle.shape, 3, 3)``; angle in radians."""
    a = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    rows = [np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)]
    return np.stack(rows, -2)


def shoulder_rotation(angles: ArrayLike) -> NDArray[np.float64]:
    """``Rz(γ) Ry(β) Rz(α)`` in the shoulder frame S, shape (T, 3, 3), from (T, ≥3) radians."""
    a = np.asarray(angles, dtype=np.float64)
    return rot_z(a[..., 0]) @ rot_y(a[..., 1]) @ rot_z(a[..., 2])


def shoulder_rotation_body(angles: ArrayLike) -> NDArray[np.float64]:
    """The shoulder rotation expressed in body axes (for a ball joint whose child hangs
    along -z_B at rest): ``M R M`` with ``M = BODY_TO_SHOULDER``. Shape (T, 3, 3)."""
    m = BODY_TO_SHOULDER
    return m @ shoulder_rotation(angles) @ m


def forward_kinematics(angles: ArrayLike, lengths: ArmLengths | None = None) -> NDArray[np.float64]:
    """Joint centres of the arm from its 4 angles.

    Parameters
    ----------
    angles : (T, 4) array, radians
        γ, β, α, elbow as defined in the module docstring.
    lengths : ArmLengths, optional
        Segment lengths in metres (default :class:`ArmLengths`).

    Returns
    -------
    (T, 4, 3) array, metres, in the **body frame** with the shoulder at the origin:
    shoulder, elbow, wrist, and the finger-sensor point on the hand.
    """
    lengths = lengths or ArmLengths()
    a = np.atleast_2d(np.asarray(angles, dtype=np.float64))
    if a.shape[-1] != 4:
        raise ValueError(f"angles must have shape (T, 4), got {a.shape}")
    rot = shoulder_rotation(a)
    upper = rot[..., :, 2]
    theta = a[..., 3]
    fore_local = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], -1)
    fore = np.einsum("...ij,...j->...i", rot, fore_local)
    shoulder = np.zeros_like(upper)
    elbow = lengths.upper_arm * upper
    wrist = elbow + lengths.forearm * fore
    hand = wrist + lengths.hand_marker * fore
    points_s = np.stack([shoulder, elbow, wrist, hand], axis=-2)
    return points_s @ BODY_TO_SHOULDER.T
