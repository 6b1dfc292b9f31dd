"""Video accuracy on the shared Pose2Sim clip (four calibrated cameras, 100 frames, 60 fps).

    PYTHONPATH=python python benches/video_accuracy.py [--data DIR] [--runs 3] [--out FILE]

Prints (and with ``--out`` writes atomically) stamped tables (date, commit, CPU, instruction
set, load average; the machine is shared):

1. **Triangulation.** Person found per view (% of frames); reprojection error of the
   four-view weighted DLT of MediaPipe's 2-D keypoints (undistorted with the QCA
   calibration), median and 90th percentile (px), per view, for three pipelines: plain DLT
   (every observation), + left/right exchange check, + outlier rejection at
   :data:`visprim.params.TRIANGULATION_MAX_REPROJECTION_PX` (the default of
   ``read_views``), the last both over the observations used and over all confident
   observations (the ones left out included); then the default, self-calibrated
   (``refine_calibration=True``, in-sample). The same per keypoint group (all 33, the
   trial's 12, face, arms, hands, hips, legs). A table over outlier thresholds shows how
   much the "used" figure is the threshold's doing. Every table uses the calibration as read
   (no self-calibration) unless it says otherwise; the line after the table says what
   read_views' default (``"auto"``) does on this clip.
   Synchronisation: ``sync=True``'s offsets (:func:`visprim.io.views.estimate_offsets`),
   per pair of views and combined, their inconsistency, the reprojection error with them,
   and an independent check: each single camera against the reference built with and
   without them.
2. **Single camera vs the four-view reference** (the default pipeline), both arms, per view:
   RMS angle of the upper-arm and forearm directions and RMS error of the elbow flexion
   (angle between upper arm and forearm). Directions are compared in a *body frame* built
   the same way from both skeletons (z mid-hip → mid-shoulder, y right → left side;
   :func:`visprim.io.assemble.torso_frame`, what the trial and IK use): MediaPipe's world
   landmarks are hip-centred and camera-oriented, so only directions relative to the torso
   are comparable without a camera model. A second column set rotates the camera-oriented
   directions into the world with the camera's extrinsics instead (absolute directions),
   with the torso frame's own error (rotation angle, RMS).
   Frames: those where the view's keypoints are confident (≥ 0.5) and the reference exists.
   Baseline beside them: a constant pose, each bone along the reference's own clip-mean
   direction (no per-frame information; optimistic, since it uses the reference).
   The single view is read as ``read_video`` reads it: frames whose left/right labels the
   estimator exchanged put back (:mod:`visprim.io.video_sides`); a table gives each view's
   error before and after, and how the repaired frames compare with the four-view check's
   flips (an independent judge). A second table checks the comparison itself: the error on
   the frames whose reference arm and hip points each come from ≥ 3 views, in the world frame
   (no torso frame), and the torso frame's own error. Cameras are fitted to their videos'
   frames (:meth:`visprim.io.calibration.Camera.fitted_to`) throughout.
3. **Jitter.** The clip has no still part (the rule "every reference wrist slower than
   :data:`STILL_SPEED`" is reported with the frames it finds), so jitter is measured as the
   high-pass residual of each bone direction: the angle between the direction at frame t and
   the mean of its neighbours t−1, t+1 (deg), RMS over frames; smooth motion at 60 fps
   contributes little, white noise of σ per frame gives about 1.22 σ.
4. **Smoothing choice.** Single-camera error (mean of the upper-arm and forearm RMS, both
   arms) against the reference as a function of the low-pass cutoff (zero-phase Butterworth,
   order :data:`visprim.params.VIDEO_LOWPASS_ORDER`, on the keypoints); leave one camera out:
   the cutoff is chosen on three cameras and scored on the fourth, beside no smoothing.
5. **Self-calibration** (:mod:`visprim.io.refine`). The cameras' rotations fitted on frames
   0–49 and scored on 50–99, and the other way round: reprojection (all 33 and the trial's
   12 keypoints) with the calibration as read and refined; each single camera against the
   reference built from the refined cameras of the *other* half (every frame held out); the
   smoothing choice against that reference; and read_views' default on the whole clip
   (in-sample: its rotations, its own held-out check, the time it took).

The pose cache lives in a temporary folder (removed at the end). Timing is not measured here
(see benches/bench_video.py).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import io
import os
import sys
import tempfile
import time
from contextlib import redirect_stdout
from pathlib import Path
from typing import Any

import numpy as np
from _harness import commit, cpu_model
from numpy.typing import NDArray
from visprim import kernels
from visprim.atomic import write_text
from visprim.io.assemble import torso_frame
from visprim.io.calibration import Camera, read_calibration
from visprim.io.keypoints import LAYOUTS, smooth_keypoints
from visprim.io.refine import refine_rotations, rotated
from visprim.io.video_pose import VideoPoses, video_poses
from visprim.io.video_sides import repair_side_exchanges
from visprim.io.views import SIDE_PAIRS, MultiView, _reproject, estimate_offsets, triangulate_poses
from visprim.params import (
    TRIANGULATION_MAX_REPROJECTION_PX,
    VIDEO_LOWPASS_ORDER,
    VIEWS_SYNC_MAX_OFFSET_S,
)
from visprim.progress import bar

#: The calibration as read (no self-calibration): what every table uses unless it says
#: otherwise (the self-calibration section compares the two).
AS_READ: dict[str, Any] = {"refine_calibration": False}
#: The still-part rule: every reference wrist slower than this (m/s).
STILL_SPEED = 0.15
#: Low-pass cutoffs tried (Hz); None is no smoothing.
CUTOFFS: tuple[float | None, ...] = (None, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 15.0)
#: BlazePose indices: shoulder, elbow, wrist of each arm; hips.
ARMS = {"right": (12, 14, 16), "left": (11, 13, 15)}
HIPS = {"right": 24, "left": 23}
MIN_CONFIDENCE = 0.5

Array = NDArray[np.float64]


def _unit(v: Array) -> Array:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _angle(a: Array, b: Array) -> Array:
    """Angle (deg) between direction arrays (..., 3)."""
    return np.rad2deg(np.arccos(np.clip(np.sum(_unit(a) * _unit(b), axis=-1), -1.0, 1.0)))


def _rms(x: Array) -> float:
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else float("nan")


def rotation_angle(a: Array, b: Array) -> Array:
    """Angle (deg) of the rotation between frames a and b, (T, 3, 3) each."""
    tr = np.einsum("tij,tij->t", a, b)
    return np.rad2deg(np.arccos(np.clip((tr - 1) / 2, -1.0, 1.0)))


def body_frame(points: Array) -> Array:
    """(T, 3, 3) torso frames (columns x forward, y left, z up) of BlazePose points (T, 33, 3)."""
    rs, ls = points[:, ARMS["right"][0]], points[:, ARMS["left"][0]]
    rh, lh = points[:, HIPS["right"]], points[:, HIPS["left"]]
    return torso_frame((rh + lh) / 2, (rs + ls) / 2, (rs + rh) / 2, (ls + lh) / 2)


def bones(points: Array, frame: Array | None) -> dict[str, Array]:
    """Upper-arm and forearm vectors per arm, (T, 3), in ``frame`` (T, 3, 3) when given."""
    out = {}
    for side, (s, e, w) in ARMS.items():
        for name, (a, b) in (("upper", (s, e)), ("fore", (e, w))):
            v = points[:, b] - points[:, a]
            out[f"{side}_{name}"] = v if frame is None else np.einsum("tji,tj->ti", frame, v)
    return out


def errors(
    mono: dict[str, Array], ref: dict[str, Array], valid: NDArray[np.bool_]
) -> dict[str, float]:
    """RMS direction errors (deg) per bone and elbow-flexion errors per arm on ``valid`` frames."""
    out = {k: _rms(_angle(mono[k], ref[k])[valid]) for k in mono}
    for side in ARMS:
        fm = _angle(mono[f"{side}_upper"], mono[f"{side}_fore"])
        fr = _angle(ref[f"{side}_upper"], ref[f"{side}_fore"])
        out[f"{side}_flex"] = _rms((fm - fr)[valid])
    return out


def jitter(vectors: Array) -> float:
    """RMS angle (deg) between each direction and the mean of its two neighbours."""
    d = _unit(vectors)
    return _rms(_angle(d[1:-1], d[:-2] + d[2:]))


def fill_time(points: Array) -> Array:
    """Linear interpolation of NaN frames (per coordinate), ends held; for the low-pass."""
    out = points.copy()
    flat = out.reshape(out.shape[0], -1)
    idx = np.arange(flat.shape[0])
    for c in range(flat.shape[1]):
        ok = np.isfinite(flat[:, c])
        if ok.any() and not ok.all():
            flat[:, c] = np.interp(idx, idx[ok], flat[ok, c])
    return out


def mono_points(q: VideoPoses, n: int) -> tuple[Array, NDArray[np.bool_]]:
    """A view's world landmarks (n, 33, 3) with unconfident arm/torso points NaN, and the
    frames where every arm and torso point is confident."""
    pts = q.world[:n].copy()
    conf = np.where(q.found[:n, None], q.confidence[:n], 0.0)
    pts[conf < MIN_CONFIDENCE] = np.nan
    need = [i for t in ARMS.values() for i in t] + list(HIPS.values())
    return pts, np.isfinite(pts[:, need]).all(axis=(1, 2))


def still_part(ref: Array, rate: float) -> tuple[int, int]:
    """Longest run of frames where both reference wrists move slower than STILL_SPEED."""
    wr = ref[:, [ARMS["right"][2], ARMS["left"][2]]]
    speed = np.linalg.norm(np.diff(wr, axis=0), axis=2).max(axis=1) * rate
    slow = np.concatenate([speed < STILL_SPEED, [False]])
    best, start = (0, 0), None
    for i, s in enumerate(slow):
        if s and start is None:
            start = i
        if not s and start is not None:
            if i - start > best[1] - best[0]:
                best = (start, i)
            start = None
    return best


def window(q: VideoPoses, a: int, b: int) -> VideoPoses:
    return dataclasses.replace(
        q,
        times=q.times[a:b],
        world=q.world[a:b],
        image=q.image[a:b],
        confidence=q.confidence[a:b],
        found=q.found[a:b],
    )


def all_views_error(mv: MultiView) -> Array:
    """Reprojection error (px) of the points into every confident observation (after the
    left/right check), the views left out as outliers included; NaN elsewhere."""
    e = _reproject(mv.cameras, mv.points, mv.pixels)
    return np.where(mv.confidence >= MIN_CONFIDENCE, e, np.nan)


def _stats(e: Array) -> str:
    return f"{np.nanmedian(e):.1f} | {np.nanpercentile(e, 90):.1f}"


def reprojection_rows(mv: MultiView, label: str) -> list[str]:
    """Median | 90th percentile per view and overall: over the observations used, and over
    all confident observations (the same without outlier rejection)."""
    used, alle = mv.reprojection, all_views_error(mv)
    rows = []
    for i, cam in enumerate(mv.cameras):
        rows.append(f"| {label} | {cam.name} | {_stats(used[:, :, i])} | {_stats(alle[:, :, i])} |")
    rows.append(f"| {label} | all | {_stats(used)} | {_stats(alle)} |")
    return rows


def _indices(spec: object) -> list[int]:
    return [int(x) for x in spec] if isinstance(spec, (tuple, list)) else [int(spec)]  # type: ignore[call-overload]


#: The BlazePose keypoints the trial is built from (``visprim.io.keypoints.LAYOUTS``:
#: shoulders, elbows, wrists, the hand points 17–20, hips).
TRIAL_KEYPOINTS = sorted({i for spec in LAYOUTS["blazepose33"].values() for i in _indices(spec)})
#: BlazePose keypoint groups of the per-group table.
GROUPS = {
    "all 33": list(range(33)),
    "the trial's 12 (shoulders, elbows, wrists, hand 17–20, hips)": TRIAL_KEYPOINTS,
    "face 0–10": list(range(11)),
    "shoulders, elbows, wrists 11–16": list(range(11, 17)),
    "hand 17–22 (pinky, index, thumb)": list(range(17, 23)),
    "hips 23–24": [23, 24],
    "legs and feet 25–32": list(range(25, 33)),
}


def group_rows(loose: MultiView, robust: MultiView) -> list[str]:
    """Reprojection medians (px) per keypoint group: no rejection | used | all views."""
    alle = all_views_error(robust)
    rows = []
    for label, ks in GROUPS.items():
        rows.append(
            f"| {label} | {np.nanmedian(loose.reprojection[:, ks]):.1f} | "
            f"{np.nanmedian(robust.reprojection[:, ks]):.1f} | {np.nanmedian(alle[:, ks]):.1f} |"
        )
    return rows


def medians(loose: MultiView, robust: MultiView, ks: list[int]) -> str:
    """``no rejection | used | all views`` reprojection medians (px) over keypoints ``ks``."""
    return (
        f"{np.nanmedian(loose.reprojection[:, ks]):.1f} | "
        f"{np.nanmedian(robust.reprojection[:, ks]):.1f} | "
        f"{np.nanmedian(all_views_error(robust)[:, ks]):.1f}"
    )


#: Outlier thresholds (px) of the threshold table.
THRESHOLDS = (8.0, 10.0, 12.0, 15.0, 20.0, 30.0)


def shift(q: VideoPoses, offset: int, start: int, stop: int) -> VideoPoses:
    """View frames ``start + offset : stop + offset`` (the reference's frames start:stop)."""
    return window(q, start + offset, stop + offset)


def jitter_2d(q: VideoPoses) -> Array:
    """Distance (px) of each 2-D keypoint from the mean of its two neighbouring frames."""
    im = q.image
    return np.linalg.norm(im[1:-1] - (im[:-2] + im[2:]) / 2, axis=-1)


def view_shifts(
    poses: list[VideoPoses], cameras: list[Camera], iterations: int = 8
) -> tuple[Array, MultiView]:
    """Diagnostic only: one constant 2-D shift (px) per view, fitted by alternating the
    default triangulation and the median residual of each view's observations used; the
    shifts and the triangulation with the shifted keypoints."""
    shifts = np.zeros((len(poses), 2))
    mv = triangulate_poses(poses, cameras, **AS_READ)
    for _ in range(iterations):
        moved = [
            dataclasses.replace(q, image=q.image - b) for q, b in zip(poses, shifts, strict=True)
        ]
        mv = triangulate_poses(moved, cameras, **AS_READ)
        for i, cam in enumerate(mv.cameras):  # fitted to the frames
            res = mv.pixels[:, :, i] - cam.project(mv.points)
            used = np.isfinite(mv.reprojection[:, :, i])
            shifts[i] += np.nanmedian(res[used], axis=0)
    return shifts, mv


#: Estimator settings the diagnostics compare with the default (``--variants``).
VARIANTS = {
    "no landmark smoothing": {"smooth_landmarks": False},
    "still-image mode": {"static_image_mode": True},
}


def report(folder: Path, variants: bool = False) -> tuple[str, dict[str, float]]:
    """The report's text and its headline figures (for the runs table)."""
    views = [folder / f"cam0{i}.mp4" for i in (1, 2, 3, 4)]
    cameras = read_calibration(folder / "Calib.qca.txt")
    poses = [video_poses(v) for v in bar(views, desc="pose per view", unit="view")]
    n = min(q.times.size for q in poses)
    rate = float(poses[0].meta["rate"])
    buf = io.StringIO()
    with redirect_stdout(buf):
        load0 = os.getloadavg()
        print(f"# video accuracy — {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}")
        print(
            f"commit {commit()} · CPU {cpu_model()} · {os.cpu_count()} cores · instruction set "
            f"{kernels.instruction_set()} · Python {sys.version.split()[0]} · load average "
            f"{load0[0]:.1f} / {load0[1]:.1f} / {load0[2]:.1f} (1/5/15 min; shared machine)"
        )
        print(
            f"\nclip: {folder.name}, {len(views)} views, {n} frames at {rate:g} fps; pose "
            f"estimator {poses[0].meta.get('estimator')}"
        )
        print("\n## person found")
        print("| view | person found | video size (px) | calibrated size (px) |")
        print("|---|---|---|---|")
        for v, q, c in zip(views, poses, cameras, strict=True):
            print(
                f"| {v.stem} | {100 * q.found[:n].mean():.0f} % | {q.size[0]}×{q.size[1]} | "
                f"{c.size[0]}×{c.size[1]} |"
            )
        print(
            "\nA video of another size than its calibration uses the camera fitted to the "
            "frame (uniform scale, centred: letterbox; visprim.io.calibration.Camera.fitted_to)."
        )

        plain = triangulate_poses(poses, cameras, swaps=False, max_reprojection=None, **AS_READ)
        swapped = triangulate_poses(poses, cameras, swaps=True, max_reprojection=None, **AS_READ)
        robust = triangulate_poses(poses, cameras, **AS_READ)  # read_views without refinement
        t0 = time.perf_counter()
        whole = triangulate_poses(poses, cameras, refine_calibration=True)
        took = time.perf_counter() - t0
        default = triangulate_poses(poses, cameras)  # read_views' default, "auto"
        fitted = robust.cameras  # each camera fitted to its video's frame size
        print(
            "\n## four-view triangulation: reprojection error (px), all 33 keypoints\n\n"
            "used: the observations each point was triangulated from; all views: every "
            f"confident (≥ {MIN_CONFIDENCE}) observation, outliers left out included (after "
            "the left/right check)."
        )
        print(
            "| pipeline | view | used: median | used: 90th pct | all views: median | "
            "all views: 90th pct |"
        )
        print("|---|---|---|---|---|---|")
        for row in reprojection_rows(plain, "plain DLT"):
            print(row)
        for row in reprojection_rows(swapped, "+ left/right check"):
            print(row)
        for row in reprojection_rows(
            robust,
            f"+ outliers > {TRIANGULATION_MAX_REPROJECTION_PX:g} px left out",
        ):
            print(row)
        for row in reprojection_rows(
            whole, "+ self-calibration (refine_calibration=True; in-sample: fitted on these frames)"
        ):
            print(row)
        used0 = np.isfinite(swapped.reprojection).sum()
        print(
            f"\nleft/right exchanges found (pair·frames, per view): "
            f"{robust.meta['side_swaps_per_view']} of {n * 16}; observations left out as "
            f"outliers: {robust.meta['rejected_per_view']} per view, "
            f"{100 * sum(robust.meta['rejected_per_view']) / used0:.1f} % of all; points with no "
            f"consistent views: {100 * np.isnan(robust.points[..., 0]).mean():.1f} %"
        )
        loose_whole = triangulate_poses(poses, whole.cameras, max_reprojection=None, **AS_READ)
        used1 = np.isfinite(loose_whole.reprojection).sum()
        print(
            "self-calibrated (refine_calibration=True): left/right exchanges "
            f"{whole.meta['side_swaps_per_view']}; observations left out as outliers: "
            f"{whole.meta['rejected_per_view']} per view, "
            f"{100 * sum(whole.meta['rejected_per_view']) / used1:.1f} % of all; points with "
            f"no consistent views: {100 * np.isnan(whole.points[..., 0]).mean():.1f} %"
        )
        rec0 = default.meta["refine_calibration"] or {}
        print(
            "read_views' default (refine_calibration='auto') on this clip: applied "
            f"{rec0.get('applied')}: {rec0.get('reason')}; people found per view: "
            f"{[q.meta.get('people') for q in poses]}"
        )
        figures = {
            "calibration as read: used median (px)": float(np.nanmedian(robust.reprojection)),
            "calibration as read: all views median (px)": float(
                np.nanmedian(all_views_error(robust))
            ),
            "self-calibrated (True, in-sample): used median (px)": float(
                np.nanmedian(whole.reprojection)
            ),
            "self-calibrated (True, in-sample): all views median (px)": float(
                np.nanmedian(all_views_error(whole))
            ),
            "all views, no outlier rejection, median (px)": float(
                np.nanmedian(swapped.reprojection)
            ),
        }

        print(
            "\n### by keypoint group (calibration as read, outliers > 15 px left out; "
            "median, px)\n\n"
            "The target is over all 33 keypoints; the trial is built from 12 of them "
            "(visprim.io.keypoints.LAYOUTS['blazepose33'])."
        )
        print("| keypoints | no rejection | used | all views |")
        print("|---|---|---|---|")
        for row_ in group_rows(swapped, robust):
            print(row_)
        tk = TRIAL_KEYPOINTS
        figures["trial keypoints: used median (px)"] = float(
            np.nanmedian(robust.reprojection[:, tk])
        )
        figures["trial keypoints: all views median (px)"] = float(
            np.nanmedian(all_views_error(robust)[:, tk])
        )

        print("\n### why the views disagree (diagnostics)\n")
        print(
            "| view | 2-D jitter: median (px) | 2-D jitter: 90th pct (px) | "
            "best constant shift (px) |"
        )
        print("|---|---|---|---|")
        shifts, shifted = view_shifts(poses, cameras)
        for v, q, b_ in zip(views, poses, shifts, strict=True):
            j = jitter_2d(q)
            print(
                f"| {v.stem} | {np.nanmedian(j):.1f} | {np.nanpercentile(j, 90):.1f} | "
                f"({b_[0]:+.1f}, {b_[1]:+.1f}), {np.linalg.norm(b_):.1f} |"
            )
        print(
            "\n2-D jitter: distance of each keypoint from the mean of its neighbouring frames. "
            "Best constant shift: one 2-D shift per view fitted to the residuals (diagnostic, "
            f"not used); with it the default's median is {np.nanmedian(shifted.reprojection):.1f} "
            f"px used, {np.nanmedian(all_views_error(shifted)):.1f} px over all views."
        )
        equal = [
            dataclasses.replace(q, confidence=(q.confidence >= MIN_CONFIDENCE).astype(float))
            for q in poses
        ]
        flat = triangulate_poses(equal, cameras, **AS_READ)
        conf_used = np.where(np.isfinite(robust.reprojection), robust.confidence, np.nan)
        print(
            "\nconfidence weighting (the DLT weight of an observation is its confidence): with "
            f"equal weights instead, the default's median is {np.nanmedian(flat.reprojection):.1f}"
            f" px used, {np.nanmedian(all_views_error(flat)):.1f} px over all views; the "
            f"confidences of the observations used: median {np.nanmedian(conf_used):.2f}, "
            f"10th pct {np.nanpercentile(conf_used, 10):.2f}."
        )
        if variants:
            from visprim.io.video_pose import MediaPipePose

            print(
                "\nestimator settings (left/right check, every observation kept; the default "
                f"{np.nanmedian(swapped.reprojection):.1f} px median):"
            )
            for label, opts in VARIANTS.items():
                est = MediaPipePose(**opts)
                alt = [video_poses(v, est) for v in views]
                mv = triangulate_poses(alt, cameras, max_reprojection=None, **AS_READ)
                print(
                    f"- {label}: {np.nanmedian(mv.reprojection):.1f} px median, "
                    f"{np.nanpercentile(mv.reprojection, 90):.1f} px 90th pct"
                )

        print(
            "\n### the outlier threshold decides the 'used' figure\n\n"
            "| threshold (px) | used: median | used: 90th pct | all views: median | "
            "all views: 90th pct | observations left out | points lost |"
        )
        print("|---|---|---|---|---|---|---|")
        for thr in THRESHOLDS:
            mv = triangulate_poses(poses, cameras, max_reprojection=thr, **AS_READ)
            left = sum(mv.meta["rejected_per_view"]) / used0
            print(
                f"| {thr:g} | {_stats(mv.reprojection)} | {_stats(all_views_error(mv))} | "
                f"{100 * left:.1f} % | {100 * np.isnan(mv.points[..., 0]).mean():.1f} % |"
            )

        pairs = list(SIDE_PAIRS["blazepose33"])
        max_off = int(round(VIEWS_SYNC_MAX_OFFSET_S * rate))
        offs, rec = estimate_offsets(poses, cameras, max_offset=max_off, pairs=pairs)
        print(
            f"\n## synchronisation (sync=True): offsets estimated from the data, ±{max_off} "
            "frames\n\nper pair of views: the offset of the second against the first that "
            "minimises the symmetric epipolar distance (px; per keypoint the median over "
            "frames, mean over keypoints)"
        )
        print("| pair | offset (frames) | distance there (px) | at 0 (px) |")
        print("|---|---|---|---|")
        for key, r in rec["pairs"].items():
            a_, b_ = (int(x) for x in key.split("-"))
            print(
                f"| {views[a_].stem}–{views[b_].stem} | {r['offset']:+d} | "
                f"{r['distance_px']:.2f} | {r['distance_px_at_zero']:.2f} |"
            )
        synced = triangulate_poses(poses, cameras, sync=offs, **AS_READ)
        print(
            f"\noffsets (least squares over the pairs, vs {views[0].stem}): {offs}; "
            f"inconsistency between the pairs: {rec['inconsistency_frames']} frames (0 for a "
            "true shift of exact keypoints)"
        )
        print(
            "\n| views | used: median | used: 90th pct | all views: median | all views: 90th pct |"
        )
        print("|---|---|---|---|---|")
        for label, mv in (
            ("as recorded (sync=False, default)", robust),
            (f"offsets {offs}", synced),
        ):
            print(f"| {label} | {_stats(mv.reprojection)} | {_stats(all_views_error(mv))} |")
        figures["sync=True used median (px)"] = float(np.nanmedian(synced.reprojection))
        figures["sync=True all views median (px)"] = float(np.nanmedian(all_views_error(synced)))
        # Independent check: each single camera against the reference built with and
        # without the offsets (a view's own estimate does not depend on the others' timing).
        start = max(0, *(-o for o in offs))
        print(
            "\nsingle camera vs each reference, mean of the four bone RMS (°, body frame); "
            "the camera's frames matched to the reference's by its offset:"
        )
        print("| view | vs reference as recorded | vs reference with the offsets |")
        print("|---|---|---|")
        for vi, (v, q) in enumerate(zip(views, poses, strict=True)):
            cells = []
            for mv_, o_, s_ in ((robust, 0, 0), (synced, offs[vi], start)):
                m = mv_.points.shape[0]
                ref_pts = mv_.points
                rf = body_frame(ref_pts)
                ok_ref = np.isfinite(rf).all(axis=(1, 2))
                pts, ok = mono_points(shift(q, o_ + s_, 0, m), m)
                e = errors(bones(pts, body_frame(pts)), bones(ref_pts, rf), ok & ok_ref)
                cells.append(
                    np.mean(
                        [e[k_] for k_ in ("right_upper", "right_fore", "left_upper", "left_fore")]
                    )
                )
            print(f"| {v.stem} | {cells[0]:.1f} | {cells[1]:.1f} |")

        ref = robust.points
        ref_frame = body_frame(ref)
        ref_body = bones(ref, ref_frame)
        ref_world = bones(ref, None)
        ref_ok = np.isfinite(ref_frame).all(axis=(1, 2)) & np.isfinite(
            np.stack(list(ref_world.values()))
        ).all(axis=(0, 2))
        a, b = still_part(np.where(ref_ok[:, None, None], ref, np.nan), rate)
        print(
            "\n## each camera vs the four-view reference (both arms; RMS over confident frames)"
            "\n\nThe single view as read_video reads it: frames whose left/right labels the "
            "estimator exchanged are put back (visprim.io.video_sides; before/after below). "
            "body frame: directions relative to each skeleton's torso; world: the camera's "
            "directions rotated by its extrinsics (MediaPipe world axes ≈ camera axes)."
        )
        print(
            "| view | arm | frames | upper arm, body (°) | forearm, body (°) | elbow flexion (°) |"
            " upper arm, world (°) | forearm, world (°) | torso, world (°) |"
        )
        print("|---|---|---|---|---|---|---|---|---|")
        # Baseline: no per-frame information, the reference's own clip-mean directions.
        const_b = {
            k: np.broadcast_to(np.nanmean(_unit(x[ref_ok]), axis=0), x.shape)
            for k, x in ref_body.items()
        }
        const_w = {
            k: np.broadcast_to(np.nanmean(_unit(x[ref_ok]), axis=0), x.shape)
            for k, x in ref_world.items()
        }
        eb, ew = errors(const_b, ref_body, ref_ok), errors(const_w, ref_world, ref_ok)
        for side in ARMS:
            print(
                f"| baseline: constant (reference's clip mean) | {side} | {ref_ok.sum()} | "
                f"{eb[f'{side}_upper']:.1f} | {eb[f'{side}_fore']:.1f} | "
                f"{eb[f'{side}_flex']:.1f} | "
                f"{ew[f'{side}_upper']:.1f} | {ew[f'{side}_fore']:.1f} | — |"
            )
        monos = []
        raw_monos = []
        repaired = []
        for q in poses:
            q2, frames = repair_side_exchanges(q)
            repaired.append((q2, frames))
            raw_monos.append(mono_points(q, n))
        for v, (q, _), cam in zip(views, repaired, fitted, strict=True):
            pts, ok = mono_points(q, n)
            valid = ok & ref_ok
            monos.append((pts, valid))
            eb = errors(bones(pts, body_frame(pts)), ref_body, valid)
            figures[f"{v.stem}: bone RMS, mean of 4, body frame (°)"] = float(
                np.mean([eb[k_] for k_ in ("right_upper", "right_fore", "left_upper", "left_fore")])
            )
            world = {k: x @ cam.R for k, x in bones(pts, None).items()}  # R^T x, row-wise
            ew = errors(world, ref_world, valid)
            torso = _rms(
                rotation_angle(np.einsum("ji,tjk->tik", cam.R, body_frame(pts)), ref_frame)[valid]
            )
            for side in ARMS:
                print(
                    f"| {v.stem} | {side} | {valid.sum()} | {eb[f'{side}_upper']:.1f} | "
                    f"{eb[f'{side}_fore']:.1f} | {eb[f'{side}_flex']:.1f} | "
                    f"{ew[f'{side}_upper']:.1f} | {ew[f'{side}_fore']:.1f} | {torso:.1f} |"
                )

        npairs = len(SIDE_PAIRS["blazepose33"])
        four = ("right_upper", "right_fore", "left_upper", "left_fore")

        def mean4(p_: Array, sel: NDArray[np.bool_], cam: Camera | None = None) -> float:
            """Mean of the four bone RMS (°) on ``sel``: body frame, or world with ``cam``."""
            if not sel.any():
                return float("nan")
            if cam is not None:
                e = errors({k: x @ cam.R for k, x in bones(p_, None).items()}, ref_world, sel)
            else:
                e = errors(bones(p_, body_frame(p_)), ref_body, sel)
            return float(np.mean([e[k_] for k_ in four]))

        print(
            "\n### left/right exchanges in the single view: before / after the repair\n\n"
            "four-view flips: frames where the four-view check exchanged at least half of this "
            "view's left/right pairs (an independent judge: the other three views); repair: "
            "the frames the single-view rule (image continuity, visprim.io.video_sides) puts "
            "back, how many of them are four-view flips, and the four-view flips it misses. "
            "Error: mean of the four bone RMS (°), on the frames valid before and after."
        )
        print(
            "| view | four-view flips | repaired | of them four-view flips | missed | "
            "body: before | body: after | world: before | world: after |"
        )
        print("|---|---|---|---|---|---|---|---|---|")
        for vi, (v, (raw, raw_ok), (pts, valid), (_, frames), cam) in enumerate(
            zip(views, raw_monos, monos, repaired, fitted, strict=True)
        ):
            flip = robust.swapped[:, vi] * 2 >= npairs
            fr = frames[:n]
            both = valid & raw_ok & ref_ok
            print(
                f"| {v.stem} | {int((flip & both).sum())} of {int(both.sum())} | "
                f"{int((fr & both).sum())} | {int((fr & flip & both).sum())} | "
                f"{int((~fr & flip & both).sum())} | {mean4(raw, both):.1f} | "
                f"{mean4(pts, both):.1f} | {mean4(raw, both, cam):.1f} | "
                f"{mean4(pts, both, cam):.1f} |"
            )
            figures[f"{v.stem}: bone RMS, mean of 4, body frame, before the repair (°)"] = mean4(
                raw, both
            )

        need = [i for t_ in ARMS.values() for i in t_] + list(HIPS.values())
        three = ref_ok & (robust.views_used[:, need] >= 3).all(axis=1)
        print(
            "\n### does the comparison itself inflate the error?\n\n"
            "The single view (repaired) against the reference: in the body frame on every "
            "reference frame (the table above), on the frames whose reference arm and hip "
            f"points each come from ≥ 3 views ({int(three.sum())} of {int(ref_ok.sum())}; a "
            "point from 2 views cannot be checked by a third), in the world frame (no torso "
            "frame: the camera's directions rotated by its extrinsics), and the torso frame's "
            "own error (rotation angle between the two torso frames in the world, RMS)."
        )
        print(
            "| view | body, all frames | body, ≥ 3-view frames | world, all frames | "
            "world, ≥ 3-view frames | torso frame (°) |"
        )
        print("|---|---|---|---|---|---|")
        for v, (pts, valid), cam in zip(views, monos, fitted, strict=True):
            torso = _rms(
                rotation_angle(np.einsum("ji,tjk->tik", cam.R, body_frame(pts)), ref_frame)[valid]
            )
            print(
                f"| {v.stem} | {mean4(pts, valid):.1f} | {mean4(pts, valid & three):.1f} | "
                f"{mean4(pts, valid, cam):.1f} | {mean4(pts, valid & three, cam):.1f} | "
                f"{torso:.1f} |"
            )
            figures[f"{v.stem}: bone RMS, mean of 4, world frame (°)"] = mean4(pts, valid, cam)

        print(
            f"\n## jitter (high-pass residual of the bone directions, RMS, deg/frame)\n\n"
            f"still part (both reference wrists < {STILL_SPEED} m/s): "
            + (f"frames {a}–{b - 1}" if b - a >= 5 else f"none of ≥ 5 frames ({b - a} found)")
        )
        print("| source | right upper | right fore | left upper | left fore |")
        print("|---|---|---|---|---|")
        keys = ["right_upper", "right_fore", "left_upper", "left_fore"]
        rw = {k: np.where(ref_ok[:, None], x, np.nan) for k, x in ref_world.items()}
        print("| 4-view reference | " + " | ".join(f"{jitter(rw[k]):.2f}" for k in keys) + " |")
        for v, (pts, valid) in zip(views, monos, strict=True):
            bw = {k: np.where(valid[:, None], x, np.nan) for k, x in bones(pts, None).items()}
            print(f"| {v.stem} | " + " | ".join(f"{jitter(bw[k]):.2f}" for k in keys) + " |")

        times = poses[0].times[:n]
        held, none_ = smoothing(views, monos, times, ref_body, "the default reference")
        figures["smoothing, leave one camera out, mean (°)"] = held
        self_calibration(views, poses, cameras, monos, n, times, robust, whole, took, figures)
        load1 = os.getloadavg()
        print(f"\nload average at the end {load1[0]:.1f} / {load1[1]:.1f} / {load1[2]:.1f}")
    return buf.getvalue(), figures


def smoothing(
    views: list[Path],
    monos: list[tuple[Array, NDArray[np.bool_]]],
    times: Array,
    ref_body: dict[str, Array],
    label: str,
) -> tuple[float, float]:
    """The smoothing tables against one reference: error per camera and cutoff, and the
    cutoff chosen on three cameras, scored on the fourth. Returns the held-out mean and the
    mean without smoothing (°)."""
    keys = ["right_upper", "right_fore", "left_upper", "left_fore"]
    score = np.empty((len(views), len(CUTOFFS)))
    for vi, (pts, valid) in enumerate(monos):
        filled = fill_time(pts)
        for ci, fc in enumerate(CUTOFFS):
            sm = filled if fc is None else smooth_keypoints(times, filled, fc)
            sm = np.where(np.isfinite(pts), sm, np.nan)
            e = errors(bones(sm, body_frame(sm)), ref_body, valid)
            score[vi, ci] = np.mean([e[k] for k in keys])
    names = ["none" if c is None else f"{c:g} Hz" for c in CUTOFFS]
    print(
        f"\n## smoothing: single camera vs {label}, mean of the four bone RMS (°, body "
        f"frame), zero-phase Butterworth order {VIDEO_LOWPASS_ORDER} on the keypoints"
    )
    print("| view | " + " | ".join(names) + " |")
    print("|---|" + "---|" * len(names))
    for v, row in zip(views, score, strict=True):
        print(f"| {v.stem} | " + " | ".join(f"{x:.2f}" for x in row) + " |")
    print("\nleave one camera out (cutoff chosen on the other three, scored on this one):")
    print("| held-out view | chosen on the others | its error there (°) | no smoothing (°) |")
    print("|---|---|---|---|")
    chosen = []
    for vi, v in enumerate(views):
        others = np.delete(score, vi, axis=0).mean(axis=0)
        ci = int(np.argmin(others))
        chosen.append(ci)
        print(f"| {v.stem} | {names[ci]} | {score[vi, ci]:.2f} | {score[vi, 0]:.2f} |")
    held = [score[vi, ci] for vi, ci in enumerate(chosen)]
    print(
        f"| mean | | {np.mean(held):.2f} | {score[:, 0].mean():.2f} |\n\n"
        f"choices per fold: {[names[c] for c in chosen]}; on all four views the best is "
        f"{names[int(np.argmin(score.mean(axis=0)))]}"
    )
    return float(np.mean(held)), float(score[:, 0].mean())


FOUR = ("right_upper", "right_fore", "left_upper", "left_fore")


def mean4_vs(
    pts: Array,
    sel: NDArray[np.bool_],
    ref: Array,
    rot: Array | None = None,
) -> float:
    """Mean of the four bone RMS (°) of a single view's points against reference points
    ``ref`` (T, 33, 3) on frames ``sel``: body frame, or, with the camera's world → camera
    rotation per frame ``rot`` (T, 3, 3), the world frame."""
    if not sel.any():
        return float("nan")
    if rot is None:
        e = errors(bones(pts, body_frame(pts)), bones(ref, body_frame(ref)), sel)
    else:
        world = {k: np.einsum("ti,tij->tj", x, rot) for k, x in bones(pts, None).items()}
        e = errors(world, bones(ref, None), sel)
    return float(np.mean([e[k] for k in FOUR]))


def self_calibration(
    views: list[Path],
    poses: list[VideoPoses],
    cameras: list[Camera],
    monos: list[tuple[Array, NDArray[np.bool_]]],
    n: int,
    times: Array,
    robust: MultiView,
    whole: MultiView,
    took: float,
    figures: dict[str, float],
) -> None:
    """The self-calibration tables (``refine_calibration=``): fitted on one half of the
    clip, scored on the other, both ways; then read_views's own use on the whole clip."""
    h = n // 2
    halves = ((0, h), (h, n))
    tk = TRIAL_KEYPOINTS
    print(
        "\n## self-calibration (read_views(..., refine_calibration=True); "
        "visprim.io.refine)\n\n"
        "One rotation per camera (3 parameters each, about the camera's centre; intrinsics "
        "kept) fitted to the keypoints of one half of the clip, then scored on the *other* "
        f"half (frames 0–{h - 1} and {h}–{n - 1}), both ways. Reprojection medians (px): "
        "no rejection | used | all views, over all 33 keypoints and over the trial's 12. "
        "'gate': whether refine_rotations' own held-out check (the fitted half cut in two "
        "again) would apply it."
    )
    print(
        "| fitted on | scored on | rotation per camera (°) | gate | cameras | all 33: none | "
        "all 33: used | all 33: all views | trial 12: none | trial 12: used | "
        "trial 12: all views |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    cf_points = np.full_like(robust.points, np.nan)
    rot_cf = np.zeros((len(views), n, 3, 3))
    alle: dict[str, list[Array]] = {"QCA": [], "refined": []}
    rotations = []
    names = [v.stem for v in views]
    for fit_on, score_on in ((0, 1), (1, 0)):
        a, b = halves[fit_on]
        fit_poses = [window(q, a, b) for q in poses]
        loose_fit = triangulate_poses(fit_poses, cameras, max_reprojection=None, **AS_READ)
        ref = refine_rotations(loose_fit.cameras, loose_fit.pixels, loose_fit.confidence)
        cams_r = rotated(loose_fit.cameras, np.deg2rad(ref.rotation_deg))
        rotations.append(ref.rotation_deg)
        angles = ", ".join(f"{x:.2f}" for x in np.linalg.norm(ref.rotation_deg, axis=1))
        c, d = halves[score_on]
        sc_poses = [window(q, c, d) for q in poses]
        for label, cams in (("QCA", cameras), ("refined", cams_r)):
            loose = triangulate_poses(sc_poses, cams, max_reprojection=None, **AS_READ)
            rob = triangulate_poses(sc_poses, cams, **AS_READ)
            alle[label].append(all_views_error(rob))
            print(
                f"| {a}–{b - 1} | {c}–{d - 1} | {angles} | {'yes' if ref.applied else 'no'} | "
                f"{label} | {medians(loose, rob, list(range(33)))} | {medians(loose, rob, tk)} |"
            )
            if label == "refined":
                cf_points[c:d] = rob.points
                for vi, cam in enumerate(rob.cameras):
                    rot_cf[vi, c:d] = cam.R
    print(
        "\nrotation vectors (°, camera axes x tilt, y pan, z roll) per fold: "
        + "; ".join(
            f"fitted on {halves[f][0]}–{halves[f][1] - 1}: "
            + ", ".join(f"{names[vi]} {np.round(r, 2).tolist()}" for vi, r in enumerate(rv))
            for f, rv in enumerate(rotations)
        )
    )
    for label, parts in alle.items():
        e = np.concatenate(parts)
        figures[f"cross-fitted halves, {label}: all views median (px)"] = float(np.nanmedian(e))
        figures[f"cross-fitted halves, {label}: trial keypoints, all views median (px)"] = float(
            np.nanmedian(e[:, tk])
        )

    ref_ok = np.isfinite(body_frame(robust.points)).all(axis=(1, 2)) & np.isfinite(
        body_frame(cf_points)
    ).all(axis=(1, 2))
    print(
        "\nEach single camera (as read_video reads it) against the four-view reference built "
        "with the calibration as read, and against the reference whose cameras were refined "
        "on the other half (every frame held out), on the same frames; mean of the four bone "
        "RMS (°). World frame: the camera's directions turned by its extrinsics (refined ones "
        "for the refined reference)."
    )
    print(
        "| view | frames | body: QCA reference | body: refined reference | "
        "world: QCA reference | world: refined reference |"
    )
    print("|---|---|---|---|---|---|")
    for vi, (v, (pts, valid)) in enumerate(zip(views, monos, strict=True)):
        sel = valid & ref_ok
        r0 = np.broadcast_to(robust.cameras[vi].R, (n, 3, 3))
        cells = [
            mean4_vs(pts, sel, robust.points),
            mean4_vs(pts, sel, cf_points),
            mean4_vs(pts, sel, robust.points, r0),
            mean4_vs(pts, sel, cf_points, rot_cf[vi]),
        ]
        print(f"| {v.stem} | {int(sel.sum())} | " + " | ".join(f"{x:.1f}" for x in cells) + " |")
        figures[f"{v.stem}: bone RMS, body frame, vs cross-fitted refined reference (°)"] = cells[1]
    held, _ = smoothing(
        views,
        [(pts, valid & ref_ok) for pts, valid in monos],
        times,
        bones(cf_points, body_frame(cf_points)),
        "the cross-fitted refined reference",
    )
    figures["smoothing vs refined reference, leave one camera out, mean (°)"] = held

    loose_w = triangulate_poses(poses, whole.cameras, max_reprojection=None, **AS_READ)
    rec = whole.meta["refine_calibration"]
    print(
        "\nread_views(..., refine_calibration=True) on the whole clip (in-sample: fitted and "
        f"scored on the same frames): applied: {rec['applied']} ({rec['reason']}); rotation "
        f"per camera {rec['rotation_angle_deg']} °; its held-out check (cost per observation, "
        f"px², before → after): "
        + "; ".join(
            f"fitted on half {c['fitted_on_half']}: {c['cost_before']:.1f} → {c['cost_after']:.1f}"
            f" (consistent observations {c['consistent_before']} → {c['consistent_after']})"
            for c in rec["held_out"]
        )
        + f"; triangulation with it {took:.1f} s wall-clock (shared machine). Reprojection "
        "medians (px), no rejection | used | all views: all 33 "
        f"{medians(loose_w, whole, list(range(33)))}; "
        f"trial 12 {medians(loose_w, whole, tk)}."
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument(
        "--data", default=str(Path(__file__).resolve().parents[1].parent / "shared" / "data")
    )
    ap.add_argument("--out", help="also write the report to this file (atomically)")
    ap.add_argument(
        "--variants",
        action="store_true",
        help="also run the estimator with other settings (no landmark smoothing, still-image "
        "mode) and compare the views' agreement (doubles the pose estimation)",
    )
    ap.add_argument(
        "--runs",
        type=int,
        default=1,
        help="run the whole measurement (pose estimation included, fresh cache) this many "
        "times; the headline figures' median and range across runs lead the report",
    )
    ap.add_argument(
        "--cache-dir",
        help="keep the pose cache in this folder (reused across runs and invocations) instead "
        "of a fresh temporary one per run",
    )
    args = ap.parse_args()
    folder = Path(args.data) / "video" / "pose2sim_single_person"
    if not folder.is_dir():
        print(f"video_accuracy: {folder}: no such folder (the shared clip)", file=sys.stderr)
        return 2
    if args.runs < 1:
        print("video_accuracy: --runs must be >= 1", file=sys.stderr)
        return 2
    runs = []
    for _ in range(args.runs):
        if args.cache_dir:
            os.environ["VISPRIM_CACHE_DIR"] = args.cache_dir
            runs.append(report(folder, variants=args.variants))
            continue
        with tempfile.TemporaryDirectory(prefix="visprim-video-bench-") as tmp:
            os.environ["VISPRIM_CACHE_DIR"] = tmp
            runs.append(report(folder, variants=args.variants))
    text = runs[-1][0]
    head, sep, rest = text.partition("\n\nclip:")
    lines = [
        f"\n\n## headline figures over {args.runs} run(s) (pose estimation repeated each run; "
        "median [min – max]; the tables below are the last run)",
        "| figure | median | range |",
        "|---|---|---|",
    ]
    for key in runs[-1][1]:
        vals = np.array([r[1][key] for r in runs])
        lines.append(f"| {key} | {np.median(vals):.2f} | {vals.min():.2f} – {vals.max():.2f} |")
    text = head + "\n".join(lines) + sep + rest
    print(text, end="")
    if args.out:
        write_text(args.out, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
