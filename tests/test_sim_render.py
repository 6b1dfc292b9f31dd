"""Headless rendering of a playback: GIF frame count, moving body, PNG size."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from visprim.sim.playback import play
from visprim.sim.render import Camera, render_gif, render_png
from visprim.sim.trajectories import minimum_jerk

SIZE = (160, 160)


@pytest.fixture(scope="module")
def playback():
    postures = np.array([[0.0, 0.3, 0.0, 0.3], [0.5, 1.6, 0.3, 1.2]])
    times, angles = minimum_jerk(postures, [0.6])
    return play(times, angles, render_fps=10.0)


def _frames(path) -> list[np.ndarray]:
    out = []
    with Image.open(path) as im:
        for i in range(im.n_frames):
            im.seek(i)
            out.append(np.asarray(im.convert("RGB"), dtype=np.int16))
    return out


def test_gif_has_one_frame_per_stored_frame_and_the_body_moves(playback, tmp_path) -> None:
    path = render_gif(playback, tmp_path / "sub" / "reach.gif", size=SIZE, title="reach")
    assert path.is_file()
    frames = _frames(path)
    assert len(frames) == playback.frames.shape[0] == 7  # t = 0, 0.1, ..., 0.6 s at 10 Hz
    assert frames[0].shape == (SIZE[1], SIZE[0], 3)
    with Image.open(path) as im:
        assert im.info["duration"] == 100  # 10 fps, real time
        assert im.info.get("loop") == 0
    changed = np.abs(frames[0] - frames[-1]).sum(axis=2) > 60
    # The arm sweeps a visible area, not just the clock text in the corner.
    assert changed.mean() > 0.01
    assert changed[SIZE[1] // 4 :, :].sum() > 100
    for a, b in zip(frames[:-1], frames[1:], strict=True):
        assert np.any(a != b)


def test_gif_fps_and_png_frames(playback, tmp_path) -> None:
    path = render_gif(playback, tmp_path / "fast.gif", fps=50, size=SIZE, png_dir=tmp_path / "f")
    with Image.open(path) as im:
        assert im.info["duration"] == 20
    pngs = sorted((tmp_path / "f").glob("frame_*.png"))
    assert len(pngs) == playback.frames.shape[0]


def test_png_single_frame(playback, tmp_path) -> None:
    first = render_png(playback, tmp_path / "first.png", 0, size=(200, 120))
    last = render_png(playback, tmp_path / "last.png", size=(200, 120), camera=Camera(azimuth=0))
    for p in (first, last):
        with Image.open(p) as im:
            assert im.format == "PNG" and im.size == (200, 120)
    a = np.asarray(Image.open(first).convert("RGB"))
    b = np.asarray(Image.open(last).convert("RGB"))
    assert np.any(a != b)


def test_render_rejects_bad_arguments(playback, tmp_path) -> None:
    with pytest.raises(ValueError, match="frame"):
        render_png(playback, tmp_path / "x.png", frame=playback.frames.shape[0])
    with pytest.raises(ValueError, match="fps"):
        render_gif(playback, tmp_path / "x.gif", fps=0)
    with pytest.raises(ValueError, match="size"):
        render_png(playback, tmp_path / "x.png", size=(10, 10))
