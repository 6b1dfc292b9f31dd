"""The RGB -> YUV 4:2:0 conversion of MP4 frames, against ffmpeg's own, and the colours of
an MP4 decoded back."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest
from PIL import Image
from visprim import _visprim
from visprim.sim.video import write_video, yuv420


def _blocky(w: int, h: int, seed: int, side: int = 16) -> np.ndarray:
    """Random colours constant on ``side`` x ``side`` blocks."""
    rng = np.random.default_rng(seed)
    blocks = rng.integers(0, 256, size=(h // side, w // side, 3), dtype=np.uint8)
    return np.ascontiguousarray(blocks.repeat(side, axis=0).repeat(side, axis=1))


def _ffmpeg(args: list[str], data: bytes) -> bytes:
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    exe = imageio_ffmpeg.get_ffmpeg_exe()
    run = subprocess.run([exe, "-loglevel", "error", *args], input=data, capture_output=True)
    assert run.returncode == 0, run.stderr.decode(errors="replace")
    return run.stdout


def test_planes_match_ffmpegs_conversion() -> None:
    """Luma everywhere; chroma inside each block, where ffmpeg's filtered subsampling and
    visprim's 2 x 2 mean both see one colour."""
    w, h = 64, 48
    rgb = _blocky(w, h, 1)
    ours = yuv420(Image.fromarray(rgb))
    theirs = np.frombuffer(
        _ffmpeg(
            ["-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{w}x{h}", "-i", "-"]
            + ["-pix_fmt", "yuv420p", "-f", "rawvideo", "-"],
            rgb.tobytes(),
        ),
        dtype=np.uint8,
    )
    assert ours.dtype == np.uint8 and ours.shape == theirs.shape == (w * h * 3 // 2,)
    diff = np.abs(ours.astype(int) - theirs.astype(int))
    assert diff[: w * h].max() <= 1  # Y
    for plane in diff[w * h :].reshape(2, h // 16, 8, w // 16, 8):  # U, V: 8 x 8 a block
        assert plane[:, 2:6, :, 2:6].max() <= 1


def test_bytes_and_image_paths_agree_and_odd_sizes_repeat_the_edge() -> None:
    rgb = np.random.default_rng(2).integers(0, 256, size=(7, 9, 3), dtype=np.uint8)
    image = Image.fromarray(rgb)
    a = yuv420(image)
    assert np.array_equal(a, _visprim.rgb_to_yuv420(rgb.tobytes(), 9, 7))
    padded = np.pad(rgb, ((0, 1), (0, 1), (0, 0)), mode="edge")
    assert np.array_equal(a, _visprim.rgb_to_yuv420(padded.tobytes(), 10, 8))
    with pytest.raises(ValueError, match=r"9 x 7 frame has 189 \(RGB\) or 252 \(RGBX\) bytes"):
        _visprim.rgb_to_yuv420(rgb.tobytes()[:-1], 9, 7)


def test_mp4_decodes_to_the_frames_colours(tmp_path) -> None:
    w, h = 96, 64
    frames = [Image.fromarray(_blocky(w, h, s, 2)) for s in range(3)]
    # Flat colours (x264 keeps them well at its default quality), one per quadrant.
    flat = np.zeros((h, w, 3), dtype=np.uint8)
    colours = [(200, 60, 30), (30, 160, 220), (250, 250, 250), (20, 20, 20)]
    for i, c in enumerate(colours):
        flat[(i // 2) * h // 2 : (i // 2 + 1) * h // 2, (i % 2) * w // 2 : (i % 2 + 1) * w // 2] = c
    frames = [Image.fromarray(flat)] * 3 + frames[:1]
    path = write_video(tmp_path / "v.mp4", frames, 25.0)
    decoded = _ffmpeg(
        ["-i", str(path), "-frames:v", "1", "-f", "rawvideo", "-pix_fmt", "rgb24", "-"], b""
    )
    back = np.frombuffer(decoded, dtype=np.uint8).reshape(h, w, 3)
    for i, c in enumerate(colours):
        y, x = (i // 2) * h // 2 + h // 4, (i % 2) * w // 2 + w // 4
        assert np.abs(back[y, x].astype(int) - c).max() <= 4, (c, back[y, x])
    info = subprocess.run(
        [pytest.importorskip("imageio_ffmpeg").get_ffmpeg_exe(), "-i", str(path)],
        capture_output=True,
        text=True,
    ).stderr
    assert "yuv420p(tv, smpte170m" in info, info
