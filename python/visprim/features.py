"""What a segment vector is made of: the paper's Euler angles or singularity-free directions.

The method resamples some per-frame description of the arm into segment vectors, and SEG-2
thresholds the summed squared velocity of that same description. Two descriptions exist:

``"zyz"`` — the paper's
    The four angles of :mod:`visprim.arm` per arm: shoulder Z-Y-Z Euler angles (γ, β, α)
    and elbow flexion, radians. With the arm hanging (β ≈ 0) γ and α are not defined
    separately: inverse kinematics keeps them continuous, but they swing in opposite
    directions while the arm barely moves, which inflates SEG-2's speed and the
    reconstruction errors of segments that pass there.

``"directions"`` — singularity-free
    The unit vectors of the upper arm ``u`` and of the forearm ``f`` in the shoulder frame,
    6 channels per arm. A unit vector moving by a small angle δ moves by δ, so the channels
    are in radians of direction and ``Σ channel velocity²`` is ``|u̇|² + |ḟ|²``, the squared
    angular speeds of the two bones in (rad/s)²: finite everywhere, and zero when the arm
    does not move whatever its posture. Humeral rotation is seen through the forearm when
    the elbow is bent, and not at all when it is straight, where it changes nothing visible.
    Angles are recovered with inverse kinematics (:func:`to_angles`).

Several arms are stacked channel-wise, arm by arm (``n_arms`` blocks of 4 or 6 channels).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import params
from visprim.arm import ANGLE_NAMES, BODY_TO_SHOULDER, shoulder_rotation

Features = Literal["zyz", "directions"]
FEATURES = params.FEATURES

_PER_ARM = {"zyz": 4, "directions": 6}
_DIRECTION_NAMES = ("upper_x", "upper_y", "upper_z", "fore_x", "fore_y", "fore_z")

__all__ = [
    "FEATURES",
    "channel_names",
    "check_features",
    "direction_rms_deg",
    "from_angles",
    "n_channels",
    "periodic_channels",
    "to_angles",
]


def check_features(features: str) -> str:
    """``features`` if it names a description (:data:`FEATURES`), else a ValueError."""
    if features not in _PER_ARM:
        raise ValueError(f"features must be one of {list(FEATURES)}, got {features!r}")
    return features


def n_channels(features: str, n_arms: int = 1) -> int:
    """Channels per frame: 4 (``"zyz"``) or 6 (``"directions"``) per arm."""
    return _PER_ARM[check_features(features)] * int(n_arms)


def periodic_channels(features: str, n_arms: int = 1) -> tuple[int, ...]:
    """Channels that are angles about an unbounded axis (γ and α of each arm for
    ``"zyz"``, none for ``"directions"``); segment vectors shift them by whole turns."""
    if check_features(features) == "directions":
        return ()
    return tuple(4 * a + c for a in range(int(n_arms)) for c in (0, 2))


def channel_names(features: str, arms: tuple[str, ...] = ("right",)) -> list[str]:
    """Channel names, prefixed by the arm when there is more than one."""
    names = ANGLE_NAMES if check_features(features) == "zyz" else _DIRECTION_NAMES
    if len(arms) == 1:
        return list(names)
    return [f"{arm}_{n}" for arm in arms for n in names]


def from_angles(angles: ArrayLike, features: str) -> NDArray[np.float64]:
    """Per-frame channels ``(T, C)`` from arm angles ``(T, 4 n_arms)`` radians."""
    a = np.asarray(angles, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] % 4:
        raise ValueError(f"angles must have shape (T, 4 * n_arms), got {a.shape}")
    if check_features(features) == "zyz":
        return np.ascontiguousarray(a)
    blocks = []
    for arm in range(a.shape[1] // 4):
        q = a[:, 4 * arm : 4 * arm + 4]
        rot = shoulder_rotation(q)
        theta = q[:, 3]
        fore_local = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], -1)
        blocks += [rot[:, :, 2], np.einsum("tij,tj->ti", rot, fore_local)]
    return np.ascontiguousarray(np.concatenate(blocks, axis=1))


def to_angles(
    values: ArrayLike, features: str, times: ArrayLike | None = None
) -> NDArray[np.float64]:
    """Arm angles ``(T, 4 n_arms)`` radians from per-frame channels ``(T, C)``.

    For ``"directions"`` the two vectors of each arm are normalised and turned into angles
    by inverse kinematics (:mod:`visprim.ik`; ``times`` (T,) seconds, if given, time the
    interpolation of γ and α through the singular postures).
    """
    from visprim.ik import angles_from_directions

    v = np.asarray(values, dtype=np.float64)
    per = _PER_ARM[check_features(features)]
    if v.ndim != 2 or v.shape[1] % per:
        raise ValueError(f"values must have shape (T, {per} * n_arms), got {v.shape}")
    if features == "zyz":
        return np.ascontiguousarray(v)
    flip = np.diag(BODY_TO_SHOULDER)
    out = [
        angles_from_directions(
            v[:, 6 * a : 6 * a + 3] * flip, v[:, 6 * a + 3 : 6 * a + 6] * flip, times
        )
        for a in range(v.shape[1] // 6)
    ]
    return np.ascontiguousarray(np.concatenate(out, axis=1))


def direction_rms_deg(angles: ArrayLike, reference: ArrayLike) -> float:
    """RMS angle in **degrees** between the bone directions (upper arm, forearm) of two
    ``(T, 4 n_arms)`` angle arrays, over every frame and bone: free of the Z-Y-Z
    singularity, where γ and α may differ while the arm does not."""
    a = np.asarray(angles, dtype=np.float64)
    b = np.asarray(reference, dtype=np.float64)
    if a.shape != b.shape or a.ndim != 2 or a.shape[1] % 4:
        raise ValueError(f"angle arrays {a.shape} and {b.shape} must be equal (T, 4 n_arms)")
    u = from_angles(a, "directions").reshape(a.shape[0], -1, 3)
    v = from_angles(b, "directions").reshape(b.shape[0], -1, 3)
    cos = np.clip(np.sum(u * v, axis=2), -1.0, 1.0)
    return float(np.degrees(np.sqrt(np.mean(np.arccos(cos) ** 2))))
