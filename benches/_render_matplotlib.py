"""Reference for bench_imitate.py: the matplotlib renderer visprim used before the PIL one
(python/visprim/sim/render.py at commit 4807ba5, unchanged below this docstring apart from
this note), kept only to time both in the same run."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon
from numpy.typing import ArrayLike, NDArray
from PIL import Image
from visprim.sim.playback import Playback

matplotlib.rcParams["path.simplify"] = False

_BOX_FACES = (  # corner indices (bit 0: +x, bit 1: +y, bit 2: +z), outward normal
    ((0, 2, 6, 4), (-1, 0, 0)),
    ((1, 5, 7, 3), (1, 0, 0)),
    ((0, 4, 5, 1), (0, -1, 0)),
    ((2, 3, 7, 6), (0, 1, 0)),
    ((0, 1, 3, 2), (0, 0, -1)),
    ((4, 6, 7, 5), (0, 0, 1)),
)
_CORNERS = np.array([[(i >> b) & 1 for b in range(3)] for i in range(8)], dtype=np.float64) - 0.5


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


class _Painter:
    """Draws one frame into an Axes covering the whole figure."""

    def __init__(self, camera: Camera, size: tuple[int, int], dpi: float) -> None:
        self.camera = camera
        self.right, self.up, self.back = camera.basis()
        self.light = self.back * 0.6 + self.up * 0.8
        self.light /= np.linalg.norm(self.light)
        w, h = size
        centre = np.array([self.right, self.up]) @ np.asarray(camera.target)
        self.px_per_m = min(w, h) / (2.0 * camera.extent)
        half = np.array([w, h]) / (2.0 * self.px_per_m)
        self.xlim = (centre[0] - half[0], centre[0] + half[0])
        self.ylim = (centre[1] - half[1], centre[1] + half[1])
        self.pt_per_m = self.px_per_m * 72.0 / dpi

    def project(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        p = np.asarray(points, dtype=np.float64)
        return np.stack([p @ self.right, p @ self.up], axis=-1)

    def depth(self, point: NDArray[np.float64]) -> float:
        return float(np.asarray(point) @ self.back)

    def shade(self, color: ArrayLike, normal: NDArray[np.float64]) -> NDArray[np.float64]:
        brightness = 0.55 + 0.45 * max(0.0, float(normal @ self.light))
        return np.clip(np.asarray(color) * brightness, 0.0, 1.0)

    def body_items(self, transform: NDArray[np.float64], shapes: Sequence, items: list) -> None:
        rot, pos = transform[:3, :3], transform[:3, 3]
        for spec in shapes:
            centre = rot @ np.asarray(spec.centre) + pos
            color = np.asarray(spec.color)
            if spec.kind == "capsule":
                r, h = spec.size
                axis = rot[:, 2] * (h / 2.0)
                ends = self.project(np.stack([centre - axis, centre + axis]))
                width = 2.0 * r * self.pt_per_m
                items.append((self.depth(centre), "capsule", ends, width, color))
            elif spec.kind == "sphere":
                (r,) = spec.size
                items.append((self.depth(centre), "sphere", self.project(centre), r, color))
            else:
                corners = (rot @ (_CORNERS * np.asarray(spec.size)).T).T + centre
                for idx, normal in _BOX_FACES:
                    n = rot @ np.asarray(normal, dtype=np.float64)
                    if n @ self.back <= 1e-9:
                        continue
                    face = corners[list(idx)]
                    items.append(
                        (
                            self.depth(face.mean(axis=0)),
                            "face",
                            self.project(face),
                            None,
                            self.shade(color, n),
                        )
                    )

    def draw(self, ax: Axes, items: list) -> None:
        for z, (_, kind, geom, size, color) in enumerate(sorted(items, key=lambda it: it[0])):
            zorder = 2 + z * 0.01
            edge = np.clip(np.asarray(color) * 0.55, 0, 1)
            if kind == "capsule":
                ax.plot(
                    geom[:, 0],
                    geom[:, 1],
                    color=edge,
                    lw=size + 1.6,
                    solid_capstyle="round",
                    zorder=zorder,
                )
                ax.plot(
                    geom[:, 0],
                    geom[:, 1],
                    color=color,
                    lw=size,
                    solid_capstyle="round",
                    zorder=zorder + 0.001,
                )
            elif kind == "sphere":
                ax.add_patch(
                    Circle(
                        tuple(geom), size, facecolor=color, edgecolor=edge, lw=0.8, zorder=zorder
                    )
                )
            else:
                ax.add_patch(
                    Polygon(
                        geom, closed=True, facecolor=color, edgecolor=edge, lw=0.6, zorder=zorder
                    )
                )


def _frame_drawer(
    playback: Playback, camera: Camera, size: tuple[int, int], dpi: float, title: str | None
) -> tuple[Figure, Callable[[int], None]]:
    fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    painter = _Painter(camera, size, dpi)
    ref_2d = painter.project(playback.hand_reference)
    via_2d = painter.project(playback.hand_via)
    path_2d = painter.project(playback.hand_path)
    footer = (
        f"RMS {playback.rms_error_deg:.1f}°  max {playback.max_error_deg:.1f}°  "
        f"{playback.completion_time:.2f} s / {playback.movement_duration:.2f} s  "
        f"via {playback.n_reached}/{playback.n_via}"
    )

    def draw(index: int) -> None:
        ax.clear()
        ax.set_xlim(*painter.xlim)
        ax.set_ylim(*painter.ylim)
        ax.set_aspect("equal")
        ax.axis("off")
        fig.set_facecolor("white")
        items: list = []
        for tf, shapes in zip(playback.frames[index], playback.body_shapes, strict=True):
            painter.body_items(tf, shapes, items)
        painter.draw(ax, items)
        t = playback.frame_times[index]
        top = 1000.0
        ax.plot(
            ref_2d[:, 0], ref_2d[:, 1], ls=(0, (3, 2)), lw=1.2, color=(0.20, 0.35, 0.85), zorder=top
        )
        reached = np.nan_to_num(playback.via_reach_times, nan=np.inf) <= t + 1e-9
        ax.scatter(
            via_2d[:, 0],
            via_2d[:, 1],
            s=14,
            zorder=top + 1,
            facecolors=np.where(reached[:, None], [(0.1, 0.65, 0.2)], [(1.0, 1.0, 1.0)]),
            edgecolors=(0.1, 0.45, 0.15),
            linewidths=0.8,
        )
        ax.plot(
            path_2d[: index + 1, 0],
            path_2d[: index + 1, 1],
            lw=1.6,
            color=(0.90, 0.40, 0.05),
            zorder=top + 2,
        )
        if title:
            ax.text(0.02, 0.98, title, transform=ax.transAxes, va="top", ha="left", fontsize=9)
        ax.text(
            0.98,
            0.98,
            f"t = {t:.2f} s",
            transform=ax.transAxes,
            va="top",
            ha="right",
            fontsize=9,
            family="monospace",
        )
        ax.text(
            0.5,
            0.015,
            footer,
            transform=ax.transAxes,
            va="bottom",
            ha="center",
            fontsize=7.5,
            color=(0.2, 0.2, 0.2),
            zorder=top + 3,
            bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.85, "pad": 2},
        )

    return fig, draw


def _to_image(fig: Figure) -> Image.Image:
    canvas = fig.canvas
    canvas.draw()
    rgba = np.asarray(canvas.buffer_rgba())  # type: ignore[attr-defined]
    return Image.fromarray(rgba[..., :3].copy())


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
    dpi: float = 100.0,
) -> Path:
    """Write one frame (index into ``playback.frame_times``; default the last) as a PNG.

    ``size`` in pixels. Returns the path written (parent folders are created).
    """
    n = playback.frames.shape[0]
    if not -n <= frame < n:
        raise ValueError(f"frame must index one of the {n} stored frames, got {frame}")
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig, draw = _frame_drawer(playback, camera or Camera(), _check_size(size), dpi, title)
    draw(frame % n)
    _to_image(fig).save(out, format="PNG")
    return out


def render_gif(
    playback: Playback,
    path: str | Path,
    fps: float | None = None,
    *,
    size: tuple[int, int] = (480, 480),
    camera: Camera | None = None,
    title: str | None = None,
    dpi: float = 100.0,
    png_dir: str | Path | None = None,
) -> Path:
    """Write an animated GIF of the playback: one image per stored frame, looping.

    ``fps`` (Hz) is the GIF's frame rate; by default ``playback.render_fps``, i.e. real time
    (GIF delays are whole centiseconds). With ``png_dir`` every frame is also written there as
    ``frame_0000.png``, .... Returns the path written (parent folders are created).
    """
    rate = playback.render_fps if fps is None else float(fps)
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"fps must be > 0 Hz, got {fps}")
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    frames_dir = Path(png_dir) if png_dir is not None else None
    if frames_dir is not None:
        frames_dir.mkdir(parents=True, exist_ok=True)
    fig, draw = _frame_drawer(playback, camera or Camera(), _check_size(size), dpi, title)
    images = []
    for i in range(playback.frames.shape[0]):
        draw(i)
        image = _to_image(fig)
        if frames_dir is not None:
            image.save(frames_dir / f"frame_{i:04d}.png", format="PNG")
        images.append(image.convert("P", palette=Image.Palette.ADAPTIVE, colors=128))
    duration = max(10, int(round(1000.0 / rate / 10.0)) * 10)
    images[0].save(
        out, format="GIF", save_all=True, append_images=images[1:], duration=duration, loop=0
    )
    return out
