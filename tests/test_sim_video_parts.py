"""A video drawn and encoded in parts by forked processes, then joined: the same pictures
as one process draws, every frame once, errors of a worker raised in the parent, nothing
left behind."""

from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from PIL import Image, ImageDraw
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.imitate import imitate
from visprim.sim import frame_workers
from visprim.sim.frame_workers import WorkerError, draw_workers, split, stop_deferred
from visprim.sim.sidebyside import render_imitation
from visprim.sim.video import write_video, write_video_parts

forks = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers fork (Linux)")


def _frame(i: int) -> Image.Image:
    """Frame ``i``: a square moving right over a background that changes colour every 7
    frames, above a strip of every colour used (so the first frame's palette holds them)."""
    image = Image.new("RGB", (64, 40), (40 * (i // 7 % 6), 90, 200))
    draw = ImageDraw.Draw(image)
    draw.rectangle((i % 50, 10, i % 50 + 12, 22), fill=(250, 250, 30))
    for c in range(6):
        draw.rectangle((8 * c, 36, 8 * c + 7, 39), fill=(40 * c, 90, 200))
    return image


def _gif_frames(path) -> list[np.ndarray]:
    with Image.open(path) as gif:
        out = []
        for k in range(gif.n_frames):
            gif.seek(k)
            out.append(np.asarray(gif.convert("RGB")))
        return out


def test_split_is_consecutive_and_even() -> None:
    for n in (0, 1, 7, 100, 101):
        for parts in (1, 2, 3, 4):
            chunks = split(n, parts)
            assert len(chunks) == parts
            assert [i for c in chunks for i in c] == list(range(n))
            sizes = [len(c) for c in chunks]
            assert max(sizes) - min(sizes) <= 1
    with pytest.raises(ValueError, match="parts"):
        split(5, 0)


def test_draw_workers_counts() -> None:
    linux = sys.platform.startswith("linux")
    assert draw_workers(1000, 3) == (3 if linux else 0)
    assert draw_workers(1000, 1) == 0 and draw_workers(1000, 0) == 0
    assert draw_workers(1, 4) == 0  # one frame: nothing to share
    assert draw_workers(50) == 0  # too few frames to pay for a fork
    # An MP4 part needs a core for its encoder too: never more parts than cores / 2.
    from visprim.sim.frame_workers import usable_cores

    assert draw_workers(10**6, cores_per_part=2) <= max(usable_cores() // 2, 0)
    with pytest.raises(ValueError, match="cores_per_part"):
        draw_workers(1000, cores_per_part=0)
    for bad in (-1, True, 2.0):
        with pytest.raises(ValueError, match="whole number"):
            draw_workers(1000, bad)  # type: ignore[arg-type]


@forks
@pytest.mark.parametrize("workers", [2, 3])
def test_gif_in_parts_shows_the_same_pictures(tmp_path, workers) -> None:
    n = 61
    one = write_video(tmp_path / "one.gif", (_frame(i) for i in range(n)), 25.0)
    parts = write_video_parts(tmp_path / "parts.gif", _frame, n, 25.0, workers)
    a, b = _gif_frames(one), _gif_frames(parts)
    assert len(a) == len(b) == n
    for k in range(n):
        np.testing.assert_array_equal(b[k], a[k])
        np.testing.assert_array_equal(b[k], np.asarray(_frame(k)))  # colours of the palette: exact
    with Image.open(parts) as gif:
        assert gif.info["loop"] == 0 and gif.info["duration"] == 40
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.gif", "parts.gif"]


@forks
def test_mp4_in_parts_has_every_frame_on_one_clock(tmp_path) -> None:
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    n = 53
    path = write_video_parts(tmp_path / "v.mp4", _frame, n, 25.0, 2)
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    frames = [np.frombuffer(f, np.uint8).reshape(40, 64, 3) for f in reader]
    assert len(frames) == n
    assert meta["fps"] == 25.0 and meta["duration"] == pytest.approx(n / 25.0, abs=0.05)
    assert "yuv420p(tv, smpte170m" in meta["pix_fmt"]
    for k in (0, 1, n // 2 - 1, n // 2, n // 2 + 1, n - 1):  # around the join too
        diff = np.abs(frames[k].astype(int) - np.asarray(_frame(k)).astype(int))
        assert np.median(diff) <= 4, k
    assert [p.name for p in tmp_path.iterdir()] == ["v.mp4"]


def _fails_at(k: int, how: str):
    def frame(i: int) -> Image.Image:
        if i == k:
            if how == "raise":
                raise ArithmeticError(f"no frame {i}")
            os._exit(3)
        return _frame(i)

    return frame


@forks
@pytest.mark.parametrize("ext", ["gif", "mp4"])
def test_a_failing_part_raises_here_and_writes_nothing(tmp_path, ext) -> None:
    """Frames 0-29 are this process's part, 30-59 the forked child's."""
    if ext == "mp4":
        pytest.importorskip("imageio_ffmpeg")
    target = tmp_path / f"v.{ext}"
    target.write_bytes(b"previous")
    with pytest.raises(WorkerError, match=r"failed: ArithmeticError: no frame 40") as info:
        write_video_parts(target, _fails_at(40, "raise"), 60, 25.0, 2)
    assert "Traceback" in "\n".join(getattr(info.value, "__notes__", []))
    with pytest.raises(WorkerError, match="exit code 3"):
        write_video_parts(target, _fails_at(45, "exit"), 60, 25.0, 2)
    with pytest.raises(ArithmeticError, match="no frame 12"):  # this process's own part
        write_video_parts(target, _fails_at(12, "raise"), 60, 25.0, 2)
    assert target.read_bytes() == b"previous"
    assert [p.name for p in tmp_path.iterdir()] == [target.name]


@pytest.fixture(scope="module")
def imitation():
    trials = imitation_experiment(2, 4, seed=3, preset="strokes")
    model = PrimitiveModel(n_clusters=6, n_init=2, seed=0).fit(trials[:-1])
    return imitate(model, trials[-1])


@forks
def test_imitation_video_in_parts_equals_one_process(imitation, tmp_path) -> None:
    one = render_imitation(imitation, tmp_path / "one.gif", size=(96, 96), workers=0)
    parts = render_imitation(imitation, tmp_path / "parts.gif", size=(96, 96), workers=3)
    a, b = _gif_frames(one), _gif_frames(parts)
    assert len(a) == len(b) > 30
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(y, x)


@forks
def test_a_stop_waits_for_the_deferred_block(tmp_path) -> None:
    """SIGTERM reaches the worker inside stop_deferred: the block finishes, what follows it
    does not run, and the worker exits as stopped."""
    ready, signalled, done, after = (tmp_path / n for n in ("ready", "sig", "done", "after"))

    def job() -> None:
        with stop_deferred():
            ready.touch()
            deadline = time.monotonic() + 10
            while not signalled.exists() and time.monotonic() < deadline:
                time.sleep(0.01)
            time.sleep(0.2)  # the signal has arrived by now
            done.touch()
        after.touch()

    ctx = multiprocessing.get_context("fork")
    p = ctx.Process(target=frame_workers._child, args=(job, ctx.Pipe(duplex=False)[1]))
    p.start()
    deadline = time.monotonic() + 10
    while not ready.exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    p.terminate()
    signalled.touch()
    p.join(10)
    assert p.exitcode == 128 + signal.SIGTERM
    assert done.exists() and not after.exists()


@forks
def test_an_encoder_a_crashed_part_left_running_writes_nothing(tmp_path, monkeypatch) -> None:
    """The child dies at once (``os._exit``) and leaves its encoder running, which writes
    its output 0.5 s later, after the parent has cleaned up (an encoder stand-in that
    creates its output file late): the part has nowhere to go."""
    pytest.importorskip("imageio_ffmpeg")
    spawn = subprocess.Popen

    def late_encoder(cmd, *args, **kwargs):
        if not str(cmd[-1]).endswith("part1"):  # the child's part
            return spawn(cmd, *args, **kwargs)
        return spawn(["sh", "-c", 'sleep 0.5; echo late > "$1"', "sh", cmd[-1]], *args, **kwargs)

    monkeypatch.setattr(subprocess, "Popen", late_encoder)
    target = tmp_path / "v.mp4"
    with pytest.raises(WorkerError, match="exit code 3"):
        write_video_parts(target, _fails_at(40, "exit"), 60, 25.0, 2)
    time.sleep(1.5)  # the encoder left running has written by now
    assert list(tmp_path.iterdir()) == []
