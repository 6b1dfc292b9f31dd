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
   needs ``min_views`` views.
4. The 3-D keypoints (world frame of the calibration: Qualisys, metres, +z up) become the trial
   as any keypoints do (:func:`visprim.io.keypoints.trial_pieces_from_keypoints`); points seen
   by too few views are gaps (short ones filled, long ones split or refused).

The videos must be frame-synchronised (frame i of each is the same instant); the trial's
times are the first view's clock, over the frames every view has.
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
from visprim.io.video_pose import PoseEstimator, VideoPoses, video_poses
from visprim.trial import Trial

__all__ = ["MultiView", "read_views", "read_views_pieces", "triangulate_views"]


@dataclass
class MultiView:
    """Triangulated keypoints of several views.

    ``points`` (T, K, 3) metres, world frame (NaN: fewer than ``min_views`` views);
    ``times`` (T,) s; ``reprojection`` (T, K, V) pixel distance between each used observation
    and the reprojected point (NaN where the view was not used); ``views_used`` (T, K);
    ``poses`` per view; ``cameras`` matched to the views.
    """

    points: NDArray[np.float64]
    times: NDArray[np.float64]
    reprojection: NDArray[np.float64]
    views_used: NDArray[np.int64]
    poses: list[VideoPoses]
    cameras: list[Camera]
    layout: str
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


def triangulate_keypoints(
    cameras: Sequence[Camera],
    pixels: NDArray[np.float64],
    confidence: NDArray[np.float64],
    *,
    min_confidence: float = 0.5,
    min_views: int = 2,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Weighted DLT of keypoints seen by calibrated cameras.

    ``pixels`` (T, K, V, 2) distorted pixel coordinates (NaN: not seen), ``confidence``
    (T, K, V) in [0, 1]. Returns the points (T, K, 3), the reprojection error (T, K, V) px of
    each used observation, and the number of views used (T, K).
    """
    from visprim import _visprim

    t, k, v, _ = pixels.shape
    norm = np.stack([cameras[i].undistort(pixels[:, :, i]) for i in range(v)], axis=2)
    weights = np.where(
        (confidence >= min_confidence) & np.isfinite(norm).all(axis=-1), confidence, 0.0
    )
    proj = np.ascontiguousarray(np.stack([c.projection for c in cameras]), dtype=np.float64)
    flat = _visprim.triangulate_points(
        proj,
        np.ascontiguousarray(norm.reshape(t * k, v, 2), dtype=np.float64),
        np.ascontiguousarray(weights.reshape(t * k, v), dtype=np.float64),
        min_views=int(min_views),
    )
    points = flat.reshape(t, k, 3)
    used = weights > 0
    reproj = np.full((t, k, v), np.nan)
    for i, cam in enumerate(cameras):
        err = np.linalg.norm(cam.project(points) - pixels[:, :, i], axis=-1)
        reproj[:, :, i] = np.where(used[:, :, i] & np.isfinite(points).all(axis=-1), err, np.nan)
    return points, reproj, used.sum(axis=-1).astype(np.int64)


def triangulate_views(
    videos: Sequence[str | os.PathLike[str]],
    calibration: str | os.PathLike[str] | Sequence[Camera],
    *,
    estimator: PoseEstimator | None = None,
    min_confidence: float = 0.5,
    min_views: int = 2,
    max_frames: int | None = None,
    cache: bool = True,
) -> MultiView:
    """Pose of every view, triangulated (see the module docstring)."""
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
    layouts = {str(q.meta["layout"]) for q in poses}
    if len(layouts) != 1:
        raise ValueError(f"the views have different keypoint layouts: {sorted(layouts)}")
    n = min(q.times.shape[0] for q in poses)
    k = min(q.image.shape[1] for q in poses)
    pixels = np.stack([q.image[:n, :k] for q in poses], axis=2)
    conf = np.stack([np.where(q.found[:n, None], q.confidence[:n, :k], 0.0) for q in poses], axis=2)
    points, reproj, used = triangulate_keypoints(
        cameras, pixels, conf, min_confidence=min_confidence, min_views=min_views
    )
    meta = {
        "format": "video views",
        "views": [str(p) for p in paths],
        "cameras": [c.name for c in cameras],
        "frames": n,
        "person_found": [float(q.found[:n].mean()) for q in poses],
        "reprojection_px_median": float(np.nanmedian(reproj))
        if np.isfinite(reproj).any()
        else None,
        "min_views": int(min_views),
        "estimator": poses[0].meta["estimator"],
        "times_from": poses[0].meta["times_from"],
        "rate": poses[0].meta["rate"],
    }
    return MultiView(
        points=points,
        times=poses[0].times[:n],
        reprojection=reproj,
        views_used=used,
        poses=poses,
        cameras=cameras,
        layout=layouts.pop(),
        meta=meta,
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
) -> list[Trial]:
    """Trials from several calibrated views (several when long gaps split them)."""
    mv = triangulate_views(
        videos,
        calibration,
        estimator=estimator,
        min_confidence=min_confidence,
        min_views=min_views,
        max_frames=max_frames,
        cache=cache,
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
