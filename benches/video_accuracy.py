"""Video accuracy and throughput on the shared Pose2Sim clip (four calibrated cameras).

    PYTHONPATH=python python benches/video_accuracy.py [--data ../shared/data] [--runs 3]

Prints a stamped table (date, commit, CPU, instruction set, load):

* person found per view (% of frames);
* four-view triangulation (weighted DLT of MediaPipe's 2-D keypoints, undistorted with the
  QCA calibration): reprojection error, median and 90th percentile (px), per view;
* each single camera (MediaPipe's metric world landmarks) against the four-view
  triangulation of the same frames, both arms: RMS angle of the upper-arm and forearm
  directions, each expressed in its own trial's torso frame (what inverse kinematics uses),
  and RMS error of the elbow flexion (from :func:`visprim.ik.arm_angles`);
* jitter on the still part (the longest run of frames where the triangulated wrists move
  slower than 0.15 m/s): RMS frame-to-frame change of the bone directions (deg/frame);
* throughput, video → trial, one view, pose cache off: frames/s, median (and range) of runs.

The pose cache lives in a temporary folder (removed at the end).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from visprim import kernels
from visprim.ik import arm_angles
from visprim.io.video import read_video_pieces
from visprim.io.views import read_views_pieces, triangulate_views
from visprim.trial import Trial

STILL_SPEED = 0.15  # m/s


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "?"


def _commit() -> str:
    try:
        out = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True
        )
        return out.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "?"


def _bones(trial: Trial, side: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit upper-arm and forearm directions in the trial's torso frame, (T, 3) each."""
    assert trial.joints is not None
    j = trial.joints[:, 3 * side : 3 * side + 3]
    u = j[:, 1] - j[:, 0]
    f = j[:, 2] - j[:, 1]
    if trial.body_frame is not None:
        u = np.einsum("tji,tj->ti", trial.body_frame, u)
        f = np.einsum("tji,tj->ti", trial.body_frame, f)
    return (
        u / np.linalg.norm(u, axis=1, keepdims=True),
        f / np.linalg.norm(f, axis=1, keepdims=True),
    )


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.rad2deg(np.arccos(np.clip(np.sum(a * b, axis=1), -1.0, 1.0)))


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def _still(reference: Trial, rate: float) -> slice:
    assert reference.joints is not None
    wrists = reference.joints[:, [2, 5]]
    speed = np.linalg.norm(np.diff(wrists, axis=0), axis=2).max(axis=1) * rate
    slow = np.concatenate([speed < STILL_SPEED, [False]])
    best, start = (0, 0), None
    for i, s in enumerate(slow):
        if s and start is None:
            start = i
        if not s and start is not None:
            if i - start > best[1] - best[0]:
                best = (start, i)
            start = None
    return slice(*best)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--data", default=str(Path(__file__).resolve().parents[1].parent / "shared" / "data")
    )
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    folder = Path(args.data) / "video" / "pose2sim_single_person"
    views = [folder / f"cam0{i}.mp4" for i in (1, 2, 3, 4)]
    calib = folder / "Calib.qca.txt"
    tmp = tempfile.TemporaryDirectory(prefix="visprim-video-bench-")
    os.environ["VISPRIM_CACHE_DIR"] = tmp.name
    load0 = os.getloadavg()
    print(f"# video accuracy — {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}")
    print(
        f"commit {_commit()} · CPU {_cpu()} · {os.cpu_count()} cores · instruction set "
        f"{kernels.instruction_set()} · Python {sys.version.split()[0]}"
    )
    print(f"load average at start: {load0[0]:.1f} / {load0[1]:.1f} / {load0[2]:.1f} (1/5/15 min)")

    mv = triangulate_views(views, calib)
    rate = float(mv.meta["rate"])
    print("\n## person found and triangulation")
    print("| view | person found | reprojection median (px) | 90th pct (px) |")
    print("|---|---|---|---|")
    for i, cam in enumerate(mv.cameras):
        e = mv.reprojection[:, :, i]
        print(
            f"| {cam.name} | {100 * mv.meta['person_found'][i]:.0f} % | "
            f"{np.nanmedian(e):.1f} | {np.nanpercentile(e, 90):.1f} |"
        )
    arm_joints = [11, 12, 13, 14, 15, 16, 23, 24]
    ea = mv.reprojection[:, arm_joints]
    print(
        f"| all (arm + torso keypoints) | | {np.nanmedian(ea):.1f} | "
        f"{np.nanpercentile(ea, 90):.1f} |"
    )
    print(
        f"| all 33 keypoints | | {np.nanmedian(mv.reprojection):.1f} | "
        f"{np.nanpercentile(mv.reprojection, 90):.1f} |"
    )

    ref = read_views_pieces(views, calib, arm="both", min_duration=0.1)[0]
    ref_angles = arm_angles(ref)
    still = _still(ref, rate)
    print(
        f"\n## each camera vs the four-view triangulation (both arms, {ref.times.size} frames;"
        f" still part: frames {still.start}–{still.stop - 1})"
    )
    print(
        "| view | arm | upper arm RMS (°) | forearm RMS (°) | elbow flexion RMS (°) | "
        "jitter upper / fore, still (°/frame) |"
    )
    print("|---|---|---|---|---|---|")
    r0 = [_bones(ref, s) for s in (0, 1)]
    for s, side in enumerate(("right", "left")):
        ju = _rms(_angle(r0[s][0][still][1:], r0[s][0][still][:-1]))
        jf = _rms(_angle(r0[s][1][still][1:], r0[s][1][still][:-1]))
        print(f"| 4-view | {side} | — | — | — | {ju:.2f} / {jf:.2f} |")
    for view in views:
        mono = read_video_pieces(view, arm="both", min_duration=0.1)[0]
        a, b = mono.meta["frame_range"][0], ref.meta["frame_range"][0]
        n = min(mono.times.size, ref.times.size)
        if a != b:
            print(f"| {view.stem} | frames do not line up ({a} vs {b}) |")
            continue
        ang = arm_angles(mono)
        for s, side in enumerate(("right", "left")):
            u, f = _bones(mono, s)
            du = _angle(u[:n], r0[s][0][:n])
            df = _angle(f[:n], r0[s][1][:n])
            dth = np.rad2deg(ang[:n, 4 * s + 3] - ref_angles[:n, 4 * s + 3])
            ju = _rms(_angle(u[still][1:], u[still][:-1]))
            jf = _rms(_angle(f[still][1:], f[still][:-1]))
            print(
                f"| {view.stem} | {side} | {_rms(du):.1f} | {_rms(df):.1f} | {_rms(dth):.1f} | "
                f"{ju:.2f} / {jf:.2f} |"
            )

    print(
        f"\n## throughput, video → trial ({views[0].name}, "
        f"{mv.poses[0].size[0]}×{mv.poses[0].size[1]}, pose cache off)"
    )
    rates = []
    for _ in range(args.runs):
        t0 = time.perf_counter()
        tr = read_video_pieces(views[0], arm="both", cache=False, min_duration=0.1)[0]
        rates.append(tr.meta["frames"] / (time.perf_counter() - t0))
    load1 = os.getloadavg()
    print(
        f"{np.median(rates):.1f} frames/s, median of {args.runs} runs "
        f"(range {min(rates):.1f}–{max(rates):.1f}); load average at the end "
        f"{load1[0]:.1f} / {load1[1]:.1f} / {load1[2]:.1f} on {os.cpu_count()} cores"
    )
    tmp.cleanup()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
