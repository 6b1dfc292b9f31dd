"""What the bundled ffmpeg costs per frame of an imitation video: frames of an imitation GIF
(a 30 s generated recording, the panels at 480 px) piped as raw RGB, 2,000 frames per case:

* ``-f null``: reading the frames only;
* ``format=yuv420p``: plus the RGB -> YUV 4:2:0 conversion MP4 frames need;
* libx264 at the ``veryfast`` preset (visprim's, :data:`visprim.sim.video.MP4_PRESET`) and at
  ``ultrafast``.

Figures: wall time and the CPU time (user + system) of the ffmpeg process, seconds, median
[min, max] of ``--repeats`` runs, stamped. Run:
``PYTHONPATH=python .venv/bin/python benches/bench_mp4_encoder.py [--repeats 3]``
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _harness import commit, cpu_model
from bench_imitate_long import looped
from PIL import Image
from visprim import PrimitiveModel, kernels
from visprim.datasets import imitation_experiment
from visprim.io.markers_csv import write_marker_csv

CASES = {
    "read only (-f null)": ["-f", "null", "-"],
    "RGB -> YUV 4:2:0 (-f null)": ["-vf", "format=yuv420p", "-f", "null", "-"],
    "libx264 veryfast": ["-c:v", "libx264", "-preset", "veryfast", "-pix_fmt", "yuv420p"],
    "libx264 ultrafast": ["-c:v", "libx264", "-preset", "ultrafast", "-pix_fmt", "yuv420p"],
}


def _frames(root: Path) -> tuple[list[bytes], tuple[int, int]]:
    trials = imitation_experiment(2, 6, seed=3)
    model = PrimitiveModel(n_clusters=8, n_init=2, seed=0).fit(trials[:-1])
    model.save(root / "model.npz")
    rec = write_marker_csv(root / "rec.csv", looped(trials[-1], 0.5), truth=False)
    argv = [sys.executable, "-m", "visprim.cli", "-q", "imitate", str(root / "model.npz")]
    argv += [str(rec), "--out", str(root / "o"), "--size", "480", "--video", "imitation.gif"]
    subprocess.run(argv, check=True, capture_output=True)
    gif = Image.open(root / "o" / "imitation.gif")
    frames = []
    for i in range(0, gif.n_frames, max(1, gif.n_frames // 200)):
        gif.seek(i)
        frames.append(gif.convert("RGB").tobytes())
    return frames, gif.size


def _run(exe: str, args: list[str], frames: list[bytes], size: tuple[int, int], n: int):
    w, h = size
    head = [exe, "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24"]
    head += ["-s", f"{w}x{h}", "-r", "29.4", "-i", "-"]
    with tempfile.TemporaryDirectory() as tmp:
        tail = args if args[-1] == "-" else [*args, "-f", "mp4", str(Path(tmp) / "v.mp4")]
        t0, c0 = time.perf_counter(), os.times()
        proc = subprocess.Popen(head + tail, stdin=subprocess.PIPE)
        assert proc.stdin is not None
        for k in range(n):
            proc.stdin.write(frames[k % len(frames)])
        proc.stdin.close()
        proc.wait()
        c1 = os.times()
    cpu = c1.children_user + c1.children_system - c0.children_user - c0.children_system
    return time.perf_counter() - t0, cpu


def _spread(values: list[float]) -> str:
    return f"{statistics.median(values):.1f} [{min(values):.1f}, {max(values):.1f}]"


def main() -> None:
    import imageio_ffmpeg

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--frames", type=int, default=2000)
    args = parser.parse_args()
    exe = imageio_ffmpeg.get_ffmpeg_exe()
    print(f"# MP4 encoder cost — {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}")
    print(
        f"commit {commit()} · CPU {cpu_model()} · {os.cpu_count()} cores · instruction set "
        f"{kernels.instruction_set()} · load average {os.getloadavg()[0]:.1f} at the start"
    )
    with tempfile.TemporaryDirectory(prefix="visprim-bench-mp4-") as tmp:
        frames, size = _frames(Path(tmp))
        print(f"{args.frames} frames of {size[0]} x {size[1]}, {args.repeats} runs\n")
        print("| case | wall s | ffmpeg CPU s | CPU ms per frame |")
        print("|---|---|---|---|")
        for name, case in CASES.items():
            runs = [_run(exe, case, frames, size, args.frames) for _ in range(args.repeats)]
            cpu = [c for _, c in runs]
            per = 1000.0 * statistics.median(cpu) / args.frames
            print(f"| {name} | {_spread([w for w, _ in runs])} | {_spread(cpu)} | {per:.1f} |")


if __name__ == "__main__":
    main()
