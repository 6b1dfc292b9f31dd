"""The imitation video of a video recording: its own frames, the detected arm drawn on them,
beside Adonis, on the video's clock.

Left panel: each decoded frame of the source video (scaled to the panel height, aspect kept)
with the arm the trial was built from drawn on it: shoulder, elbow, wrist and hand, the pixel
keypoints the pose estimator found in that frame (:func:`visprim.io.video_pose.video_poses`,
read again from its cache; the keypoints and arms named in the trial's ``meta``). A keypoint
below the reader's confidence threshold, or a frame without a person, draws nothing.
Right panel: Adonis (:class:`visprim.sim.render.PlaybackDrawer`) at the same time.

One clock: output frame ``i`` is source frame ``i · k`` (``k = 1`` up to 60 frames per second,
else the smallest whole step that brings the rate to at most 60), shown with its own
timestamp ``t`` (the container's clock, from its first frame, as the trial's times), and
Adonis at ``t``: its joint positions at simulation time ``t − start`` (``start`` = where the
first segment begins on that clock), holding its first pose before and its last after. The
video is written at the source's rate divided by ``k``.

Frames are decoded, drawn and encoded one at a time: memory holds a few frames whatever
the length. Needs the ``video`` extra (OpenCV decodes the source).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PIL import Image, ImageDraw

from visprim.sim.render import TEXT_PX, TITLE_PX, Camera, Painter, _Label
from visprim.sim.video import write_video

#: Highest frame rate of the output video, Hz (a faster source is taken every k-th frame).
MAX_FPS = 60.0
#: Colours of the upper arm, forearm and hand segments (as the stick figure of
#: :mod:`visprim.sim.sidebyside`).
ARM_COLORS = ((200, 60, 30), (220, 110, 30), (235, 160, 40))
_PARTS = ("shoulder", "elbow", "wrist", "hand")


def is_video_trial(trial: Any) -> bool:
    """Whether ``trial`` was read from a video file that still exists."""
    meta = getattr(trial, "meta", None) or {}
    source = getattr(trial, "source", None)
    return meta.get("format") == "video" and source is not None and Path(source).is_file()


def arm_keypoints(trial: Any) -> list[list[list[int]]]:
    """Per drawn arm, the keypoint indices of shoulder, elbow, wrist and hand (each a list:
    their centroid; the hand may be empty), from the trial's ``meta["keypoints"]``."""
    roles = dict(trial.meta.get("keypoints") or {})
    arm = str(trial.meta.get("arm", "right"))
    sides = ("right", "left") if arm == "both" else (arm,)
    out = []
    for side in sides:
        parts = [[int(i) for i in roles.get(f"{side}_{part}", [])] for part in _PARTS]
        if all(parts[:3]):
            out.append(parts)
    if not out:
        raise ValueError(f"{trial.source}: the trial names no arm keypoints to draw")
    return out


def arm_pixels(
    image: NDArray[np.float64],
    confidence: NDArray[np.float64],
    found: bool,
    arms: list[list[list[int]]],
    min_confidence: float,
) -> list[list[NDArray[np.float64] | None]]:
    """Pixel position (2,) of each arm part in one frame, None where it is not seen (no
    person, or a keypoint below ``min_confidence``)."""
    out: list[list[NDArray[np.float64] | None]] = []
    for parts in arms:
        row: list[NDArray[np.float64] | None] = []
        for idx in parts:
            if not found or not idx or np.any(~(confidence[idx] >= min_confidence)):
                row.append(None)
                continue
            p = image[idx].mean(axis=0)
            row.append(p if np.all(np.isfinite(p)) else None)
        out.append(row)
    return out


def draw_arm(
    draw: ImageDraw.ImageDraw, pixels: list[list[NDArray[np.float64] | None]], scale: float
) -> None:
    """Bones and joints of the arms at ``pixels`` (source pixels) times ``scale``."""
    width = max(3, int(round(0.02 * draw.im.size[1])))
    r = width * 0.8
    for row in pixels:
        pts = [None if p is None else (float(p[0] * scale), float(p[1] * scale)) for p in row]
        for u, v, col in zip(pts[:-1], pts[1:], ARM_COLORS, strict=True):
            if u is not None and v is not None:
                draw.line((*u, *v), fill=col, width=width)
        for p in pts:
            if p is not None:
                draw.ellipse((p[0] - r, p[1] - r, p[0] + r, p[1] + r), fill=(60, 60, 60))


class VideoSideBySide:
    """Draws the frames of an imitation of a video recording (see the module docstring)."""

    def __init__(
        self,
        imitation: Any,
        size: tuple[int, int] = (480, 480),
        camera: Camera | None = None,
        *,
        min_confidence: float | None = None,
    ) -> None:
        from visprim.io.video_pose import video_poses
        from visprim.sim.model import build_adonis
        from visprim.sim.sidebyside import adonis_drawer

        if imitation.playback is None:
            raise ValueError("the imitation was not played on Adonis (play=False): no video")
        trial = imitation.trial
        if not is_video_trial(trial):
            raise ValueError(f"{trial.source}: not a trial read from a video file")
        self.path = Path(trial.source)
        self.arms = arm_keypoints(trial)
        conf = trial.meta.get("min_confidence", 0.5) if min_confidence is None else min_confidence
        self.min_confidence = float(conf)
        poses = video_poses(self.path)  # the reader's cache: no second pass of the network
        self.poses = poses
        rate = float(poses.meta.get("rate") or 0.0)
        if not (np.isfinite(rate) and rate > 0) and poses.times.size > 1:
            rate = 1.0 / float(np.median(np.diff(poses.times)))
        self.step = max(1, int(np.ceil(rate / MAX_FPS - 1e-9)))
        self.fps = rate / self.step
        self.times = poses.times[:: self.step]
        self.n_frames = int(self.times.size)
        w_src, h_src = (int(v) for v in poses.size)
        self.size = size
        _, h = size
        self.scale = h / h_src
        self.video_size = (max(2, int(round(w_src * self.scale / 2)) * 2), h)
        pb = imitation.playback
        self.start = float(imitation.rebuild.start)
        self.adonis = adonis_drawer(imitation, size, camera or Camera())
        self.dt = float(pb.times[1] - pb.times[0]) if pb.times.shape[0] > 1 else 1.0
        self.kinematics = _kinematics(build_adonis(self.dt)[1])
        self.labels = [
            _Label(f"video: {imitation.name}", TITLE_PX, "la", (4, 4), True),
        ]

    def adonis_at(self, t: float) -> Image.Image:
        """The Adonis panel at time ``t`` s of the video's clock."""
        pb = self.adonis.playback
        sim = float(np.clip(t - self.start, 0.0, pb.times[-1]))
        step = int(np.clip(np.rint(sim / self.dt), 0, pb.q_actual.shape[0] - 1))
        transforms = self.kinematics.transforms(np.asarray(pb.q_actual[step])[None, :])[0]
        index = int(np.clip(np.searchsorted(pb.frame_times, sim + 1e-9) - 1, 0, None))
        return self.adonis.draw(index, clock=t, transforms=transforms, time=sim)

    def video_panel(self, rgb: NDArray[np.uint8], source_index: int) -> Image.Image:
        """Source frame ``source_index`` (RGB, source size) scaled, with the arm drawn."""
        import cv2

        small = cv2.resize(rgb, self.video_size, interpolation=cv2.INTER_AREA)
        image = Image.fromarray(small)
        p = self.poses
        pixels = arm_pixels(
            p.image[source_index],
            p.confidence[source_index],
            bool(p.found[source_index]),
            self.arms,
            self.min_confidence,
        )
        draw_arm(ImageDraw.Draw(image), pixels, self.video_size[0] / p.size[0])
        for label in self.labels:
            label.paste(image)
        return image

    def frames(self) -> Iterator[Image.Image]:
        """The output frames, decoded, drawn and yielded one at a time."""
        vw, h = self.video_size
        w = self.size[0]
        for i, (k, rgb) in enumerate(_decoded(self.path, self.step, self.n_frames)):
            t = float(self.times[i])
            out = Image.new("RGB", (vw + w, h), (255, 255, 255))
            out.paste(self.video_panel(rgb, k), (0, 0))
            out.paste(self.adonis_at(t), (vw, 0))
            Painter.text(out, (4, h - 4), f"t = {t:.3f} s", TEXT_PX, "ld", box=True)
            yield out


def _kinematics(skeleton: Any) -> Any:
    from visprim.sim.kinematics import BatchKinematics

    return BatchKinematics(skeleton)


def _decoded(path: Path, step: int, n: int) -> Iterator[tuple[int, NDArray[np.uint8]]]:
    """(source index, RGB frame) of every ``step``-th decoded frame, ``n`` of them, in the
    order :func:`visprim.io.video_pose.video_poses` read them."""
    import cv2

    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise ValueError(f"{path}: OpenCV cannot decode the video again")
    try:
        k = 0
        while k < n * step:
            ok, frame = cap.read()
            if not ok:
                break
            if k % step == 0:
                yield k, np.asarray(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB), dtype=np.uint8)
            k += 1
    finally:
        cap.release()


def render_video_imitation(
    imitation: Any,
    path: str | Path,
    *,
    size: tuple[int, int] = (480, 480),
    camera: Camera | None = None,
) -> Path:
    """Write the side-by-side video of an imitation of a video recording (.mp4 or .gif, from
    the extension), frame by frame and atomically. Returns the path."""
    view = VideoSideBySide(imitation, size, camera)
    return write_video(path, view.frames(), view.fps)
