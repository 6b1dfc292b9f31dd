"""Video → trial throughput on the shared Pose2Sim clip (1080 × 1920, 60 fps), and what the
speed-ups cost in accuracy.

    python benches/bench_video.py [--data ../shared/data] [--runs 3] [--view cam01]

Writes ``benches/bench_video.result.md`` (and prints it), stamped with the date, commit, CPU,
``visprim.kernels.instruction_set()`` and the load average before and after (the machine
may be shared: the load says how much of it the bench had).

* Where the time goes: CPU milliseconds per frame of each stage, one pass, one thread each
  (decoding, colour conversion of the full frame, downsizing, MediaPipe).
* Throughput of ``visprim.io.video.read_video_pieces`` (both arms, pose cache off),
  frames/s: median and range over ``--runs`` runs, for one pass (``workers=1``, the
  default), the two halves at once (``workers=2``), and frames downsized before MediaPipe
  (one pass: each row changes one thing).
* Accuracy of each against one pass at full resolution: landmark distance in the video's
  pixels (arm and hip landmarks, frames from the split on for ``workers=2``; median, 95th
  percentile, maximum), and of the metric world landmarks (mm).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _harness import commit, cpu_model
from visprim import atomic, kernels

HERE = Path(__file__).resolve().parent
ARM_HIPS = [11, 12, 13, 14, 15, 16, 23, 24]
#: (label, workers, max_side)
CONFIGS = [
    ("one pass, full resolution (default)", 1, None),
    ("two halves at once, full resolution", 2, None),
    ("one pass, frames downsized to 960 px", 1, 960),
    ("one pass, frames downsized to 640 px", 1, 640),
]
# the configurations' table reads `--view` with read_video_pieces (pose estimation and the
# trial); the views' table times video_poses alone on each view.


def _load() -> str:
    return " / ".join(f"{v:.1f}" for v in os.getloadavg())


def stages(clip: Path) -> dict[str, float]:
    """CPU ms per frame of each stage, one sequential pass."""
    import cv2
    import mediapipe as mp

    cap = cv2.VideoCapture(str(clip))
    pose = mp.solutions.pose.Pose(model_complexity=1)
    cost = dict.fromkeys(("decode", "BGR→RGB, full frame", "downsize to 960 px", "MediaPipe"), 0.0)
    buf, n = None, 0
    while True:
        t0 = time.process_time()
        ok, buf = cap.read(buf)
        t1 = time.process_time()
        if not ok:
            break
        rgb = cv2.cvtColor(buf, cv2.COLOR_BGR2RGB)
        t2 = time.process_time()
        h, w = buf.shape[:2]
        s = 960 / max(h, w)
        cv2.resize(buf, (round(w * s), round(h * s)), interpolation=cv2.INTER_AREA)
        t3 = time.process_time()
        pose.process(rgb)
        t4 = time.process_time()
        for k, dt in zip(cost, (t1 - t0, t2 - t1, t3 - t2, t4 - t3), strict=True):
            cost[k] += dt
        n += 1
    pose.close()
    cap.release()
    return {k: 1e3 * v / n for k, v in cost.items()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(HERE.parent.parent / "shared" / "data"))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--view", default="cam02", help="the view of the configurations' table")
    ap.add_argument("--out", default=str(HERE / "bench_video.result.md"))
    args = ap.parse_args()
    clip = Path(args.data) / "video" / "pose2sim_single_person" / f"{args.view}.mp4"
    if not clip.is_file():
        print(f"{clip}: the shared clip is not there (--data)", file=sys.stderr)
        return 2
    try:
        import cv2  # noqa: F401
        import mediapipe  # noqa: F401
    except ImportError as exc:
        print(f"bench_video needs the video extra: pip install 'visprim[video]' ({exc})")
        return 2
    os.environ["VISPRIM_PROGRESS"] = "0"
    os.environ["VISPRIM_CACHE_DIR"] = tempfile.mkdtemp(prefix="visprim-bench-video-")
    from visprim.io.video import read_video_pieces
    from visprim.io.video_pose import MediaPipePose, video_poses

    load_before = _load()
    when = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    print(f"stages ({clip.name}) ...", flush=True)
    cost = stages(clip)
    rows, poses = [], {}
    for label, workers, side in CONFIGS:
        est = MediaPipePose(max_side=side)
        poses[label] = video_poses(clip, est, cache=False, workers=workers)
        frames = poses[label].times.shape[0]
        rates = []
        for _ in range(args.runs):
            t0 = time.perf_counter()
            read_video_pieces(
                clip, "both", estimator=MediaPipePose(max_side=side), cache=False, workers=workers
            )
            rates.append(frames / (time.perf_counter() - t0))
        rows.append((label, statistics.median(rates), min(rates), max(rates)))
        print(f"  {label}: {statistics.median(rates):.1f} frames/s", flush=True)
    views = []
    for cam in ("cam01", "cam02", "cam03", "cam04"):
        path = clip.with_name(f"{cam}.mp4")
        rates, q = [], None
        for _ in range(args.runs):
            t0 = time.perf_counter()
            q = video_poses(path, cache=False)
            rates.append(q.times.shape[0] / (time.perf_counter() - t0))
        assert q is not None
        views.append((cam, q, statistics.median(rates), min(rates), max(rates)))
        print(f"  {cam}: {statistics.median(rates):.1f} frames/s ({q.meta['passes']})", flush=True)
    load_after = _load()

    ref = poses[CONFIGS[0][0]]
    acc = []
    for label, _, _ in CONFIGS[1:]:
        q = poses[label]
        passes = str(q.meta["passes"])
        start = int(passes.split("frame ")[1].split(",")[0]) if "halves" in passes else 0
        px = np.linalg.norm(q.image - ref.image, axis=2)[start:, ARM_HIPS]
        mm = 1e3 * np.linalg.norm(q.world - ref.world, axis=2)[start:, ARM_HIPS]
        acc.append((label, passes, start, px, mm))

    w, h = ref.size
    lines = [
        f"# video → trial throughput — {when}",
        f"commit {commit()} · CPU {cpu_model()} · {os.cpu_count()} cores · instruction set "
        f"{kernels.instruction_set()} · Python {platform.python_version()}",
        f"load average (1/5/15 min) before: {load_before}; after: {load_after} "
        "(a shared machine: a load above the core count means the bench had only part of it)",
        f"clip: {clip.name}, {w} × {h} px, {ref.times.shape[0]} frames; "
        f"command: `python benches/bench_video.py --runs {args.runs} --view {args.view}`",
        "",
        "## where the time goes (CPU ms per frame, one sequential pass)",
        "| stage | CPU ms / frame |",
        "|---|---:|",
        *(f"| {k} | {v:.1f} |" for k, v in cost.items()),
        "",
        f"## throughput, `read_video_pieces(arm='both', cache=False)`, {args.runs} runs",
        "| configuration | frames/s, median | range |",
        "|---|---:|---|",
        *(f"| {a} | {m:.1f} | {lo:.1f}–{hi:.1f} |" for a, m, lo, hi in rows),
        "",
        f"## the default (`video_poses(path, cache=False)`), each view, {args.runs} runs",
        "| view | people found | person found (% of frames) | passes | frames/s, median | range |",
        "|---|---:|---:|---|---:|---|",
        *(
            f"| {c} | {q.meta['people']} | {100 * q.found.mean():.0f} | {q.meta['passes']} "
            f"| {m:.1f} | {lo:.1f}–{hi:.1f} |"
            for c, q, m, lo, hi in views
        ),
        "",
        "## accuracy against one pass at full resolution (arm and hip landmarks)",
        "| configuration | frames compared | image, median / p95 / max (px) "
        "| world, median / p95 / max (mm) |",
        "|---|---|---|---|",
    ]
    for label, passes, start, px, mm in acc:
        lines.append(
            f"| {label} ({passes}) | {start}–{ref.times.shape[0] - 1} | "
            f"{np.median(px):.1f} / {np.percentile(px, 95):.1f} / {px.max():.1f} | "
            f"{np.median(mm):.1f} / {np.percentile(mm, 95):.1f} / {mm.max():.1f} |"
        )
    text = "\n".join(lines) + "\n"
    atomic.write_text(args.out, text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
