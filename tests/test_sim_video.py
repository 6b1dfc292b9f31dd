"""Video files: format from the extension, refused formats, atomic writes."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from visprim.sim.video import check_video_path, write_video


def _frames(n: int = 5, size: tuple[int, int] = (65, 48)) -> list[Image.Image]:
    out = []
    for i in range(n):
        a = np.full((size[1], size[0], 3), 255, dtype=np.uint8)
        a[:, i * 10 : i * 10 + 8] = (200, 30, 30)
        out.append(Image.fromarray(a))
    return out


def test_gif_frames_and_timing(tmp_path) -> None:
    path = write_video(tmp_path / "a" / "v.gif", _frames(), 25.0)
    with Image.open(path) as im:
        assert im.n_frames == 5 and im.info["duration"] == 40
        im.seek(3)
        a = np.asarray(im.convert("RGB"))
    assert tuple(a[10, 32]) == (200, 30, 30) and tuple(a[10, 0]) == (255, 255, 255)
    assert [p.name for p in path.parent.iterdir()] == ["v.gif"]


def test_mp4_through_imageio_ffmpeg(tmp_path) -> None:
    pytest.importorskip("imageio_ffmpeg")
    path = write_video(tmp_path / "v.mp4", _frames(), 25.0)
    data = path.read_bytes()
    assert data[4:8] == b"ftyp" and len(data) > 500
    assert [p.name for p in tmp_path.iterdir()] == ["v.mp4"]


def test_other_formats_are_refused_before_writing(tmp_path) -> None:
    for name in ("v.avi", "v.webm", "v"):
        with pytest.raises(ValueError, match=r"unsupported video format.*\.gif.*\.mp4"):
            check_video_path(tmp_path / name)
        with pytest.raises(ValueError, match="unsupported video format"):
            write_video(tmp_path / name, _frames(), 25.0)
    assert not list(tmp_path.iterdir())


def test_failure_leaves_no_file(tmp_path) -> None:
    def broken():
        yield from _frames(2)
        raise RuntimeError("renderer failed")

    with pytest.raises(RuntimeError, match="renderer failed"):
        write_video(tmp_path / "v.gif", broken(), 25.0)
    assert not list(tmp_path.iterdir())
    with pytest.raises(ValueError, match="no frames"):
        write_video(tmp_path / "v.gif", [], 25.0)
    assert not list(tmp_path.iterdir())
