"""Rotation helpers shared by the skeleton readers (vectorised over frames)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray


def axis_rotation(axis: str, angle: ArrayLike) -> NDArray[np.float64]:
    """Right-handed rotations about ``axis`` ('x', 'y' or 'z') by ``angle`` radians.

    Returns shape ``(*angle.shape, 3, 3)``.
    """
    a = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((*a.shape, 3, 3))
    i = "xyz".index(axis.lower())
    j, k = (i + 1) % 3, (i + 2) % 3
    out[..., i, i] = 1.0
    out[..., j, j] = c
    out[..., k, k] = c
    out[..., j, k] = -s
    out[..., k, j] = s
    return out


def euler_matrix(axes: Sequence[str], angles: NDArray[np.float64]) -> NDArray[np.float64]:
    """``R = R_axes[0](angles[..., 0]) @ R_axes[1](angles[..., 1]) @ ...`` (radians).

    The first listed rotation is the outermost (BVH channel order; the Acclaim ASF/AMC
    order string read right to left). ``angles`` has shape ``(..., len(axes))``.
    """
    shape = angles.shape[:-1]
    out = np.broadcast_to(np.eye(3), (*shape, 3, 3)).copy()
    for n, axis in enumerate(axes):
        out = out @ axis_rotation(axis, angles[..., n])
    return out


def nearest_rotation(m: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rotation matrix closest (Frobenius) to each 3×3 matrix in ``m`` (SVD)."""
    u, _, vt = np.linalg.svd(m)
    d = np.sign(np.linalg.det(u @ vt))
    u = u.copy()
    u[..., :, 2] *= d[..., None]
    return u @ vt


def frame_from_axes(
    primary: NDArray[np.float64], secondary: NDArray[np.float64], order: str
) -> NDArray[np.float64]:
    """Orthonormal frames (columns x, y, z) from two direction fields (…, 3).

    ``order`` says which body axes the two directions approximate: ``"zx"`` (primary = up,
    secondary = forward), ``"zy"`` (up, left). The primary axis is kept exactly; the
    secondary is made orthogonal to it; the third completes a right-handed frame. Frames
    where the directions are (nearly) parallel or zero come out NaN.
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        p = primary / np.linalg.norm(primary, axis=-1, keepdims=True)
        s = secondary - np.sum(secondary * p, axis=-1, keepdims=True) * p
        norm = np.linalg.norm(s, axis=-1, keepdims=True)
        s = np.where(norm > 1e-9, s / norm, np.nan)
    if order == "zx":
        z, x = p, s
        y = np.cross(z, x)
    elif order == "zy":
        z, y = p, s
        x = np.cross(y, z)
    else:
        raise ValueError(f"order must be 'zx' or 'zy', got {order!r}")
    return np.stack([x, y, z], axis=-1)
