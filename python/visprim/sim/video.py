"""Writing frames as a video file, the format from the extension, atomically.

* ``.gif``: Pillow (core dependency), looping; frame delays are whole centiseconds. Frames
  are reduced to one shared 255-colour palette (taken from the first frame, plus pure
  white) without dithering, which keeps encoding fast and the colours stable.
* ``.mp4``: H.264 through ``imageio-ffmpeg``, a wheel that ships its own ffmpeg binary
  (the optional extra ``pip install visprim[video]``); yuv420p, so width and height are
  rounded up to even numbers by padding.

Any other extension is refused with a message naming the supported ones. The file is written
under a temporary name in the target's folder and renamed over the target at the end
(:func:`os.replace`), so a failure never leaves a half-written video.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from PIL import Image

#: Supported extensions → what writes them.
VIDEO_FORMATS: dict[str, str] = {".gif": "Pillow", ".mp4": "imageio-ffmpeg (visprim[video])"}


def check_video_path(path: str | Path) -> Path:
    """``path`` as a Path if its extension is a supported video format, else ValueError
    (and ImportError for ``.mp4`` without imageio-ffmpeg)."""
    out = Path(path)
    ext = out.suffix.lower()
    if ext not in VIDEO_FORMATS:
        raise ValueError(
            f"{out}: unsupported video format {out.suffix or '(no extension)'!r}; use "
            + " or ".join(f"{e} ({w})" for e, w in VIDEO_FORMATS.items())
        )
    if ext == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise ImportError(
                f"{out}: writing .mp4 needs imageio-ffmpeg: pip install 'visprim[video]' "
                "(or write a .gif)"
            ) from None
    return out


def _gif(tmp: Path, frames: Iterable[Image.Image], fps: float) -> int:
    it = iter(frames)
    first = next(it, None)
    if first is None:
        raise ValueError("write_video: no frames to write")
    palette = first.quantize(colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)

    def quantized() -> Iterable[Image.Image]:
        yield palette
        for im in it:
            yield im.quantize(palette=palette, dither=Image.Dither.NONE)

    images = list(quantized())
    duration = max(10, int(round(1000.0 / fps / 10.0)) * 10)
    images[0].save(
        tmp, format="GIF", save_all=True, append_images=images[1:], duration=duration, loop=0
    )
    return len(images)


def _mp4(tmp: Path, frames: Iterable[Image.Image], fps: float) -> int:
    import imageio_ffmpeg

    writer = None
    n = 0
    try:
        for im in frames:
            a = np.asarray(im.convert("RGB"))
            h, w = a.shape[:2]
            if h % 2 or w % 2:
                a = np.pad(a, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
            if writer is None:
                writer = imageio_ffmpeg.write_frames(
                    str(tmp),
                    (a.shape[1], a.shape[0]),
                    fps=fps,
                    codec="libx264",
                    pix_fmt_out="yuv420p",
                    macro_block_size=1,
                    output_params=["-f", "mp4"],
                )
                writer.send(None)
            writer.send(np.ascontiguousarray(a))
            n += 1
        if writer is None:
            raise ValueError("write_video: no frames to write")
    finally:
        if writer is not None:
            writer.close()
    return n


def _usual_mode(path: Path) -> None:
    """Give ``path`` (made 0600 by :func:`tempfile.mkstemp`) the mode a new file gets."""
    umask = os.umask(0o022)
    os.umask(umask)
    os.chmod(path, 0o666 & ~umask)


def write_video(path: str | Path, frames: Iterable[Image.Image], fps: float) -> Path:
    """Write ``frames`` (RGB images of one size) at ``fps`` Hz to ``path`` (.gif or .mp4),
    atomically. Returns the path. Parent folders are created."""
    out = check_video_path(path)
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be > 0 Hz, got {fps}")
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{out.stem}.", suffix=out.suffix, dir=out.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        if out.suffix.lower() == ".gif":
            _gif(tmp, frames, float(fps))
        else:
            _mp4(tmp, frames, float(fps))
        _usual_mode(tmp)
        os.replace(tmp, out)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return out
