"""Errors between movements (bone directions, joint space) and the keyframe and DCT
baselines."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

# ---------------------------------------------------------------------------- errors


def bone_rms_deg(values: ArrayLike, reference: ArrayLike) -> float:
    """RMS angle in degrees between the bones of two ``(T, 6 n_arms)`` bone-direction
    arrays (upper arm then forearm per arm; rows need not be unit vectors), over every frame
    and bone."""
    a = np.asarray(values, dtype=np.float64).reshape(len(values), -1, 3)  # type: ignore[arg-type]
    b = np.asarray(reference, dtype=np.float64).reshape(a.shape)
    na = np.linalg.norm(a, axis=2)
    nb = np.linalg.norm(b, axis=2)
    cos = np.sum(a * b, axis=2) / np.maximum(na * nb, 1e-12)
    return float(np.degrees(np.sqrt(np.mean(np.arccos(np.clip(cos, -1.0, 1.0)) ** 2))))


def joint_rms_deg(
    angles: NDArray[np.float64],
    reference: NDArray[np.float64],
    reference_rotations: NDArray[np.float64] | None = None,
) -> float:
    """Joint-space RMS, degrees, over the shoulder's geodesic angles and the elbow
    differences of two ``(T, 4)`` one-arm angle arrays (what ``visprim imitate`` reports);
    ``reference_rotations`` (T, 3, 3) are ``shoulder_rotation(reference)`` if known."""
    from visprim.arm import shoulder_rotation

    ra = shoulder_rotation(angles)
    rb = shoulder_rotation(reference) if reference_rotations is None else reference_rotations
    # The rotation between two orientations turns by arccos((tr(Raᵀ Rb) − 1) / 2).
    cos = (np.einsum("tij,tij->t", ra, rb) - 1.0) / 2.0
    shoulder = np.arccos(np.clip(cos, -1.0, 1.0))
    elbow = angles[:, 3] - reference[:, 3]
    return float(np.degrees(np.sqrt(np.mean(np.concatenate([shoulder, elbow]) ** 2))))


# ---------------------------------------------------------------------------- baselines


def keyframe_rebuild(values: ArrayLike, n_keys: int) -> NDArray[np.float64]:
    """Each channel of ``values`` ``(T, C)`` sampled at ``n_keys`` equally spaced instants
    (from the first frame to the last, linear interpolation between frames) and joined
    again by a cubic interpolating spline (not-a-knot; a line for two keys, a parabola
    for three)."""
    from scipy.interpolate import make_interp_spline

    v = np.asarray(values, dtype=np.float64)
    t = np.arange(v.shape[0], dtype=np.float64)
    n = int(np.clip(n_keys, 2, v.shape[0]))
    keys_t = np.linspace(0.0, t[-1], n)
    keys = np.stack([np.interp(keys_t, t, v[:, j]) for j in range(v.shape[1])], axis=1)
    degree = min(3, n - 1) if n != 3 else 2
    return np.asarray(make_interp_spline(keys_t, keys, k=degree, axis=0)(t), dtype=np.float64)


def dct_rebuild(values: ArrayLike, n_coefficients: int) -> NDArray[np.float64]:
    """Each channel of ``values`` ``(T, C)`` rebuilt from its first ``n_coefficients``
    orthonormal DCT-II coefficients (all T give the input back)."""
    from scipy.fft import dct, idct

    v = np.asarray(values, dtype=np.float64)
    c = dct(v, type=2, norm="ortho", axis=0)
    c[int(max(n_coefficients, 1)) :] = 0.0
    return np.asarray(idct(c, type=2, norm="ortho", axis=0), dtype=np.float64)
