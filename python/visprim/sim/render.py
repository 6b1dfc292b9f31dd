"""Headless pictures of a playback: PNG frames and an animated GIF, drawn with PIL.

The stored body transforms of a :class:`visprim.sim.playback.Playback` are projected
orthographically from a fixed camera (front-right, slightly above, looking at the chest) and
the shapes of :data:`visprim.sim.model.LINKS` are painted back to front with
:mod:`PIL.ImageDraw`: capsules as thick round-capped strokes, boxes as their visible shaded
faces, spheres as discs. Frames are drawn at twice the output size and reduced (a 2×2 box
filter) for smooth edges. The right hand's target path is drawn dashed with its via points
(filled once reached), and the path the hand actually took so far as a solid line. No
display, OpenGL or X server is needed.

:class:`Painter` is the reusable part (projection, body shapes, paths, text);
:mod:`visprim.sim.video` builds the side-by-side imitation video with it.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from PIL import Image, ImageDraw, ImageFont

from visprim.sim.playback import Playback
from visprim.sim.trace import blocks

#: Supersampling factor: frames are drawn this many times larger, then reduced.
SUPERSAMPLE = 2

_BOX_FACES = (  # corner indices (bit 0: +x, bit 1: +y, bit 2: +z), outward normal
    ((0, 2, 6, 4), (-1, 0, 0)),
    ((1, 5, 7, 3), (1, 0, 0)),
    ((0, 4, 5, 1), (0, -1, 0)),
    ((2, 3, 7, 6), (0, 1, 0)),
    ((0, 1, 3, 2), (0, 0, -1)),
    ((4, 6, 7, 5), (0, 0, 1)),
)
_CORNERS = np.array([[(i >> b) & 1 for b in range(3)] for i in range(8)], dtype=np.float64) - 0.5
_FACE_IDX = np.array([f for f, _ in _BOX_FACES])
_FACE_NORMALS = np.array([n for _, n in _BOX_FACES], dtype=np.float64)

RGB = tuple[int, int, int]


@dataclass(frozen=True)
class Camera:
    """A fixed orthographic camera.

    ``azimuth`` (degrees, about +z from +x: 0 looks at the figure's front, −90 at its right
    side) and ``elevation`` (degrees above the horizontal) place the viewing direction;
    ``target`` (metres) is the point at the image centre; ``extent`` (metres) the half-size of
    the region kept in view around it.
    """

    azimuth: float = -40.0
    elevation: float = 10.0
    target: tuple[float, float, float] = (0.0, -0.1, 1.22)
    extent: float = 0.88

    def basis(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Unit vectors (right, up, towards the camera) in world coordinates."""
        az, el = np.radians(self.azimuth), np.radians(self.elevation)
        back = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        right = np.cross(-back, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, -back)
        return right, up, back


def _rgb(color: ArrayLike) -> RGB:
    c = np.clip(np.asarray(color, dtype=np.float64), 0.0, 1.0)
    return (int(c[0] * 255 + 0.5), int(c[1] * 255 + 0.5), int(c[2] * 255 + 0.5))


@lru_cache(maxsize=256)
def _colors(
    color: tuple[float, float, float], tint: tuple[float, float] | None
) -> tuple[NDArray[np.float64], RGB, RGB]:
    """Base colour (float RGB), fill and edge colours (8-bit) of a shape colour."""
    base = np.asarray(color, dtype=np.float64)
    if tint is not None:
        base = base * (1.0 - tint[0]) + tint[1] * tint[0]
    return base, _rgb(base), _rgb(base * 0.55)


@lru_cache(maxsize=8)
def _font(size: int) -> ImageFont.ImageFont | ImageFont.FreeTypeFont:
    try:
        return ImageFont.load_default(size=size)
    except (TypeError, OSError):  # pragma: no cover - Pillow without FreeType
        return ImageFont.load_default()


class Painter:
    """Projects world points (metres) into an image of ``size`` pixels and draws on it.

    Drawing happens on a canvas ``SUPERSAMPLE`` times larger; :meth:`finish` returns the
    reduced image.
    """

    def __init__(self, camera: Camera, size: tuple[int, int]) -> None:
        self.camera = camera
        self.size = size
        self.right, self.up, self.back = camera.basis()
        light = self.back * 0.6 + self.up * 0.8
        self.light = light / np.linalg.norm(light)
        w, h = size
        s = SUPERSAMPLE
        self.px_per_m = min(w, h) / (2.0 * camera.extent) * s
        centre = np.array([self.right, self.up]) @ np.asarray(camera.target)
        self._origin = np.array([w * s / 2.0, h * s / 2.0])
        self._centre = centre
        self._proj = np.stack([self.right, -self.up], axis=1) * self.px_per_m

    def project(self, points: ArrayLike) -> NDArray[np.float64]:
        """Canvas pixel coordinates (..., 2) of world points (..., 3)."""
        p = np.asarray(points, dtype=np.float64)
        return p @ self._proj - self._centre * np.array([1.0, -1.0]) * self.px_per_m + self._origin

    def canvas(self, background: RGB = (255, 255, 255)) -> tuple[Image.Image, ImageDraw.ImageDraw]:
        """A new blank canvas and its drawing context."""
        w, h = self.size
        image = Image.new("RGB", (w * SUPERSAMPLE, h * SUPERSAMPLE), background)
        return image, ImageDraw.Draw(image)

    def finish(self, image: Image.Image) -> Image.Image:
        """The canvas reduced to the output size."""
        return image.reduce(SUPERSAMPLE) if SUPERSAMPLE > 1 else image

    def finish_part(self, image: Image.Image, box: tuple[int, int, int, int]) -> Image.Image:
        """The part ``box`` of the canvas (its edges multiples of :data:`SUPERSAMPLE`)
        reduced to the output size, without copying it out first."""
        return image.reduce(SUPERSAMPLE, box=box) if SUPERSAMPLE > 1 else image.crop(box)

    # -------------------------------------------------------------- bodies

    def body_items(
        self,
        transforms: NDArray[np.float64],
        body_shapes: Sequence[Sequence[Any]],
        tint: tuple[float, float] | None = None,
    ) -> list[tuple[float, str, Any, float, RGB, RGB]]:
        """Depth-tagged draw items of bodies at (n, 4, 4) world ``transforms``.

        ``tint = (mix, grey)`` blends every colour towards ``grey`` by ``mix`` (ghosts)."""
        items: list[tuple[float, str, Any, float, RGB, RGB]] = []
        back = self.back
        for tf, shapes in zip(transforms, body_shapes, strict=True):
            rot, pos = tf[:3, :3], tf[:3, 3]
            for spec in shapes:
                centre = rot @ np.asarray(spec.centre) + pos
                base, fill, edge = _colors(spec.color, tint)
                depth = float(centre @ back)
                if spec.kind == "capsule":
                    r, h = spec.size
                    axis = rot[:, 2] * (h / 2.0)
                    ends = self.project(np.stack([centre - axis, centre + axis]))
                    items.append((depth, "capsule", ends, r * self.px_per_m, fill, edge))
                elif spec.kind == "sphere":
                    items.append(
                        (depth, "sphere", self.project(centre), spec.size[0] * self.px_per_m,
                         fill, edge)
                    )  # fmt: skip
                else:
                    corners = (_CORNERS * np.asarray(spec.size)) @ rot.T + centre
                    normals = _FACE_NORMALS @ rot.T
                    facing = normals @ back > 1e-9
                    shade = 0.55 + 0.45 * np.maximum(0.0, normals @ self.light)
                    faces = corners[_FACE_IDX[facing]]  # (n facing, 4 corners, 3)
                    depths = faces.mean(axis=1) @ back
                    pixels = self.project(faces)
                    colours = np.clip(base * shade[facing][:, None], 0.0, 1.0) * 255 + 0.5
                    for d, px, c in zip(
                        depths.tolist(), pixels, colours.astype(int).tolist(), strict=True
                    ):
                        items.append((d, "face", px, 0.0, (c[0], c[1], c[2]), edge))
        return items

    @staticmethod
    def draw_items(draw: ImageDraw.ImageDraw, items: Iterable[tuple]) -> None:
        """Paint items back to front."""
        for _, kind, geom, radius, color, edge in sorted(items, key=lambda it: it[0]):
            if kind == "capsule":
                (x0, y0), (x1, y1) = geom
                for col, extra in ((edge, 1.6), (color, 0.0)):
                    r = radius + extra
                    draw.line((x0, y0, x1, y1), fill=col, width=max(1, int(round(2 * r))))
                    draw.ellipse((x0 - r, y0 - r, x0 + r, y0 + r), fill=col)
                    draw.ellipse((x1 - r, y1 - r, x1 + r, y1 + r), fill=col)
            elif kind == "sphere":
                x, y = geom
                r = radius
                draw.ellipse((x - r, y - r, x + r, y + r), fill=color, outline=edge, width=2)
            else:
                draw.polygon([tuple(p) for p in geom], fill=color, outline=edge)

    # -------------------------------------------------------------- overlays

    def polyline(
        self, draw: ImageDraw.ImageDraw, points_2d: NDArray[np.float64], color: RGB, width: float
    ) -> None:
        if points_2d.shape[0] >= 2:
            draw.line([tuple(p) for p in points_2d], fill=color, width=max(1, int(width)))

    @staticmethod
    def dash_runs(points_2d: NDArray[np.float64], dash: float = 12.0) -> list[list[tuple]]:
        """The visible runs of a dashed polyline (dash and gap ``dash`` canvas pixels)."""
        if points_2d.shape[0] < 2:
            return []
        seg = np.diff(points_2d, axis=0)
        arc = np.concatenate([[0.0], np.cumsum(np.hypot(seg[:, 0], seg[:, 1]))])
        on = (arc // dash).astype(np.int64) % 2 == 0
        runs, start = [], None
        for i in range(points_2d.shape[0]):
            if on[i] and start is None:
                start = i
            if (not on[i] or i == points_2d.shape[0] - 1) and start is not None:
                if i > start:
                    runs.append([tuple(p) for p in points_2d[start : i + 1]])
                start = None
        return runs

    @staticmethod
    def text(
        image: Image.Image,
        xy: tuple[float, float],
        text: str,
        size: float = 11,
        anchor: str = "la",
        fill: RGB = (20, 20, 20),
        box: bool = False,
    ) -> None:
        """Text on a finished (output-size) image at pixel ``xy``, font ``size`` pixels.

        The glyphs' coverage is rendered once per text (:func:`_text_mask`; a frame shows
        its clock in both panels) and the colour pasted through it, which blends exactly as
        drawing the text does."""
        x, y = (int(round(v)) for v in xy)
        mask, (x0, y0, x1, y1) = _text_mask(text, int(round(size)), anchor)
        if box:
            ImageDraw.Draw(image).rectangle(
                (x + x0 - 3, y + y0 - 2, x + x1 + 3, y + y1 + 3), fill=(255, 255, 255)
            )
        image.paste(fill, (x + x0, y + y0), mask)


@lru_cache(maxsize=16)
def _text_mask(text: str, size: int, anchor: str) -> tuple[Image.Image, tuple[int, int, int, int]]:
    """The coverage (mode L) of ``text`` in the font of ``size`` pixels, and its box
    relative to the ``anchor`` point (left, top, right, bottom pixels)."""
    font = _font(size)
    x0, y0, x1, y1 = ImageDraw.Draw(Image.new("L", (1, 1))).textbbox(
        (0, 0), text, font=font, anchor=anchor
    )
    x0, y0, x1, y1 = int(x0), int(y0), int(x1), int(y1)
    mask = Image.new("L", (max(1, x1 - x0), max(1, y1 - y0)), 0)
    ImageDraw.Draw(mask).text((-x0, -y0), text, font=font, fill=255, anchor=anchor)
    return mask, (x0, y0, x1, y1)


#: Font sizes (pixels at the output size) of the frame texts: title, figures, clock.
TITLE_PX = 16
TEXT_PX = 14


class _Label:
    """A text rendered once and pasted on every frame (lines split at ``\\n``); ``width``
    pixels, if given, makes its box a band that wide (hiding what lies under it), the text
    centred in it."""

    def __init__(
        self,
        text: str,
        size: float,
        anchor: str,
        xy: tuple[float, float],
        box: bool,
        width: int | None = None,
    ):
        probe = ImageDraw.Draw(Image.new("RGB", (1, 1)))
        font = _font(int(round(size)))
        x0, y0, x1, y1 = probe.multiline_textbbox((0, 0), text, font=font, spacing=3)
        pad = 3 if box else 0
        w, h = int(x1 - x0) + 2 * pad + 1, int(y1 - y0) + 2 * pad + 1
        left = pad - x0
        if width is not None and width > w:
            left += (width - w) // 2
            w = width
        self.image = Image.new("RGBA", (w, h), (255, 255, 255, 255 if box else 0))
        ImageDraw.Draw(self.image).multiline_text(
            (left, pad - y0), text, font=font, fill=(40, 40, 40), spacing=3, align="center"
        )
        # Opaque everywhere (a boxed label): pasted as RGB, without the mask (same pixels).
        self.mask: Image.Image | None = self.image
        if self.image.getchannel("A").getextrema()[0] == 255:
            self.image, self.mask = self.image.convert("RGB"), None
        x, y = xy
        x -= {"l": 0, "m": w / 2, "r": w}[anchor[0]]
        y -= {"a": 0, "m": h / 2, "d": h}[anchor[1]]
        self.xy = (int(round(x)), int(round(y)))

    def paste(self, image: Image.Image, offset: tuple[int, int] = (0, 0)) -> None:
        """Paste the label on ``image``, shifted by ``offset`` pixels (a panel's place)."""
        image.paste(self.image, (self.xy[0] + offset[0], self.xy[1] + offset[1]), self.mask)


class PlaybackDrawer:
    """Draws frame ``i`` of a playback: bodies, the hand's target path and via points, the
    path taken so far, title, clock and a footer with the tracking figures."""

    def __init__(
        self,
        playback: Playback,
        camera: Camera,
        size: tuple[int, int],
        title: str | None = None,
        footer: str | None = None,
    ) -> None:
        self.playback = playback
        self.painter = Painter(camera, size)
        self.title = title
        p = self.painter
        w, h = size
        self.labels = []
        if title:
            self.labels.append(_Label(title, TITLE_PX, "la", (4, 4), False))
        self.ref_2d = p.project(playback.hand_reference)
        self.ref_runs = p.dash_runs(self.ref_2d, 6.0 * SUPERSAMPLE)
        self.via_2d = p.project(playback.hand_via)
        self.path_2d = p.project(playback.hand_path)
        self.footer = (
            footer
            if footer is not None
            else (
                f"tracking error RMS {playback.rms_error_deg:.1f}°, max "
                f"{playback.max_error_deg:.1f}°\ntook {playback.completion_time:.2f} s for "
                f"{playback.movement_duration:.2f} s · via points {playback.n_reached}/"
                f"{playback.n_via}"
            )
        )

        if self.footer:
            self.labels.append(_Label(self.footer, TEXT_PX, "md", (w / 2, h), True, width=w))
        # Bodies that never move (the pelvis and legs) are projected once.
        frames = playback.frames  # an array, or a Trace on disk: read a block at a time
        first = np.asarray(frames[0])
        moved = np.zeros(first.shape[0])
        for _, block in blocks(frames):
            moved = np.maximum(moved, np.abs(block - first).max(axis=(0, 2, 3)))
        still = moved < 1e-12
        self.moving = np.flatnonzero(~still)
        self.static_items = p.body_items(
            first[still], [s for s, k in zip(playback.body_shapes, still, strict=True) if k]
        )
        self.moving_shapes = [playback.body_shapes[i] for i in self.moving]
        # Over the bodies: the target path and via points, then the path taken so far. Both
        # are transparent layers drawn incrementally as time goes forward (a via point's dot
        # is drawn open at the start and filled over when it is reached; the path a segment at
        # a time), and only the part of a layer that holds drawing is composited, so a frame
        # costs the same at the end of a long playback as at its start.
        self._marks: Image.Image | None = None
        self._reached: NDArray[np.bool_] | None = None
        self._path: Image.Image | None = None
        self._path_end = 0
        self._path_box: tuple[int, int, int, int] | None = None
        self._marks_box = _box(np.concatenate([self.ref_2d, self.via_2d]), 4.0 * SUPERSAMPLE)
        # Both layers flattened into one picture and where it holds drawing, kept up to date
        # where the layers gain drawing: a frame composites it once, by a plain copy of the
        # pixels the mask holds.
        self._over: Image.Image | None = None
        self._over_mask: Image.Image | None = None
        # The last frame drawn: its canvas, reduced, and the box its moving bodies covered. A
        # frame redraws and reduces only the box that changed (the bodies that move, then and
        # now, and what the overlays gained); ``_changed`` is what the overlays gained (None:
        # nothing; the whole canvas after a restart).
        self._canvas: Image.Image | None = None
        self._small: Image.Image | None = None
        self._bodies_box: tuple[int, int, int, int] | None = None
        self._changed: tuple[int, int, int, int] | None = None

    def _whole(self) -> tuple[int, int, int, int]:
        w, h = self.painter.size
        return (0, 0, w * SUPERSAMPLE, h * SUPERSAMPLE)

    def _layer(self) -> Image.Image:
        w, h = self.painter.size
        return Image.new("RGBA", (w * SUPERSAMPLE, h * SUPERSAMPLE), (0, 0, 0, 0))

    def _dot(self, draw: ImageDraw.ImageDraw, j: int, hit: bool) -> None:
        s = SUPERSAMPLE
        r = 2.2 * s
        x, y = self.via_2d[j]
        draw.ellipse(
            (x - r, y - r, x + r, y + r),
            fill=(26, 166, 51) if hit else (255, 255, 255),
            outline=(26, 115, 38),
            width=max(1, s),
        )

    def _overlays(
        self, index: int, t: float
    ) -> tuple[Image.Image, Image.Image, tuple[int, int, int, int] | None]:
        """The overlays at frame ``index`` (time ``t`` s) as one picture: its colours (RGB),
        where it holds drawing (mode 1) and the box that does (None: nothing drawn yet)."""
        pb, p, s = self.playback, self.painter, SUPERSAMPLE
        reached = np.nan_to_num(pb.via_reach_times, nan=np.inf) <= t + 1e-9
        gained = None  # what the overlays gained this frame
        if self._marks is None or self._reached is None or np.any(self._reached & ~reached):
            # From the start (or back in time): the path, every dot open, the reached filled.
            self._marks, self._reached = self._layer(), np.zeros_like(reached)
            draw = ImageDraw.Draw(self._marks)
            for run in self.ref_runs:
                draw.line(run, fill=(51, 89, 217), width=max(1, int(1.2 * s)))
            for j in range(self.via_2d.shape[0]):
                self._dot(draw, j, False)
            gained = self._whole()
        if np.any(reached & ~self._reached):
            draw = ImageDraw.Draw(self._marks)
            for hit in np.flatnonzero(reached & ~self._reached).tolist():
                self._dot(draw, hit, True)
                gained = _union(gained, _box(self.via_2d[hit], 4.0 * s))
            self._reached = reached
        if self._path is None or index < self._path_end:
            self._path, self._path_end, self._path_box = self._layer(), 0, None
            gained = self._whole()
        if index > self._path_end:
            piece = self.path_2d[self._path_end : index + 1]
            p.polyline(ImageDraw.Draw(self._path), piece, (230, 102, 13), 1.6 * s)
            self._path_box = _union(self._path_box, _box(piece, 2.0 * s))
            gained = _union(gained, _box(piece, 2.0 * s))
            self._path_end = index
        self._changed = _union(self._changed, gained)
        self._flatten(gained)
        assert self._over is not None and self._over_mask is not None
        return self._over, self._over_mask, _union(self._marks_box, self._path_box)

    def _flatten(self, box: tuple[int, int, int, int] | None) -> None:
        """Bring the flat copy of the overlays (the path taken over the marks; their
        drawing is opaque, so a pixel is one layer's colour or neither) up to date in
        ``box``."""
        if self._over is None or self._over_mask is None:
            w, h = self._whole()[2:]
            self._over, self._over_mask = Image.new("RGB", (w, h)), Image.new("1", (w, h))
            box = self._whole()
        box = _intersection(box, self._whole())
        if box is None or self._marks is None or self._path is None:
            return
        part = self._marks.crop(box)
        part.alpha_composite(self._path.crop(box))
        self._over.paste(part.convert("RGB"), box[:2])
        self._over_mask.paste(part.getchannel("A").convert("1", dither=Image.Dither.NONE), box[:2])

    def draw(
        self,
        index: int,
        clock: float | None = None,
        *,
        transforms: NDArray[np.float64] | None = None,
        time: float | None = None,
        into: tuple[Image.Image, tuple[int, int]] | None = None,
    ) -> Image.Image:
        """Frame ``index`` as an RGB image; ``clock`` (s) overrides the time shown.

        ``transforms`` (n_bodies, 4, 4) draws the bodies there instead of at the stored
        frame (a pose between frames), and ``time`` (s, simulation) decides which via
        points are shown reached; the path taken is drawn up to frame ``index``.
        ``into = (image, (x, y))`` draws the frame into ``image`` at pixel ``(x, y)`` (a
        panel of a larger frame; no copy of its own) and returns ``image``."""
        pb, p = self.playback, self.painter
        tfs = pb.frames[index] if transforms is None else transforms
        items = p.body_items(tfs[self.moving], self.moving_shapes)
        t = pb.frame_times[index] if time is None else time
        over, over_mask, over_box = self._overlays(index % pb.frames.shape[0], float(t))
        bodies = _items_box(items)
        if self._canvas is None or self._small is None:
            self._canvas, _ = p.canvas()
            self._small = p.finish(self._canvas)
            self._changed = self._whole()
        changed = _union(_union(self._changed, self._bodies_box), bodies)
        self._changed, self._bodies_box = None, bodies
        box = _even_box(changed, self._canvas.size) if changed is not None else None
        if box is not None:
            # Inside ``box``: white, every body back to front, the overlays — what a whole
            # canvas would hold there. Outside it the canvas is stale, but never read.
            image = self._canvas
            image.paste((255, 255, 255), box)
            p.draw_items(ImageDraw.Draw(image), items + self.static_items)
            paste_layer(image, over, over_mask, _intersection(over_box, box))
            s = SUPERSAMPLE
            self._small.paste(p.finish_part(image, box), (box[0] // s, box[1] // s))
        out, at = _place(self._small, into)
        for label in self.labels:
            label.paste(out, at)
        clock_text = f"t = {t if clock is None else clock:.2f} s"
        p.text(out, (at[0] + p.size[0] - 4, at[1] + 4), clock_text, TEXT_PX, "ra")
        return out


def _place(
    panel: Image.Image, into: tuple[Image.Image, tuple[int, int]] | None
) -> tuple[Image.Image, tuple[int, int]]:
    """The image a finished ``panel`` is drawn on and the panel's pixel offset there: a copy
    of it, or ``into = (image, (x, y))`` with the panel pasted at ``(x, y)``."""
    if into is None:
        return panel.copy(), (0, 0)
    image, at = into
    image.paste(panel, at)
    return image, at


def _box(points: NDArray[np.float64], margin: float) -> tuple[int, int, int, int] | None:
    """The integer pixel box (left, top, right, bottom) around ``points`` (n, 2), widened by
    ``margin`` pixels; None for no points."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if pts.shape[0] == 0:
        return None
    lo = np.floor(pts.min(axis=0) - margin).astype(int)
    hi = np.ceil(pts.max(axis=0) + margin).astype(int) + 1
    return (int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1]))


def _union(
    a: tuple[int, int, int, int] | None, b: tuple[int, int, int, int] | None
) -> tuple[int, int, int, int] | None:
    if a is None or b is None:
        return a if b is None else b
    return (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))


def _intersection(
    a: tuple[int, int, int, int] | None, b: tuple[int, int, int, int]
) -> tuple[int, int, int, int] | None:
    if a is None:
        return None
    out = (max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3]))
    return out if out[0] < out[2] and out[1] < out[3] else None


def _even_box(
    box: tuple[int, int, int, int], size: tuple[int, int]
) -> tuple[int, int, int, int] | None:
    """``box`` clipped to a canvas of ``size`` and widened to multiples of
    :data:`SUPERSAMPLE`, so that its reduction is exactly that part of the reduced canvas
    (None if nothing is left)."""
    s = SUPERSAMPLE
    w, h = size
    x0, y0 = max(0, box[0]) // s * s, max(0, box[1]) // s * s
    x1, y1 = min(w, -(-box[2] // s) * s), min(h, -(-box[3] // s) * s)
    return (x0, y0, x1, y1) if x0 < x1 and y0 < y1 else None


def _items_box(items: Sequence[tuple]) -> tuple[int, int, int, int] | None:
    """The pixel box that draw items (:meth:`Painter.body_items`) paint, with a margin for
    their outlines and edges (None for no items)."""
    if not items:
        return None
    pts, margins = [], []
    for _, _, geom, radius, _, _ in items:
        g = np.asarray(geom, dtype=np.float64).reshape(-1, 2)
        pts.append(g)
        margins.append(np.full(g.shape[0], radius + 4.0))
    p, m = np.concatenate(pts), np.concatenate(margins)[:, None]
    keep = np.isfinite(p).all(axis=1)
    if not keep.any():
        return None
    lo = np.floor((p[keep] - m[keep]).min(axis=0)).astype(int)
    hi = np.ceil((p[keep] + m[keep]).max(axis=0)).astype(int) + 1
    return (int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1]))


def paste_layer(image: Image.Image, layer: Image.Image, mask: Image.Image, box: Any) -> None:
    """Copy the pixels of ``layer`` (the size of ``image``) that ``mask`` (mode 1 or L, the
    same size) holds onto ``image`` within ``box`` (left, top, right, bottom pixels; None:
    nothing to composite): the same pixels as the whole layer pasted through the mask, at
    the cost of the box."""
    if box is None:
        return
    w, h = image.size
    box = (max(0, box[0]), max(0, box[1]), min(w, box[2]), min(h, box[3]))
    if box[0] >= box[2] or box[1] >= box[3]:
        return
    image.paste(layer.crop(box), box[:2], mask.crop(box))


def _check_size(size: tuple[int, int]) -> tuple[int, int]:
    w, h = (int(v) for v in size)
    if w < 64 or h < 64:
        raise ValueError(f"size must be at least (64, 64) pixels, got {size}")
    return w, h


def render_png(
    playback: Playback,
    path: str | Path,
    frame: int = -1,
    *,
    size: tuple[int, int] = (480, 480),
    camera: Camera | None = None,
    title: str | None = None,
) -> Path:
    """Write one frame (index into ``playback.frame_times``; default the last) as a PNG.

    ``size`` in pixels. Returns the path written (parent folders are created).
    """
    n = playback.frames.shape[0]
    if not -n <= frame < n:
        raise ValueError(f"frame must index one of the {n} stored frames, got {frame}")
    out = Path(path)
    drawer = PlaybackDrawer(playback, camera or Camera(), _check_size(size), title)
    out.parent.mkdir(parents=True, exist_ok=True)
    drawer.draw(frame % n).save(out, format="PNG")
    return out


def render_gif(
    playback: Playback,
    path: str | Path,
    fps: float | None = None,
    *,
    size: tuple[int, int] = (480, 480),
    camera: Camera | None = None,
    title: str | None = None,
    png_dir: str | Path | None = None,
) -> Path:
    """Write an animated GIF of the playback: one image per stored frame, looping.

    ``fps`` (Hz) is the GIF's frame rate; by default ``playback.render_fps``, i.e. real time
    (GIF delays are whole centiseconds). With ``png_dir`` every frame is also written there as
    ``frame_0000.png``, .... Returns the path written (parent folders are created); the GIF
    is written atomically.
    """
    from visprim.sim.video import write_video

    rate = playback.render_fps if fps is None else float(fps)
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"fps must be > 0 Hz, got {fps}")
    drawer = PlaybackDrawer(playback, camera or Camera(), _check_size(size), title)
    frames_dir = Path(png_dir) if png_dir is not None else None
    if frames_dir is not None:
        frames_dir.mkdir(parents=True, exist_ok=True)

    def frames() -> Iterable[Image.Image]:
        for i in range(playback.frames.shape[0]):
            image = drawer.draw(i)
            if frames_dir is not None:
                image.save(frames_dir / f"frame_{i:04d}.png", format="PNG")
            yield image

    out = Path(path)
    if out.suffix.lower() != ".gif":
        raise ValueError(f"render_gif writes .gif files, got {out.name!r}")
    return write_video(out, frames(), rate)
