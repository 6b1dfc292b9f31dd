"""Self-calibration: small corrections of each camera's orientation from the keypoints.

A calibration can be slightly off against the videos it is used with (a camera bumped after
the calibration, or a calibration from another session): the views' keypoints then disagree
by a bias that lasts, which no outlier rule removes. :func:`refine_rotations` fits, from the
keypoints themselves, one small rotation per camera (a bundle adjustment with few
parameters, as anipose and EasyMocap do for their extrinsics):

* **Parameters: 3 per camera**, a rotation vector ``ω`` in the camera's own axes (x: tilt,
  y: pan, z: roll) applied about the camera's centre (``R' = exp(ω) R``, ``t' = exp(ω) t``;
  the centre ``−Rᵀt`` and the intrinsics stay as calibrated). A rotation also covers what a
  principal-point shift does (for a narrow field of view, turning the camera by θ moves the
  image by about ``f·θ``, 26 px per degree at f = 1500 px) and the roll, with the
  intrinsics, usually the best-known part of a calibration, left alone. Camera centres are
  not moved: with three or more cameras that are not in a line, fixed centres leave no
  free direction, but some are weakly seen: cameras in a ring all tilting by the same angle
  look almost like the scene moved up or down (and all panning alike, like the scene turned
  about the vertical); such a common part moves the triangulated points as a whole, not the
  directions between them.
* **Cost**: the reprojection error (px) of every confident observation (confidence ≥
  ``min_confidence``; left/right exchanges put back first), the 3-D points re-triangulated
  with the corrected cameras at each step (weighted DLT; the points are not parameters, so
  no per-point unknowns), under a soft-L1 loss of scale :data:`REFINE_LOSS_SCALE_PX`: an
  observation far off (wrong limb, another person) counts about linearly, not squared.
  Plus a Gaussian prior on each rotation component of σ = :data:`REFINE_PRIOR_DEG`, worth one
  observation: it pins the rotation about the baseline that two cameras alone cannot see,
  and otherwise hardly acts.
* **Held-out check** (whether to use the result): the frames are cut into a first and a
  second half; the rotations fitted on each half must, on the *other* half, both lower the
  cost (the same robust cost per observation, the points triangulated from that half's
  observations) and keep more observations as consistent (not left out by the default
  outlier rule of :func:`visprim.io.views.triangulate_keypoints`), in both folds. Only
  then are the rotations fitted on all frames used. They are also refused when a half has
  fewer than :data:`REFINE_MIN_POINTS` points seen by at least three views, or when a
  fitted rotation exceeds :data:`REFINE_MAX_DEG` (that is not a small correction: a wrong
  camera order, a wrong calibration). A refused refinement keeps the calibration unchanged
  and says why (``Refinement.reason``).

What the check cannot see: a view that follows *another person* than the others. A person
offset sideways in one view is, geometrically, that camera turned (the fit turns it, the
others stay; beyond 5° it is refused); but a person offset in depth along one camera's axis
(someone standing behind the subject) can be explained almost as well by every camera
turning by 1–2°, with 3-D points 8–14 cm off (measured on the synthetic ring: 0.3–0.6 m
behind). So ``read_views``' default, ``"auto"``
(:data:`visprim.params.VIEWS_REFINE_CALIBRATION`), does not refine when a view found
several people.

At most :data:`REFINE_MAX_FRAMES` frames, evenly spaced, enter a fit (the cost is then a few
dozen triangulations of ``frames × keypoints`` points each, in the Rust kernel).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.io.calibration import Camera, rodrigues

__all__ = [
    "REFINE_LOSS_SCALE_PX",
    "REFINE_MAX_DEG",
    "REFINE_MAX_FRAMES",
    "REFINE_MIN_POINTS",
    "REFINE_PRIOR_DEG",
    "Refinement",
    "refine_rotations",
    "rotated",
    "robust_cost",
]

#: Scale (px) of the soft-L1 loss: residuals below it count squared, above it about linearly.
#: Of the order of a pose estimator's keypoint error at 1080p (a few px).
REFINE_LOSS_SCALE_PX = 5.0
#: Prior standard deviation (deg) of each component of a camera's correction: a calibration is
#: trusted to about a degree.
REFINE_PRIOR_DEG = 1.0
#: Largest correction (deg, rotation angle of any camera) accepted as a refinement.
REFINE_MAX_DEG = 5.0
#: Fewest points seen by at least three views in each half of the frames.
REFINE_MIN_POINTS = 30
#: Most frames entering one fit (evenly spaced over the clip).
REFINE_MAX_FRAMES = 300
#: Function evaluations of one fit (each is one triangulation of every point).
REFINE_MAX_EVALUATIONS = 200


@dataclass
class Refinement:
    """Result of :func:`refine_rotations`.

    ``cameras``: the corrected cameras when ``applied``, else the input cameras;
    ``rotation_deg`` (V, 3): each camera's fitted rotation vector (deg, in the camera's axes,
    about its centre) on all frames, whether applied or not; ``reason``: why it was or
    was not applied; ``held_out`` the check's costs (mean robust cost per observation, px²):
    per fold, without and with the correction fitted on the other half; ``observations``:
    how many entered the fit on all frames.
    """

    cameras: list[Camera]
    applied: bool
    reason: str
    rotation_deg: NDArray[np.float64]
    held_out: list[dict[str, float]] = field(default_factory=list)
    observations: int = 0

    def record(self) -> dict[str, Any]:
        """A JSON-friendly summary (for ``trial.meta``)."""
        return {
            "applied": self.applied,
            "reason": self.reason,
            "rotation_deg": np.round(self.rotation_deg, 4).tolist(),
            "rotation_angle_deg": np.round(np.linalg.norm(self.rotation_deg, axis=1), 4).tolist(),
            "held_out": self.held_out,
            "observations": self.observations,
        }


def rotated(cameras: Sequence[Camera], omega: NDArray[np.float64]) -> list[Camera]:
    """The cameras turned about their own centres by the rotation vectors ``omega`` (V, 3)
    rad (world → camera ``R' = exp(ω) R``, ``t' = exp(ω) t``)."""
    out = []
    for c, w in zip(cameras, np.asarray(omega, dtype=np.float64), strict=True):
        d = rodrigues(w)
        out.append(dataclasses.replace(c, R=d @ c.R, t=d @ c.t))
    return out


def _soft_l1(r2: NDArray[np.float64], scale: float) -> NDArray[np.float64]:
    """scipy's soft-L1 loss of squared residuals (px²): ``2 s² (√(1 + r²/s²) − 1)``."""
    return 2.0 * scale**2 * (np.sqrt(1.0 + r2 / scale**2) - 1.0)


def _residuals(
    cameras: Sequence[Camera],
    pixels: NDArray[np.float64],
    weights: NDArray[np.float64],
    norm: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Reprojection residuals (N, V, 2) px of observations ``pixels`` (N, V, 2) with DLT
    weights (N, V), the points triangulated by these cameras (0 where not used). ``norm``:
    the observations undistorted (as :meth:`Camera.undistort`; a rotation does not change
    them, so a fit computes them once)."""
    from visprim.io.views import _dlt

    if norm is None:
        norm = _undistorted(cameras, pixels)
    proj = np.ascontiguousarray(np.stack([c.projection for c in cameras]), dtype=np.float64)
    points = _dlt(proj, norm, weights, 2)
    res = np.stack([c.project(points) - pixels[:, i] for i, c in enumerate(cameras)], axis=1)
    return np.where((weights > 0)[..., None] & np.isfinite(res), res, 0.0)


def _undistorted(cameras: Sequence[Camera], pixels: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.stack([c.undistort(pixels[:, i]) for i, c in enumerate(cameras)], axis=1)


def robust_cost(
    cameras: Sequence[Camera],
    pixels: NDArray[np.float64],
    weights: NDArray[np.float64],
    scale: float = REFINE_LOSS_SCALE_PX,
) -> float:
    """Mean soft-L1 cost (px², summed over u and v as the fit does) per used observation of
    points (N, V, 2) with weights (N, V), each point triangulated by these cameras from its
    own observations."""
    res = _residuals(cameras, pixels, weights)
    used = weights > 0
    if not used.any():
        return float("nan")
    return float(_soft_l1(res**2, scale).sum(axis=-1)[used].mean())


def consistent(
    cameras: Sequence[Camera], pixels: NDArray[np.float64], weights: NDArray[np.float64]
) -> int:
    """How many of the observations (N, V, 2) with weights (N, V) the default robust
    triangulation keeps (:func:`visprim.io.views.triangulate_keypoints`, outliers above
    :data:`visprim.params.TRIANGULATION_MAX_REPROJECTION_PX` left out)."""
    from visprim.io.views import triangulate_keypoints

    n, v, _ = pixels.shape
    tri = triangulate_keypoints(
        cameras,
        np.where((weights > 0)[..., None], pixels, np.nan).reshape(n, 1, v, 2),
        weights.reshape(n, 1, v),
        min_confidence=float(np.min(weights[weights > 0])) if (weights > 0).any() else 1.0,
    )
    return int(np.isfinite(tri.reprojection).sum())


def _observations(
    pixels: NDArray[np.float64], confidence: NDArray[np.float64], min_confidence: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points of frames (T, K, V, 2) flattened to (T·K, V, 2) with their weights (T·K, V):
    confident, finite observations of points seen by at least two such views."""
    t, k, v, _ = pixels.shape
    pix = pixels.reshape(t * k, v, 2)
    w = np.where(
        (confidence >= min_confidence) & np.isfinite(pixels).all(axis=-1), confidence, 0.0
    ).reshape(t * k, v)
    keep = (w > 0).sum(axis=1) >= 2
    return np.nan_to_num(pix[keep]), w[keep]


def _fit(
    cameras: Sequence[Camera],
    pix: NDArray[np.float64],
    w: NDArray[np.float64],
    scale: float,
    prior_deg: float,
) -> NDArray[np.float64]:
    """Rotation vectors (V, 3) rad minimising the robust reprojection cost plus the prior.

    The solver runs on one BLAS thread: its products and SVDs are of a tall, 12-column
    Jacobian, and waking OpenBLAS's threads on cores that are busy costs more than the work
    (``benches/bench_refine.py``: the same rotations, bit for bit, several times faster on a
    loaded machine)."""
    from scipy.optimize import least_squares
    from threadpoolctl import threadpool_limits

    v = len(cameras)
    sigma = np.deg2rad(prior_deg)
    used = w > 0
    norm = _undistorted(cameras, pix)

    def resid(x: NDArray[np.float64]) -> NDArray[np.float64]:
        r = _residuals(rotated(cameras, x.reshape(v, 3) * sigma), pix, w, norm)
        # Prior in px: a component of one σ costs as much as one residual of ``scale``.
        return np.concatenate([r[used].ravel(), scale * x])

    with threadpool_limits(limits=1, user_api="blas"):
        sol = least_squares(
            resid,
            np.zeros(3 * v),
            loss="soft_l1",
            f_scale=scale,
            max_nfev=REFINE_MAX_EVALUATIONS,
            x_scale=1.0,
        )
    return np.asarray(sol.x).reshape(v, 3) * sigma


def _even(n: int, most: int) -> NDArray[np.int64]:
    """At most ``most`` indices of ``range(n)``, evenly spaced."""
    if n <= most:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, most).round().astype(np.int64))


def refine_rotations(
    cameras: Sequence[Camera],
    pixels: NDArray[np.float64],
    confidence: NDArray[np.float64],
    *,
    min_confidence: float = 0.5,
    scale: float = REFINE_LOSS_SCALE_PX,
    prior_deg: float = REFINE_PRIOR_DEG,
    max_deg: float = REFINE_MAX_DEG,
    min_points: int = REFINE_MIN_POINTS,
) -> Refinement:
    """Fit one small rotation per camera to keypoints ``pixels`` (T, K, V, 2) px with
    ``confidence`` (T, K, V) (left/right exchanges already put back), check it on held-out
    frames and return the corrected cameras, or the input cameras and the reason (see the
    module docstring)."""
    cams = list(cameras)
    v = len(cams)
    t = pixels.shape[0]
    zero = np.zeros((v, 3))
    if v < 2 or t < 4:
        return Refinement(cams, False, f"too few views ({v}) or frames ({t})", zero)
    halves = (np.arange(t // 2), np.arange(t // 2, t))

    def data(frames: NDArray[np.int64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        sel = frames[_even(frames.size, REFINE_MAX_FRAMES)]
        return _observations(pixels[sel], confidence[sel], min_confidence)

    parts = [data(h) for h in halves]
    few = [int(((w > 0).sum(axis=1) >= 3).sum()) for _, w in parts]
    if min(few) < min_points:
        return Refinement(
            cams,
            False,
            f"too few points seen by 3 or more views in a half of the frames ({few}; "
            f"{min_points} needed)",
            zero,
        )
    pix_all, w_all = data(np.arange(t))
    omega = _fit(cams, pix_all, w_all, scale, prior_deg)
    deg = np.rad2deg(omega)
    n_obs = int((w_all > 0).sum())
    largest = float(np.linalg.norm(deg, axis=1).max())
    if largest > max_deg:
        return Refinement(
            cams,
            False,
            f"a fitted rotation of {largest:.1f}° exceeds {max_deg:g}°: not a small correction "
            "(wrong camera order or calibration?)",
            deg,
            observations=n_obs,
        )
    checks = []
    for fit_on, score_on in ((0, 1), (1, 0)):
        om = _fit(cams, *parts[fit_on], scale, prior_deg)
        moved = rotated(cams, om)
        checks.append(
            {
                "fitted_on_half": fit_on,
                "scored_on_half": score_on,
                "cost_before": round(robust_cost(cams, *parts[score_on], scale), 4),
                "cost_after": round(robust_cost(moved, *parts[score_on], scale), 4),
                "consistent_before": consistent(cams, *parts[score_on]),
                "consistent_after": consistent(moved, *parts[score_on]),
            }
        )
    if not all(
        c["cost_after"] < c["cost_before"] and c["consistent_after"] > c["consistent_before"]
        for c in checks
    ):
        return Refinement(
            cams,
            False,
            "the correction fitted on one half of the frames does not both lower the "
            "reprojection cost and keep more observations as consistent on the other half, in "
            "both folds",
            deg,
            checks,
            n_obs,
        )
    return Refinement(
        rotated(cams, omega),
        True,
        "lowers the held-out reprojection cost and keeps more held-out observations as "
        "consistent, in both folds",
        deg,
        checks,
        n_obs,
    )
