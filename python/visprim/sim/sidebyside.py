"""The imitation video: the human's recorded arm beside Adonis, on the same clock.

Left panel: the recorded right arm (shoulder, elbow, wrist, finger; body axes, shoulder at
the origin) as a stick figure attached at Adonis's right shoulder, over a faint picture of
Adonis's body at rest (drawn once and reused), with the path of the finger. Right panel:
Adonis's playback (:class:`visprim.sim.render.PlaybackDrawer`). Both panels use the same
camera. Video time ``τ`` runs on the recording's clock from its first frame: the human at
``τ``, Adonis ``τ − start`` seconds into its playback (``start`` = where the first segment
begins), holding its first pose before and its last after.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PIL import Image, ImageDraw

from visprim.sim.model import LINKS, SHOULDER_OFFSET, WAIST_HEIGHT
from visprim.sim.render import (
    SUPERSAMPLE,
    TEXT_PX,
    TITLE_PX,
    Camera,
    Painter,
    PlaybackDrawer,
    _box,
    _even_box,
    _Label,
    _place,
    _union,
)
from visprim.sim.video import write_video, write_video_parts

#: Where the human's shoulders are drawn: Adonis's right (then left) shoulder at rest
#: (world, metres).
SHOULDER_WORLD = np.array(
    [
        [SHOULDER_OFFSET[0], -SHOULDER_OFFSET[1], WAIST_HEIGHT + SHOULDER_OFFSET[2]],
        [SHOULDER_OFFSET[0], SHOULDER_OFFSET[1], WAIST_HEIGHT + SHOULDER_OFFSET[2]],
    ]
)
_ARM_BODIES = ("r_upper_arm", "r_forearm", "r_hand", "l_upper_arm", "l_forearm", "l_hand")
_HUMAN_COLORS = ((200, 60, 30), (220, 110, 30), (235, 160, 40))


def _rest_transforms(n_arms: int) -> tuple[NDArray[np.float64], list[Any]]:
    """World transforms (n, 4, 4) and shapes of Adonis's bodies at rest, without the arms
    drawn from the recording (the right one, or both)."""
    tfs, shapes = [], []
    offsets: dict[str, NDArray[np.float64]] = {}
    for link in LINKS:
        base = offsets.get(link.parent, np.zeros(3)) if link.parent else np.zeros(3)
        origin = base + np.asarray(link.joint_offset)
        offsets[link.name] = origin
        if link.name in _ARM_BODIES[: 3 * n_arms]:
            continue
        tf = np.eye(4)
        tf[:3, 3] = origin
        tfs.append(tf)
        shapes.append(link.shapes)
    return np.stack(tfs), shapes


def adonis_drawer(imitation: Any, size: tuple[int, int], camera: Camera) -> PlaybackDrawer:
    """The drawer of the Adonis panel of an imitation: title (what the rebuild is made of)
    and a footer with the headline figures."""
    pb = imitation.playback
    m = imitation.metrics
    adonis = m["adonis"]
    seq = " ".join(str(int(k)) for k in imitation.primitives)
    if len(seq) > 40:
        seq = seq[:37] + "..."
    what = "primitives" if imitation.source == "primitives" else "NEAR-COPY (projection)"
    return PlaybackDrawer(
        pb,
        camera,
        size,
        title=f"Adonis: {what} {seq if imitation.source == 'primitives' else ''}".strip(),
        footer=(
            f"Adonis vs human, bone directions: {adonis['vs_human_direction_rms_deg']:.1f}° "
            f"RMS\nholding still instead: {m['headline']['still_posture_rms_deg']:.1f}°\n"
            f"tracks its rebuild to {adonis['vs_rebuild_joint_rms_deg']['overall']:.1f}° · "
            f"time {adonis['time_ratio']:.2f}x · via {pb.n_reached}/{pb.n_via}"
        ),
    )


class SideBySide:
    """Draws the frames of an :class:`visprim.imitate.Imitation` (see the module docstring)."""

    def __init__(
        self,
        imitation: Any,
        size: tuple[int, int] = (480, 480),
        camera: Camera | None = None,
    ) -> None:
        from visprim.ik import human_arm_points

        if imitation.playback is None:
            raise ValueError("the imitation was not played on Adonis (play=False): no video")
        cam = camera or Camera()
        self.size = size
        self.fps = float(imitation.playback.render_fps)
        pb = imitation.playback
        m = imitation.metrics
        self.adonis = adonis_drawer(imitation, size, cam)
        self.painter = Painter(cam, size)
        p = self.painter
        # Background of the human panel: Adonis at rest without the recorded arm(s), faint.
        n_arms = imitation.human.shape[1] // 4
        tfs, shapes = _rest_transforms(n_arms)
        self.background, draw = p.canvas()
        p.draw_items(draw, p.body_items(tfs, shapes, tint=(0.75, 0.93)))
        trial = imitation.trial
        self.human_times = trial.times - trial.times[0]
        points = human_arm_points(trial) + np.repeat(SHOULDER_WORLD[:n_arms], 4, axis=0)
        self.human_2d = p.project(points)  # (T, 4 n_arms, 2)
        self.n_arms = n_arms
        self.finger_runs = [
            run
            for a in range(n_arms)
            for run in p.dash_runs(self.human_2d[:, 4 * a + 3], 6.0 * SUPERSAMPLE)
        ]
        w, h = size
        rb = m["rebuild_vs_human_direction_rms_deg"]
        cov = m["coverage"]
        self.labels = [
            _Label(f"human: {imitation.name}", TITLE_PX, "la", (4, 4), False),
            _Label(
                f"rebuild vs human, bone directions: {rb:.1f}° RMS\n"
                f"not in a segment: {cov['uncovered_s']:.2f} s ({cov['uncovered_percent']:.0f}%)",
                TEXT_PX,
                "md",
                (w / 2, h),
                True,
                width=w,
            ),
        ]
        # The dashed finger path never changes: drawn once into the background. The trail
        # (the finger's path so far) grows: drawn onto ``_trail`` a segment at a time, so a
        # frame costs the same at the end of a long recording as at its start.
        draw = ImageDraw.Draw(self.background)
        for run in self.finger_runs:
            draw.line(run, fill=(150, 150, 210), width=SUPERSAMPLE)
        self._reset_trail()
        self.start = float(imitation.rebuild.start - trial.times[0])
        end = max(self.human_times[-1], self.start + float(pb.frame_times[-1]))
        self.n_frames = int(np.floor(end * self.fps + 1e-9)) + 1

    def _reset_trail(self) -> None:
        """Start the trail again: nothing of it drawn, no stick figure on the scratch canvas."""
        self._trail = self.background.copy()
        self._trail_end = 0  # trail drawn up to this frame
        # ``_scratch`` is the trail with the last stick figure drawn on it, and ``_small``
        # its reduction: a frame restores, redraws and reduces only the box that changed.
        self._scratch = self._trail.copy()
        self._small = self.painter.finish(self._scratch)
        self._figure_box: tuple[int, int, int, int] | None = None

    def human_frame(
        self, tau: float, into: tuple[Image.Image, tuple[int, int]] | None = None
    ) -> Image.Image:
        """The human panel at video time ``tau`` seconds (``into``: as
        :meth:`~visprim.sim.render.PlaybackDrawer.draw`).

        Only the box that changed since the last frame (the last and the new stick figure,
        the new piece of trail) is redrawn and reduced: the same pixels as drawing the whole
        canvas and reducing it, at the cost of the box."""
        p = self.painter
        i = int(np.clip(np.searchsorted(self.human_times, tau, side="right") - 1, 0, None))
        s = SUPERSAMPLE
        if i < self._trail_end:  # earlier than the trail drawn so far: start it again
            self._reset_trail()
        dirty = self._figure_box
        if i > self._trail_end:
            trail = ImageDraw.Draw(self._trail)
            for a in range(self.n_arms):
                piece = self.human_2d[self._trail_end : i + 1, 4 * a + 3]
                p.polyline(trail, piece, (230, 102, 13), 1.6 * s)
                dirty = _union(dirty, _box(piece, 2.0 * s))
            self._trail_end = i
        width = int(7 * s)
        r = 4.5 * s
        figure = self.human_2d[i, : 4 * self.n_arms]
        self._figure_box = _box(figure, max(width / 2.0, r) + 2.0)
        dirty = _union(dirty, self._figure_box)
        box = _even_box(dirty, self._scratch.size) if dirty is not None else None
        if box is not None:
            self._scratch.paste(self._trail.crop(box), box[:2])
        draw = ImageDraw.Draw(self._scratch)
        for a in range(self.n_arms):
            pts = self.human_2d[i, 4 * a : 4 * a + 4]
            for u, v, col in zip(pts[:-1], pts[1:], _HUMAN_COLORS, strict=True):
                draw.line((*u, *v), fill=col, width=width)
            for x, y in pts:
                draw.ellipse((x - r, y - r, x + r, y + r), fill=(60, 60, 60))
        if box is not None:
            part = p.finish_part(self._scratch, box)
            self._small.paste(part, (box[0] // s, box[1] // s))
        out, at = _place(self._small, into)
        for label in self.labels:
            label.paste(out, at)
        p.text(out, (at[0] + self.size[0] - 4, at[1] + 4), f"t = {tau:.2f} s", TEXT_PX, "ra")
        return out

    def frame(self, index: int) -> Image.Image:
        """Video frame ``index`` (both panels side by side)."""
        tau = index / self.fps
        k = int(
            np.clip(
                round((tau - self.start) * self.fps), 0, self.adonis.playback.frames.shape[0] - 1
            )
        )
        w, h = self.size
        out = Image.new("RGB", (2 * w, h), None)  # not filled: the two panels cover it
        self.human_frame(tau, into=(out, (0, 0)))
        self.adonis.draw(k, clock=tau, into=(out, (w, 0)))
        return out

    def frames(self) -> Iterator[Image.Image]:
        for i in range(self.n_frames):
            yield self.frame(i)


def render_imitation(
    imitation: Any,
    path: str | Path,
    *,
    size: tuple[int, int] = (480, 480),
    camera: Camera | None = None,
    workers: int | None = None,
) -> Path:
    """Write the side-by-side video of an imitation (.gif or .mp4, from the extension),
    atomically, one frame at a time. A recording read from a video shows its own frames with
    the detected arm, on the video's clock (:mod:`visprim.sim.sidebyside_video`); any other
    shows the recorded arm as a stick figure at the playback's frame rate, its frames drawn
    by ``workers`` processes (None: as many as the usable cores keep busy,
    :func:`visprim.sim.frame_workers.draw_workers`). Returns the path."""
    from visprim.sim.frame_workers import draw_workers
    from visprim.sim.sidebyside_video import is_video_trial, render_video_imitation

    if is_video_trial(imitation.trial):
        return render_video_imitation(imitation, path, size=size, camera=camera)
    view = SideBySide(imitation, size, camera)
    mp4 = Path(path).suffix.lower() == ".mp4"
    n = draw_workers(view.n_frames, workers, cores_per_part=2 if mp4 else 1)
    if n < 2:
        return write_video(path, view.frames(), view.fps)
    return write_video_parts(path, view.frame, view.n_frames, view.fps, n)
