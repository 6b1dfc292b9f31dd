"""Writing frames as a video file, the format from the extension, atomically.

* ``.gif``: a Rust encoder (:class:`visprim._visprim.GifFrames`) writes each frame as it
  comes, so memory holds a few frames whatever the length. Looping; frame delays are whole
  centiseconds. Frames are reduced to one shared 255-colour palette (median cut of the first
  frame), each pixel to its nearest palette colour as Pillow's ``quantize(palette=…)`` does,
  without dithering, which keeps encoding fast and the colours stable. After the first,
  a frame is only the rectangle of pixels whose colour changed (unchanged pixels inside it
  transparent over the kept previous frame), the standard GIF optimisation: a decoder shows
  the same pictures, from a file a fraction of the size. The encoding runs without the GIL,
  alongside the thread drawing the next frame.
* ``.mp4``: H.264 by the ffmpeg binary of ``imageio-ffmpeg``, a wheel that ships it (the
  optional extra ``pip install visprim[video]``), run as a process of visprim's own that
  is killed and waited for on any error. Frames are converted to YUV 4:2:0
  (BT.601, studio range, tagged as such) in Rust, beside the drawing thread, and piped to
  ffmpeg as they are, which halves the bytes piped and spares ffmpeg its own conversion;
  width and height are rounded up to even numbers by repeating the last column and row.

Frames are drawn in a second thread while the first encodes (:func:`prefetched`, a queue
of :data:`PREFETCH` frames), so drawing and encoding share the machine's cores and memory
still holds a few frames. Any other extension is refused with a message naming the
supported ones. The file is written under a temporary name in the target's folder and
renamed over the target at the end (:func:`os.replace`), so a failure never leaves a
half-written video.
"""

from __future__ import annotations

import functools
import itertools
import queue
import shutil
import struct
import subprocess
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from fractions import Fraction
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from PIL import Image

from visprim import _visprim
from visprim.atomic import atomic_file

T = TypeVar("T")

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


def default_video_name(stem: str) -> tuple[str, str | None]:
    """``stem.mp4`` when imageio-ffmpeg is installed, else ``stem.gif`` with the reason (one
    line to show the user)."""
    try:
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        return (
            f"{stem}.gif",
            f"imageio-ffmpeg is not installed (pip install 'visprim[video]'): writing "
            f"{stem}.gif instead of {stem}.mp4",
        )
    return f"{stem}.mp4", None


def palette_lut(palette: Image.Image) -> bytes:
    """The colour lookup table of the palette image ``palette`` for
    :class:`visprim._visprim.GifFrames`: the index Pillow's ``quantize(palette=palette,
    dither=NONE)`` gives each colour, one entry per cell of 4 × 4 × 4 colour values (Pillow
    looks colours up in cells of that size, so the table reproduces its indices exactly).
    262,144 bytes."""
    k = np.arange(64**3, dtype=np.uint32)
    cells = np.stack([(k & 63) << 2, ((k >> 6) & 63) << 2, (k >> 12) << 2], axis=-1)
    probe = Image.fromarray(cells.astype(np.uint8).reshape(512, 512, 3))
    return probe.quantize(palette=palette, dither=Image.Dither.NONE).tobytes()


class _GifPalette:
    """The palette every frame of a GIF is reduced to: 255 colours by median cut of its
    first frame (``table``: the colours, 3 bytes each; ``lut``: :func:`palette_lut`)."""

    def __init__(self, first: Image.Image) -> None:
        palette = first.quantize(
            colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
        )
        self.size = first.size
        self.table = bytes(palette.getpalette() or [])[: 3 * 255]
        self.lut = palette_lut(palette)

    def header(self) -> bytes:
        """Header, logical screen with a 256-colour global table (the palette, then unused
        entries; the last index is the transparent one), loop forever (NETSCAPE2.0)."""
        w, h = self.size
        return (
            b"GIF89a"
            + struct.pack("<HHBBB", w, h, 0xF7, 0, 0)
            + self.table.ljust(768, b"\x00")
            + b"!\xff\x0bNETSCAPE2.0\x03\x01\x00\x00\x00"
        )


def _gif_frames(fh: Any, palette: _GifPalette, frames: Iterable[Image.Image], fps: float) -> int:
    """Write the blocks of ``frames`` to ``fh``: the first whole, each after it the
    rectangle that changed. Returns the number of frames."""
    centis = max(1, int(round(1000.0 / fps / 10.0)))
    encoder = _visprim.GifFrames(*palette.size, palette.lut)
    n = 0
    for im in frames:
        if im.size != palette.size:
            raise ValueError(f"write_video: frame {n} is {im.size}, the first {palette.size}")
        rgb = im if im.mode == "RGB" else im.convert("RGB")
        try:  # the image's own memory (Arrow C data interface), no copy
            blocks, _ = encoder.frame_arrow(*rgb.__arrow_c_array__(), centis)
        except (AttributeError, ValueError):  # an older Pillow, or not one block
            blocks, _ = encoder.frame(rgb.tobytes("raw", "RGBX"), centis)
        fh.write(blocks)
        n += 1
    return n


def _gif(tmp: Path, frames: Iterable[Image.Image], fps: float) -> int:
    """Write the GIF one frame at a time (memory: a few frames), every frame reduced to the
    first frame's palette; after the first, each frame is the rectangle that changed."""
    it = iter(frames)
    first = next(it, None)
    if first is None:
        raise ValueError("write_video: no frames to write")
    palette = _GifPalette(first)
    with open(tmp, "wb") as fh:
        fh.write(palette.header())
        n = _gif_frames(fh, palette, itertools.chain([first], it), fps)
        fh.write(b";")
    return n


#: x264's speed preset for MP4 videos. "veryfast" spends less encoder time than the default
#: ("medium"), for a larger file at the same quality setting; the encoder shares the cores
#: with the drawing (a 5-minute imitation: 103 -> 80 s of CPU, docs/imitation.rst).
MP4_PRESET = "veryfast"

#: x264 encodes in one thread. Its own choice (about 1.5 threads a core, and lookahead
#: threads) takes the cores from the thread drawing the frames, the critical path of a
#: long imitation on a small machine (docs/imitation.rst).
MP4_THREADS = ["-threads", "1"]

#: How the YUV frames handed to x264 are tagged: BT.601 coefficients (``smpte170m``), studio
#: range (``tv``), what :func:`yuv420` computes, so players turn them back into the same RGB.
MP4_COLOUR = ["-colorspace", "smpte170m", "-color_range", "tv"]


def yuv420(image: Image.Image) -> np.ndarray:
    """The ``yuv420p`` planes of an RGB image (uint8, 1-D: Y, U, V), converted in Rust with
    the GIL released (:func:`visprim._visprim.rgb_to_yuv420`): BT.601 studio range, odd
    sizes rounded up to even by repeating the last column and row. ffmpeg then encodes the
    planes as they are, without converting the colours itself."""
    w, h = image.size
    try:  # the image's own memory (Arrow C data interface), no copy
        return _visprim.rgb_to_yuv420_arrow(*image.__arrow_c_array__(), w, h)
    except (AttributeError, ValueError):  # an older Pillow, or not one block
        return _visprim.rgb_to_yuv420(image.tobytes(), w, h)


def _yuv_frames(
    frames: Iterable[Image.Image],
) -> Iterator[tuple[tuple[int, int], np.ndarray]]:
    """Each frame's size (pixels) and :func:`yuv420` planes. The conversion runs here, in
    the thread that feeds the encoder, beside the thread drawing the next frame (which is
    the critical path)."""
    for im in frames:
        rgb = im if im.mode == "RGB" else im.convert("RGB")
        yield rgb.size, yuv420(rgb)


#: x264's constant rate factor: imageio-ffmpeg's default quality (5 of 10).
MP4_CRF = 25


def _ffmpeg_command(path: Path, size: tuple[int, int], fps: float) -> list[str]:
    """The ffmpeg command reading raw yuv420p frames of ``size`` (even) from its stdin and
    writing H.264 to ``path`` (imageio-ffmpeg's ``write_frames`` command, with the settings
    above)."""
    import imageio_ffmpeg

    rate = str(Fraction(fps).limit_denominator())
    cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-f", "rawvideo", "-vcodec", "rawvideo"]
    cmd += ["-s", f"{size[0]}x{size[1]}", "-pix_fmt", "yuv420p", "-r", rate, *MP4_COLOUR]
    cmd += ["-i", "-", "-an", "-vcodec", "libx264", "-pix_fmt", "yuv420p"]
    cmd += ["-crf", str(MP4_CRF), "-v", "warning", "-f", "mp4", "-preset", MP4_PRESET]
    return [*cmd, *MP4_THREADS, *MP4_COLOUR, str(path)]


def _mp4(tmp: Path, frames: Iterable[tuple[tuple[int, int], np.ndarray]], fps: float) -> int:
    """Write ``(size, yuv420p planes)`` frames (:func:`_yuv_frames`) as H.264.

    ffmpeg is this function's own process: it is started with a worker's stop deferred
    (:func:`visprim.sim.frame_workers.stop_deferred`), so it is never left running unowned,
    and on any error or stop it is killed and waited for before the error propagates, so
    it cannot write ``tmp`` after its owner has cleaned up."""
    from visprim.sim.frame_workers import stop_deferred

    proc: subprocess.Popen[bytes] | None = None
    size = (0, 0)
    n = 0
    try:
        for frame_size, planes in frames:
            if proc is None:
                size = frame_size
                with stop_deferred():
                    proc = subprocess.Popen(
                        _ffmpeg_command(tmp, (size[0] + size[0] % 2, size[1] + size[1] % 2), fps),
                        stdin=subprocess.PIPE,
                        stdout=subprocess.DEVNULL,
                        start_new_session=True,  # a Ctrl-C is the parent's to handle
                    )
            elif frame_size != size:
                raise ValueError(f"write_video: frame {n} is {frame_size}, the first {size}")
            assert proc.stdin is not None
            try:
                proc.stdin.write(np.ascontiguousarray(planes).data)
            except BrokenPipeError:
                raise RuntimeError(
                    f"{tmp}: ffmpeg stopped at frame {n} (its message above)"
                ) from None
            n += 1
        if proc is None:
            raise ValueError("write_video: no frames to write")
        assert proc.stdin is not None
        proc.stdin.close()
        if proc.wait() != 0:
            raise RuntimeError(f"{tmp}: ffmpeg failed with exit code {proc.returncode}")
    finally:
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()
    return n


#: Frames drawn ahead of the encoder.
PREFETCH = 4


def prefetched(frames: Iterable[T], depth: int = PREFETCH) -> Iterator[T]:
    """``frames``, produced by a background thread up to ``depth`` ahead (memory: ``depth``
    frames). An exception in the producer is raised here; leaving the loop early (or an
    interrupt) stops the producer."""
    q: queue.Queue[tuple[str, Any]] = queue.Queue(maxsize=max(1, depth))
    stop = threading.Event()

    def put(item: tuple[str, Any]) -> bool:
        while not stop.is_set():
            try:
                q.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def produce() -> None:
        try:
            for frame in frames:
                if not put(("frame", frame)):
                    return
            put(("end", None))
        except BaseException as exc:  # handed to the consumer
            put(("error", exc))

    worker = threading.Thread(target=produce, name="visprim-frames", daemon=True)
    worker.start()
    try:
        while True:
            kind, value = q.get()
            if kind == "end":
                return
            if kind == "error":
                raise value
            yield value
    finally:
        stop.set()
        worker.join()


def write_video(path: str | Path, frames: Iterable[Image.Image], fps: float) -> Path:
    """Write ``frames`` (RGB images of one size) at ``fps`` Hz to ``path`` (.gif or .mp4),
    atomically. Returns the path. Parent folders are created."""
    out = check_video_path(path)
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be > 0 Hz, got {fps}")
    with atomic_file(out) as tmp:
        if out.suffix.lower() == ".gif":
            _gif(tmp, prefetched(frames), float(fps))
        else:
            _mp4(tmp, _yuv_frames(prefetched(frames)), float(fps))
    return out


def _join_mp4(parts: list[Path], out: Path) -> None:
    """Join MP4 ``parts`` (the same encoder settings) into ``out`` without re-encoding
    (ffmpeg's concat demuxer, streams copied)."""
    import imageio_ffmpeg

    listing = parts[0].with_name("parts.txt")
    quoted = ("'" + str(p.resolve()).replace("'", "'\\''") + "'" for p in parts)
    listing.write_text("".join(f"file {q}\n" for q in quoted), encoding="utf-8")
    try:
        cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-nostdin", "-f", "concat"]
        cmd += ["-safe", "0", "-i", str(listing), "-c", "copy", "-f", "mp4", "-y", str(out)]
        done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    finally:
        listing.unlink(missing_ok=True)
    if done.returncode != 0:
        why = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise RuntimeError(f"{out}: joining the video's parts failed: {why}")


def _write_part(
    tmp: Path,
    frame: Callable[[int], Image.Image],
    indices: range,
    fps: float,
    palette: _GifPalette | None,
) -> None:
    """One part of :func:`write_video_parts`: frames ``indices`` drawn (in a background
    thread) and encoded into ``tmp``: GIF blocks with ``palette``, or an MP4 without it."""
    frames = prefetched(frame(i) for i in indices)
    if palette is None:
        _mp4(tmp, _yuv_frames(frames), fps)
        return
    with open(tmp, "wb") as fh:
        _gif_frames(fh, palette, frames, fps)


def write_video_parts(
    path: str | Path,
    frame: Callable[[int], Image.Image],
    n_frames: int,
    fps: float,
    workers: int,
) -> Path:
    """Write ``frame(0) … frame(n_frames − 1)`` as :func:`write_video` does, drawn and
    encoded by ``workers`` forked processes at once, each a consecutive part of the video
    (:func:`visprim.sim.frame_workers.run_forked`), then joined: an MP4's parts without
    re-encoding, a GIF's frame blocks after one header (each part's first frame is whole,
    so the file shows the same pictures as :func:`write_video`'s). ``frame`` must draw
    frame ``i`` the same whichever frame it drew before (a forked process starts at its
    part's first frame). Atomic, like :func:`write_video`; returns the path."""
    from visprim.sim.frame_workers import run_forked, split

    out = check_video_path(path)
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be > 0 Hz, got {fps}")
    if n_frames < 1:
        raise ValueError("write_video: no frames to write")
    gif = out.suffix.lower() == ".gif"
    chunks = [c for c in split(n_frames, max(1, workers)) if len(c)]
    with atomic_file(out) as tmp:
        # The parts go in a folder of their own, removed at the end: once it is gone no
        # process can create a part (an encoder a crashed worker left running, say).
        folder = tmp.with_name(f"{tmp.name}.parts")
        folder.mkdir()
        parts = [folder / f"part{k}" for k in range(len(chunks))]
        try:
            palette = _GifPalette(frame(0).convert("RGB")) if gif else None
            jobs = [
                functools.partial(_write_part, part, frame, chunk, float(fps), palette)
                for part, chunk in zip(parts, chunks, strict=True)
            ]
            run_forked(jobs, "a process drawing the video")
            if palette is None:
                _join_mp4(parts, tmp)
            else:
                with open(tmp, "wb") as fh:
                    fh.write(palette.header())
                    for part in parts:
                        with open(part, "rb") as src:
                            shutil.copyfileobj(src, fh, 1 << 20)
                    fh.write(b";")
        finally:
            _remove_folder(folder)
    return out


def _remove_folder(folder: Path, tries: int = 100) -> None:
    """Remove ``folder`` and what is in it, again while a file appears in it meanwhile."""
    for _ in range(tries):
        shutil.rmtree(folder, ignore_errors=True)
        if not folder.exists():
            return
        time.sleep(0.01)
