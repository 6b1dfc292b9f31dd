"""Several calibrated cameras → triangulated 3-D keypoints → :class:`visprim.Trial`.

>>> from visprim.io import read_views
>>> trial = read_views(["cam01.mp4", "cam02.mp4", "cam03.mp4", "cam04.mp4"],
...                    calibration="Calib.qca.txt", arm="both")          # doctest: +SKIP

1. Each view's 2-D keypoints (pixels) and confidences come from the pose estimator
   (:mod:`visprim.io.video_pose`; cached per video).
2. Views are matched to the calibration's cameras by name (file stem = camera serial, e.g.
   ``cam01.mp4`` ↔ ``serial="cam01"``) when every stem names a camera, else by order.
3. Keypoints are undistorted to normalised image coordinates (:meth:`Camera.undistort`) and
   triangulated by weighted DLT (the Rust kernel ``triangulate_points``): each view's weight is
   its confidence, views below ``min_confidence`` or without a person are left out, a point
   needs ``min_views`` views. Two robust steps (:func:`triangulate_keypoints`): a view whose
   estimator exchanged left and right (common when the person faces away from it) is put
   back per frame and per left/right pair, by reprojection; then outlier observations
   (reprojection above ``max_reprojection`` px) are left out, worst first. Before that, by
   default, each camera's rotation is refined from the keypoints (self-calibration,
   :mod:`visprim.io.refine`; kept only where it passes a held-out check; not where a view
   found several people; ``refine_calibration=True / False`` always / never).
4. The 3-D keypoints (world frame of the calibration: Qualisys, metres, +z up) become the trial
   as any keypoints do (:func:`visprim.io.keypoints.trial_pieces_from_keypoints`); points seen
   by too few views are gaps (short ones filled, long ones split or refused).

By default the videos are taken as frame-synchronised (frame i of each is the same instant);
``sync=True`` estimates each view's whole-frame offset from the data instead
(:func:`estimate_offsets`: per pair of views, the offset that minimises the epipolar
distance of their keypoints; then the offsets that best agree with all pairs), and
``sync=[0, 2, ...]`` gives known offsets. The trial's times are the first view's clock, over
the frames every view has.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.io.calibration import Camera, read_calibration
from visprim.io.errors import GapError, ReadError
from visprim.io.keypoints import read_error, trial_pieces_from_keypoints
from visprim.io.refine import refine_rotations
from visprim.io.video_pose import PoseEstimator, VideoPoses, video_poses
from visprim.params import (
    TRIANGULATION_MAX_REPROJECTION_PX,
    VIDEO_LOWPASS_HZ,
    VIEWS_REFINE_CALIBRATION,
    VIEWS_SYNC,
    VIEWS_SYNC_MAX_OFFSET_S,
)
from visprim.trial import Trial

__all__ = [
    "SIDE_PAIRS",
    "MultiView",
    "Sync",
    "Triangulation",
    "read_views",
    "read_views_pieces",
    "estimate_offsets",
    "triangulate_keypoints",
    "triangulate_poses",
    "triangulate_views",
]


@dataclass
class MultiView:
    """Triangulated keypoints of several views.

    ``points`` (T, K, 3) metres, world frame (NaN: fewer than ``min_views`` views);
    ``times`` (T,) s; ``reprojection`` (T, K, V) pixel distance between each used observation
    and the reprojected point (NaN where the view was not used); ``views_used`` (T, K);
    ``poses`` per view; ``cameras`` matched to the views; ``swapped`` (T, V) left/right
    pairs exchanged per frame and view; ``rejected`` (T, K, V) outlier observations;
    ``pixels`` (T, K, V, 2) and ``confidence`` (T, K, V) the observations (the views' frames
    matched by the offsets ``meta["offsets"]``; pixels after the left/right check).
    """

    points: NDArray[np.float64]
    times: NDArray[np.float64]
    reprojection: NDArray[np.float64]
    views_used: NDArray[np.int64]
    poses: list[VideoPoses]
    cameras: list[Camera]
    layout: str
    swapped: NDArray[np.int64]
    rejected: NDArray[np.bool_]
    pixels: NDArray[np.float64]
    confidence: NDArray[np.float64]
    meta: dict[str, Any] = field(default_factory=dict)


def match_cameras(paths: Sequence[Path], cameras: Sequence[Camera], where: str) -> list[Camera]:
    """The camera of each view: by file stem = camera name, else by order."""
    by_name = {c.name.lower(): c for c in cameras}
    stems = [p.name.split(".")[0].lower() for p in paths]
    if all(s in by_name for s in stems):
        return [by_name[s] for s in stems]
    if len(paths) != len(cameras):
        raise ReadError(
            where,
            f"{len(paths)} videos but {len(cameras)} cameras, and the file names do not name "
            f"cameras ({', '.join(c.name for c in cameras)})",
        )
    return list(cameras)


#: Left/right keypoint pairs (left index, right index) of each layout: the points a pose
#: estimator can exchange in one view (typically when the person turns away from it).
SIDE_PAIRS: dict[str, tuple[tuple[int, int], ...]] = {
    "blazepose33": tuple((a, a + 3) for a in (1, 2, 3))
    + tuple((a, a + 1) for a in range(7, 33, 2)),
    "coco17": tuple((a, a + 1) for a in range(1, 17, 2)),
    "h36m17": ((4, 1), (5, 2), (6, 3), (11, 14), (12, 15), (13, 16)),
}


@dataclass
class Triangulation:
    """Result of :func:`triangulate_keypoints`.

    ``points`` (T, K, 3) world units of the projections (NaN: not enough consistent views);
    ``reprojection`` (T, K, V) px between each used observation and the reprojected point
    (NaN where the view was not used); ``views_used`` (T, K); ``swapped`` (T, V) number of
    left/right pairs exchanged in each view and frame; ``rejected`` (T, K, V) observations
    left out as outliers (reprojection above ``max_reprojection``); ``pixels`` (T, K, V, 2)
    and ``confidence`` (T, K, V) the observations after the left/right check (what the
    points were triangulated from).
    """

    points: NDArray[np.float64]
    reprojection: NDArray[np.float64]
    views_used: NDArray[np.int64]
    swapped: NDArray[np.int64]
    rejected: NDArray[np.bool_]
    pixels: NDArray[np.float64]
    confidence: NDArray[np.float64]


def _dlt(
    proj: NDArray[np.float64],
    norm: NDArray[np.float64],
    weights: NDArray[np.float64],
    min_views: int,
) -> NDArray[np.float64]:
    """The Rust weighted DLT on (..., V, 2) normalised coordinates → (..., 3)."""
    from visprim import _visprim

    lead, v = norm.shape[:-2], norm.shape[-2]
    flat = _visprim.triangulate_points(
        proj,
        np.ascontiguousarray(norm.reshape(-1, v, 2), dtype=np.float64),
        np.ascontiguousarray(weights.reshape(-1, v), dtype=np.float64),
        min_views=int(min_views),
    )
    return np.asarray(flat).reshape(*lead, 3)


def _reproject(
    cameras: Sequence[Camera], points: NDArray[np.float64], pixels: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Pixel distance (..., V) between ``pixels`` (..., V, 2) and ``points`` (..., 3)
    projected by each camera (NaN where either is missing)."""
    return np.stack(
        [
            np.linalg.norm(c.project(points) - pixels[..., i, :], axis=-1)
            for i, c in enumerate(cameras)
        ],
        axis=-1,
    )


#: Views up to which every exchange hypothesis is tried (2^(V−1) of them).
MAX_EXHAUSTIVE_VIEWS = 8


def _swap_combos(v: int) -> NDArray[np.bool_]:
    """Which views to exchange, one row per hypothesis (C, V), fewest exchanges first. A
    hypothesis and its complement give the same points with the labels exchanged, so only
    one of each is kept: fewer than V/2 exchanges, or exactly V/2 with view 0 kept. Above
    :data:`MAX_EXHAUSTIVE_VIEWS` views, only single-view exchanges are tried."""
    if v > MAX_EXHAUSTIVE_VIEWS:
        return np.vstack([np.zeros((1, v), dtype=bool), np.eye(v, dtype=bool)])
    rows = []
    for code in range(2**v):
        row = [(code >> i) & 1 == 1 for i in range(v)]
        n = sum(row)
        if 2 * n < v or (2 * n == v and not row[0]):
            rows.append(row)
    combos = np.array(rows, dtype=bool)
    return combos[np.argsort(combos.sum(axis=1), kind="stable")]


def resolve_swaps(
    cameras: Sequence[Camera],
    pixels: NDArray[np.float64],
    norm: NDArray[np.float64],
    weights: NDArray[np.float64],
    pairs: Sequence[tuple[int, int]],
    *,
    min_views: int = 2,
    cap: float = 50.0,
) -> NDArray[np.bool_]:
    """Left/right exchanges, per frame, pair and view: (T, P, V) bool.

    For each left/right pair and frame, every hypothesis of :func:`_swap_combos` (which views
    to exchange) is triangulated and scored by the reprojection error of both points over
    the views that see them, each observation's error capped at ``cap`` px (so one outlier
    view does not decide); the lowest score wins, ties going to the fewest exchanges.
    """
    t, _, v, _ = pixels.shape
    if not pairs:
        return np.zeros((t, 0, v), dtype=bool)
    left = np.array([a for a, _ in pairs])
    right = np.array([b for _, b in pairs])
    proj = np.ascontiguousarray(np.stack([c.projection for c in cameras]), dtype=np.float64)
    combos = _swap_combos(v)
    scores = np.empty((combos.shape[0], t, len(pairs)))
    for ci, swap in enumerate(combos):
        # (T, P, 2 sides, V, 2): the observations labelled left / right under this hypothesis.
        lo = np.where(swap[:, None], norm[:, right], norm[:, left])
        ro = np.where(swap[:, None], norm[:, left], norm[:, right])
        lp = np.where(swap[:, None], pixels[:, right], pixels[:, left])
        rp = np.where(swap[:, None], pixels[:, left], pixels[:, right])
        lw = np.where(swap, weights[:, right], weights[:, left])
        rw = np.where(swap, weights[:, left], weights[:, right])
        nrm = np.stack([lo, ro], axis=2)
        pix = np.stack([lp, rp], axis=2)
        w = np.stack([lw, rw], axis=2)
        pts = _dlt(proj, nrm, w, min_views)
        err = np.minimum(np.nan_to_num(_reproject(cameras, pts, pix), nan=cap), cap)
        scores[ci] = np.where(w > 0, err, 0.0).sum(axis=(2, 3))
    best = np.argmin(scores, axis=0)  # first minimum: the fewest exchanges
    return combos[best]


def _apply_swaps(
    a: NDArray[Any], swaps: NDArray[np.bool_], pairs: Sequence[tuple[int, int]]
) -> NDArray[Any]:
    """Exchange the left/right keypoints of ``a`` (T, K, V, ...) where ``swaps`` (T, P, V)."""
    out = a.copy()
    for pi, (left, right) in enumerate(pairs):
        s = swaps[:, pi, :]
        if a.ndim == 4:
            s = s[..., None]
        out[:, left] = np.where(s, a[:, right], a[:, left])
        out[:, right] = np.where(s, a[:, left], a[:, right])
    return out


def triangulate_keypoints(
    cameras: Sequence[Camera],
    pixels: NDArray[np.float64],
    confidence: NDArray[np.float64],
    *,
    min_confidence: float = 0.5,
    min_views: int = 2,
    pairs: Sequence[tuple[int, int]] = (),
    max_reprojection: float | None = TRIANGULATION_MAX_REPROJECTION_PX,
) -> Triangulation:
    """Robust weighted DLT of keypoints seen by calibrated cameras.

    ``pixels`` (T, K, V, 2) distorted pixel coordinates (NaN: not seen), ``confidence``
    (T, K, V) in [0, 1] (the DLT weight; below ``min_confidence`` the view is not used).

    1. Left/right exchanges: with ``pairs`` (e.g. :data:`SIDE_PAIRS` of the layout), each
       view's left and right keypoints are exchanged where that fits the other views better
       (:func:`resolve_swaps`).
    2. Outlier views: while the worst observation of a point reprojects further than
       ``max_reprojection`` px and more than ``min_views`` views remain, that view is left
       out and the point triangulated again; a point still above the bound with
       ``min_views`` views is NaN (no consistent views). ``None`` keeps every view.
    """
    if max_reprojection is not None and not max_reprojection > 0:
        raise ValueError(f"max_reprojection must be > 0 px or None, got {max_reprojection!r}")
    t, k, v, _ = pixels.shape
    norm = np.stack([cameras[i].undistort(pixels[:, :, i]) for i in range(v)], axis=2)
    weights = np.where(
        (confidence >= min_confidence) & np.isfinite(norm).all(axis=-1), confidence, 0.0
    )
    swaps = resolve_swaps(cameras, pixels, norm, weights, pairs, min_views=min_views)
    if pairs:
        pixels = _apply_swaps(pixels, swaps, pairs)
        confidence = _apply_swaps(confidence, swaps, pairs)
        norm = _apply_swaps(norm, swaps, pairs)
        weights = _apply_swaps(weights, swaps, pairs)
    proj = np.ascontiguousarray(np.stack([c.projection for c in cameras]), dtype=np.float64)
    rejected = np.zeros((t, k, v), dtype=bool)
    points = _dlt(proj, norm, weights, min_views)
    if max_reprojection is not None:
        for _ in range(max(v - min_views, 0)):
            err = np.where(weights > 0, _reproject(cameras, points, pixels), -np.inf)
            err = np.nan_to_num(err, nan=np.inf, neginf=-np.inf)
            worst = np.argmax(err, axis=-1)
            bad = (np.take_along_axis(err, worst[..., None], -1)[..., 0] > max_reprojection) & (
                (weights > 0).sum(axis=-1) > min_views
            )
            if not bad.any():
                break
            ti, ki = np.nonzero(bad)
            weights[ti, ki, worst[ti, ki]] = 0.0
            rejected[ti, ki, worst[ti, ki]] = True
            points = _dlt(proj, norm, weights, min_views)
        err = np.where(weights > 0, _reproject(cameras, points, pixels), -np.inf)
        still = np.nan_to_num(err, nan=np.inf).max(axis=-1) > max_reprojection
        points[still] = np.nan
    used = weights > 0
    reproj = _reproject(cameras, points, pixels)
    finite: NDArray[np.bool_] = np.asarray(np.isfinite(points).all(axis=-1))
    reproj = np.where(used & finite[..., None], reproj, np.nan)
    return Triangulation(
        points=points,
        reprojection=reproj,
        views_used=used.sum(axis=-1).astype(np.int64),
        swapped=swaps.sum(axis=1).astype(np.int64),
        rejected=rejected,
        pixels=pixels,
        confidence=confidence,
    )


#: ``sync=`` of :func:`triangulate_poses`: False / None (frame-synchronised), True (estimate
#: the offsets), or each view's known offset in frames.
Sync = bool | None | Sequence[int]


def _common_frames(poses: Sequence[VideoPoses], offsets: Sequence[int]) -> tuple[int, int]:
    """First and one-past-last frame of the first view that every view has once view v's
    frame ``i + offsets[v]`` is matched with the first view's frame i."""
    start = max(0, *(-o for o in offsets))
    stop = min(q.times.shape[0] - o for q, o in zip(poses, offsets, strict=True))
    if stop - start < 2:
        raise ValueError(f"the views share fewer than 2 frames with the offsets {list(offsets)}")
    return start, stop


def _stack_views(
    poses: Sequence[VideoPoses], offsets: Sequence[int], k: int, start: int, stop: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Pixels (T, K, V, 2) and confidences (T, K, V; 0 where no person) of the first view's
    frames ``start:stop``, view v's frames shifted by ``offsets[v]``."""
    spans = [slice(start + o, stop + o) for o in offsets]
    pixels = np.stack([q.image[w, :k] for q, w in zip(poses, spans, strict=True)], axis=2)
    conf = np.stack(
        [
            np.where(q.found[w, None], q.confidence[w, :k], 0.0)
            for q, w in zip(poses, spans, strict=True)
        ],
        axis=2,
    )
    return pixels, conf


def _skew(t: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([[0.0, -t[2], t[1]], [t[2], 0.0, -t[0]], [-t[1], t[0], 0.0]])


def epipolar_distance(
    a: Camera, b: Camera, norm_a: NDArray[np.float64], norm_b: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Symmetric epipolar distance (px) of matched observations (..., 2) in undistorted
    normalised coordinates of cameras ``a`` and ``b``: the mean of each point's distance to
    the other's epipolar line, in its own camera's pixels (mean focal length). NaN where
    either is missing. Zero for a correct calibration and simultaneous, exact observations,
    whatever the 3-D point."""
    rel = b.R @ a.R.T
    e = _skew(b.t - rel @ a.t) @ rel  # x_b^T E x_a = 0
    ha = np.concatenate([norm_a, np.ones(norm_a.shape[:-1] + (1,))], axis=-1)
    hb = np.concatenate([norm_b, np.ones(norm_b.shape[:-1] + (1,))], axis=-1)
    line_b = ha @ e.T  # in b's image
    line_a = hb @ e  # in a's image
    num = np.abs(np.sum(hb * line_b, axis=-1))
    with np.errstate(invalid="ignore", divide="ignore"):
        db = num / np.linalg.norm(line_b[..., :2], axis=-1) * (b.K[0, 0] + b.K[1, 1]) / 2
        da = num / np.linalg.norm(line_a[..., :2], axis=-1) * (a.K[0, 0] + a.K[1, 1]) / 2
    return (da + db) / 2


def _pair_distance(
    a: Camera,
    b: Camera,
    norm_a: NDArray[np.float64],
    norm_b: NDArray[np.float64],
    pairs: Sequence[tuple[int, int]],
) -> NDArray[np.float64]:
    """:func:`epipolar_distance` (T, K) of two views' keypoints (T, K, 2), each left/right
    pair of ``pairs`` taken in the assignment (as labelled, or exchanged) that fits better
    in each frame, so that an estimator's left/right exchange does not count."""
    d = epipolar_distance(a, b, norm_a, norm_b)
    if pairs:
        left = [x for x, _ in pairs]
        right = [y for _, y in pairs]
        crossed_l = epipolar_distance(a, b, norm_a[:, left], norm_b[:, right])
        crossed_r = epipolar_distance(a, b, norm_a[:, right], norm_b[:, left])
        same = d[:, left] + d[:, right]
        swap = (crossed_l + crossed_r) < same
        d[:, left] = np.where(swap, crossed_l, d[:, left])
        d[:, right] = np.where(swap, crossed_r, d[:, right])
    return d


def _score(d: NDArray[np.float64]) -> float:
    """Mean over keypoints of each keypoint's median (over frames) of ``d`` (T, K): robust
    to bad frames, and every keypoint counts (a median over all observations would be
    decided by the keypoints that do not move, which no offset changes)."""
    ok = np.isfinite(d).any(axis=0)
    if not ok.any():
        return float("inf")
    return float(np.mean(np.nanmedian(d[:, ok], axis=0)))


def estimate_offsets(
    poses: Sequence[VideoPoses],
    cameras: Sequence[Camera],
    *,
    max_offset: int,
    min_confidence: float = 0.5,
    pairs: Sequence[tuple[int, int]] = (),
) -> tuple[list[int], dict[str, Any]]:
    """Whole-frame time offsets of the views, from the data: view v's frame ``i + o[v]`` is
    the instant of the first view's frame i (``o[0] = 0``).

    1. Every pair of views (a, b): the offset ``d_ab`` in ``[−max_offset, max_offset]`` of b
       against a that minimises the symmetric epipolar distance
       (:func:`epipolar_distance`, px; per keypoint the median over frames, then the mean
       over keypoints) of their confident keypoints (confidence ≥
       ``min_confidence`` in both; left/right pairs in the better assignment), over the
       first view's frames that every candidate covers, so that all candidates are scored on
       the same instants. Two views at a time: a third view's error cannot pull it, and the
       calibration alone decides (any motion, no 3-D model). Ties go to the smaller offset.
    2. The offsets: least squares ``o_b − o_a ≈ d_ab`` over all pairs with ``o_0 = 0``,
       rounded. With 2 views that is ``d_01``.

    The record reports every pair's offset, its distance there and at 0, and the
    inconsistency: the largest ``|o_b − o_a − d_ab|`` (frames; 0 when the pairs agree, as
    for a true shift of exact keypoints). Motion is what makes offsets visible; on a still
    scene every offset scores alike and 0 is kept. Cost: ``V(V−1)/2 · (2·max_offset + 1)``
    median distances over the clip. Cameras are fitted to their views' frame sizes as in
    :func:`triangulate_poses`.
    """
    v = len(poses)
    cameras = [c.fitted_to(q.size) for c, q in zip(cameras, poses, strict=True)]
    if max_offset < 0:
        raise ValueError(f"max_offset must be >= 0 frames, got {max_offset!r}")
    n = min(q.times.shape[0] for q in poses)
    if n - 2 * max_offset < 2:
        raise ValueError(
            f"sync: {n} frames are too few to search offsets of up to {max_offset} frames"
        )
    k = min(q.image.shape[1] for q in poses)
    norms = [
        np.where(
            (q.found[:n, None] & (q.confidence[:n, :k] >= min_confidence))[..., None],
            c.undistort(q.image[:n, :k]),
            np.nan,
        )
        for q, c in zip(poses, cameras, strict=True)
    ]
    lo, hi = max_offset, n - max_offset
    found: dict[tuple[int, int], tuple[int, float, float]] = {}
    for a in range(v):
        for b in range(a + 1, v):
            res = {}
            for s in range(-max_offset, max_offset + 1):
                d = _pair_distance(
                    cameras[a], cameras[b], norms[a][lo:hi], norms[b][lo + s : hi + s], pairs
                )
                res[s] = _score(d)
            best = min(res, key=lambda s: (res[s], abs(s)))
            found[(a, b)] = (best, res[best], res[0])
    design = np.zeros((len(found), v - 1))
    target = np.zeros(len(found))
    for row, ((a, b), (off, _, _)) in enumerate(found.items()):
        if a > 0:
            design[row, a - 1] = -1.0
        design[row, b - 1] = 1.0
        target[row] = off
    sol = np.linalg.lstsq(design, target, rcond=None)[0] if v > 1 else np.zeros(0)
    offsets = [0] + [int(np.rint(x)) for x in sol]
    worst = max(
        (abs(offsets[b] - offsets[a] - d) for (a, b), (d, _, _) in found.items()), default=0
    )
    record = {
        "offsets": list(offsets),
        "max_offset": int(max_offset),
        "pairs": {
            f"{a}-{b}": {"offset": d, "distance_px": at, "distance_px_at_zero": zero}
            for (a, b), (d, at, zero) in found.items()
        },
        "inconsistency_frames": int(worst),
    }
    return offsets, record


def _offsets(
    sync: Sync, poses: Sequence[VideoPoses], cameras: Sequence[Camera], **options: Any
) -> tuple[list[int], dict[str, Any] | None]:
    """The frame offsets ``sync`` asks for (see :func:`triangulate_poses`)."""
    v = len(poses)
    if sync is None or sync is False:
        return [0] * v, None
    if sync is True:
        rate = float(poses[0].meta.get("rate") or 0.0)
        if not rate > 0:
            raise ValueError("sync=True needs the views' frame rate (meta['rate'])")
        rates = [float(q.meta.get("rate") or 0.0) for q in poses]
        if any(abs(r - rate) > 1e-3 * rate for r in rates):
            raise ValueError(f"sync=True needs one frame rate for every view, got {rates}")
        n = min(q.times.shape[0] for q in poses)
        # A short clip searches what it can: each candidate needs 2 frames every view has.
        reach = min(int(round(VIEWS_SYNC_MAX_OFFSET_S * rate)), max((n - 2) // 2, 0))
        return estimate_offsets(poses, cameras, max_offset=reach, **options)
    offs = [int(o) for o in sync]
    if len(offs) != v or any(isinstance(o, bool) for o in sync):
        raise ValueError(f"sync: one whole-frame offset per view ({v}), got {list(sync)!r}")
    return [o - offs[0] for o in offs], None


def _people(q: VideoPoses) -> int:
    """How many people the estimator found in a view (1 when it does not say)."""
    try:
        return int(q.meta.get("people") or 1)
    except (TypeError, ValueError):
        return 1


def triangulate_poses(
    poses: Sequence[VideoPoses],
    cameras: Sequence[Camera],
    *,
    min_confidence: float = 0.5,
    min_views: int = 2,
    swaps: bool = True,
    max_reprojection: float | None = TRIANGULATION_MAX_REPROJECTION_PX,
    views: Sequence[str] = (),
    sync: Sync = VIEWS_SYNC,
    refine_calibration: bool | str = VIEWS_REFINE_CALIBRATION,
) -> MultiView:
    """Triangulate the poses of the views (one :class:`VideoPoses` per camera, in the
    cameras' order) over the frames every view has; ``swaps`` checks left/right exchanges
    with the layout's :data:`SIDE_PAIRS`.

    ``sync``: False (default :data:`visprim.params.VIEWS_SYNC`) takes frame i of every view
    as the same instant; True estimates each view's whole-frame offset against the first
    view within ±:data:`visprim.params.VIEWS_SYNC_MAX_OFFSET_S` (less in a clip too short
    for it: ``meta["sync"]["max_offset"]`` says how far; :func:`estimate_offsets`);
    a sequence gives the offsets (frames, view v's frame ``i + o[v]`` ↔ the first view's
    frame i; relative to the first). The times are the first view's clock.

    A view whose frame size differs from its camera's calibrated ``size`` uses the camera
    fitted to the frame (:meth:`visprim.io.calibration.Camera.fitted_to`: the calibrated
    image scaled uniformly and centred, letterbox / pillarbox); ``meta["calibrated_sizes"]``
    and ``meta["frame_sizes"]`` record both; the result's ``cameras`` are the fitted ones.

    ``refine_calibration`` (default :data:`visprim.params.VIEWS_REFINE_CALIBRATION`, ``"auto"``):
    first fit one small rotation per camera to the keypoints (self-calibration,
    :func:`visprim.io.refine.refine_rotations`, after the left/right check), used only where
    it passes a held-out check; ``"auto"`` does so unless a view found several people
    (``meta["people"]`` of its poses), True always, False never. ``meta["refine_calibration"]``
    records the rotations, whether they were applied and why; the result's ``cameras`` are
    then the refined ones.
    """
    if len(poses) != len(cameras) or len(poses) < 2:
        raise ValueError(
            f"need one pose series per camera, at least 2; got {len(poses)} / {len(cameras)}"
        )
    layouts = {str(q.meta["layout"]) for q in poses}
    if len(layouts) != 1:
        raise ValueError(f"the views have different keypoint layouts: {sorted(layouts)}")
    layout = layouts.pop()
    calibrated = [tuple(c.size) for c in cameras]
    cameras = [c.fitted_to(q.size) for c, q in zip(cameras, poses, strict=True)]
    k = min(q.image.shape[1] for q in poses)
    pairs = [(a, b) for a, b in SIDE_PAIRS.get(layout, ()) if a < k and b < k] if swaps else []
    offsets, sync_record = _offsets(
        sync, poses, cameras, min_confidence=min_confidence, pairs=pairs
    )
    start, stop = _common_frames(poses, offsets)
    pixels, conf = _stack_views(poses, offsets, k, start, stop)
    n = stop - start
    refined = None
    if refine_calibration == "auto":
        crowded = [c.name for c, q in zip(cameras, poses, strict=True) if _people(q) > 1]
        if crowded:
            refined = {
                "applied": False,
                "reason": (
                    f"auto: several people in view ({', '.join(crowded)}); the views may "
                    "follow different people, which the held-out check cannot tell from a "
                    "calibration error (refine_calibration=True refines anyway)"
                ),
            }
    elif not isinstance(refine_calibration, bool):
        raise ValueError(
            f"refine_calibration must be True, False or 'auto', got {refine_calibration!r}"
        )

    def triangulate(cams: Sequence[Camera], max_px: float | None) -> Triangulation:
        return triangulate_keypoints(
            cams,
            pixels,
            conf,
            min_confidence=min_confidence,
            min_views=min_views,
            pairs=pairs,
            max_reprojection=max_px,
        )

    if refine_calibration is True or (refine_calibration == "auto" and refined is None):
        # The left/right check first, no outlier rule: the fit weighs every observation.
        first = triangulate(cameras, None)
        ref = refine_rotations(
            cameras, first.pixels, first.confidence, min_confidence=min_confidence
        )
        cameras = ref.cameras
        refined = ref.record()
    tri = triangulate(cameras, max_reprojection)
    reproj = tri.reprojection
    meta = {
        "format": "video views",
        "views": list(views),
        "cameras": [c.name for c in cameras],
        "calibrated_sizes": [list(sz) for sz in calibrated],
        "frame_sizes": [list(q.size) for q in poses],
        "frames": n,
        "offsets": list(offsets),
        "sync": sync_record,
        "person_found": [
            float(q.found[start + o : stop + o].mean()) for q, o in zip(poses, offsets, strict=True)
        ],
        "reprojection_px_median": float(np.nanmedian(reproj))
        if np.isfinite(reproj).any()
        else None,
        "min_views": int(min_views),
        "max_reprojection_px": max_reprojection,
        "side_swaps_per_view": [int(x) for x in tri.swapped.sum(axis=0)],
        "rejected_per_view": [int(x) for x in tri.rejected.sum(axis=(0, 1))],
        "refine_calibration": refined,
        "estimator": poses[0].meta.get("estimator"),
        "times_from": poses[0].meta.get("times_from"),
        "rate": poses[0].meta.get("rate"),
    }
    return MultiView(
        points=tri.points,
        times=poses[0].times[start:stop],
        reprojection=reproj,
        views_used=tri.views_used,
        poses=list(poses),
        cameras=list(cameras),
        layout=layout,
        swapped=tri.swapped,
        rejected=tri.rejected,
        pixels=tri.pixels,
        confidence=tri.confidence,
        meta=meta,
    )


def triangulate_views(
    videos: Sequence[str | os.PathLike[str]],
    calibration: str | os.PathLike[str] | Sequence[Camera],
    *,
    estimator: PoseEstimator | None = None,
    min_confidence: float = 0.5,
    min_views: int = 2,
    swaps: bool = True,
    max_reprojection: float | None = TRIANGULATION_MAX_REPROJECTION_PX,
    max_frames: int | None = None,
    cache: bool = True,
    sync: Sync = VIEWS_SYNC,
    refine_calibration: bool | str = VIEWS_REFINE_CALIBRATION,
) -> MultiView:
    """Pose of every view, triangulated (see the module docstring,
    :func:`triangulate_poses` for ``sync`` and ``refine_calibration``, and
    :func:`triangulate_keypoints`)."""
    paths = [Path(v) for v in videos]
    if len(paths) < 2:
        raise ValueError(f"read_views needs at least 2 videos, got {len(paths)}")
    where = str(paths[0].parent / ("{" + ",".join(p.name for p in paths) + "}"))
    if isinstance(calibration, (str, os.PathLike)):
        cams_all = read_calibration(calibration)
    else:
        cams_all = list(calibration)
    cameras = match_cameras(paths, cams_all, where)
    poses = [video_poses(p, estimator, max_frames=max_frames, cache=cache) for p in paths]
    return triangulate_poses(
        poses,
        cameras,
        min_confidence=min_confidence,
        min_views=min_views,
        swaps=swaps,
        max_reprojection=max_reprojection,
        views=[str(p) for p in paths],
        sync=sync,
        refine_calibration=refine_calibration,
    )


def read_views_pieces(
    videos: Sequence[str | os.PathLike[str]],
    calibration: str | os.PathLike[str] | Sequence[Camera],
    arm: str = "right",
    *,
    estimator: PoseEstimator | None = None,
    min_confidence: float = 0.5,
    min_views: int = 2,
    max_frames: int | None = None,
    cache: bool = True,
    mirror: bool = False,
    max_gap: float = 0.2,
    on_gap: str = "split",
    gap_method: str = "cubic",
    min_duration: float = 0.5,
    swaps: bool = True,
    max_reprojection: float | None = TRIANGULATION_MAX_REPROJECTION_PX,
    lowpass_hz: float | None = VIDEO_LOWPASS_HZ,
    sync: Sync = VIEWS_SYNC,
    refine_calibration: bool | str = VIEWS_REFINE_CALIBRATION,
) -> list[Trial]:
    """Trials from several calibrated views (several when long gaps split them).

    ``calibration``: a Qualisys ``.qca.txt`` or Pose2Sim/OpenCV ``.toml`` file, or cameras;
    ``swaps``, ``max_reprojection`` (px): see :func:`triangulate_keypoints`; ``sync``: the
    views' time alignment (default :data:`visprim.params.VIEWS_SYNC`: frame-synchronised;
    True estimates whole-frame offsets; see :func:`triangulate_poses`);
    ``refine_calibration``: fit a small rotation per camera to the keypoints, kept only where
    it passes a held-out check (default :data:`visprim.params.VIEWS_REFINE_CALIBRATION`,
    ``"auto"``: not where a view found several people; see :func:`triangulate_poses`);
    ``lowpass_hz``:
    smoothing of the 3-D keypoints (default :data:`visprim.params.VIDEO_LOWPASS_HZ`); the
    other options as :func:`visprim.io.read_pieces`.
    """
    mv = triangulate_views(
        videos,
        calibration,
        estimator=estimator,
        min_confidence=min_confidence,
        min_views=min_views,
        swaps=swaps,
        max_reprojection=max_reprojection,
        max_frames=max_frames,
        cache=cache,
        sync=sync,
        refine_calibration=refine_calibration,
    )
    first = Path(videos[0])
    try:
        return trial_pieces_from_keypoints(
            mv.points,
            mv.layout,
            times=mv.times,
            arm=arm,
            up_axis="+z",
            mirror=mirror,
            max_gap=max_gap,
            on_gap=on_gap,
            gap_method=gap_method,
            min_duration=min_duration,
            name=first.parent.name or first.stem,
            source=first,
            meta=mv.meta,
            lowpass_hz=lowpass_hz,
        )
    except ReadError:
        raise
    except ValueError as exc:
        raise read_error(first, exc) from None


def read_views(
    videos: Sequence[str | os.PathLike[str]],
    calibration: str | os.PathLike[str] | Sequence[Camera],
    arm: str = "right",
    **options: Any,
) -> Trial:
    """One trial from several calibrated, synchronised videos (options of
    :func:`read_views_pieces`; :class:`GapError` when long gaps split it)."""
    trials = read_views_pieces(videos, calibration, arm, **options)
    if len(trials) > 1:
        raise GapError(
            Path(videos[0]),
            f"long gaps split the views into {len(trials)} pieces; use read_views_pieces() "
            "or on_gap='longest'",
        )
    return trials[0]
