"""Is the shared clip's calibration read right? Checks against Pose2Sim's own material.

    PYTHONPATH=python python benches/video_calibration_check.py --pose2sim GIT_DIR \\
        [--data ../shared/data] [--out FILE]

``GIT_DIR``: a git clone of github.com/perfanalytics/pose2sim (BSD-3; read with ``git show``,
nothing is copied into the repository). Used from it:

* ``HEAD:Pose2Sim/Demo_SinglePerson/calibration/extrinsics/cam0N_ext.png``: Pose2Sim's
  1088 × 1920 image of each camera (the frame its calibration refers to);
* ``bd9bbb6:Pose2Sim/S01_Demo_SingleTrial/pose/cam0N_json/cam0N.NNNN.json``: OpenPose
  BODY_25B keypoints of the same 100 frames, made by Pose2Sim's authors (an estimator
  independent of MediaPipe);
* ``eca0229:Pose2Sim/Demo_SinglePerson/calibration/Calib_scene.toml``: Pose2Sim's own
  calibration of the same cameras from a checkerboard (intrinsics) and 8 clicked scene points
  (extrinsics), independent of the QCA file.

Prints (``--out``: writes atomically) stamped tables:

1. **Frame registration.** SIFT matches between each video's first frame and Pose2Sim's image
   of that camera, an affine fit (RANSAC, 2 px) and a per-axis line fit on its inliers: how a
   calibrated pixel maps into the video (the rule of
   :meth:`visprim.io.calibration.Camera.fitted_to` beside it).
2. **Triangulation of two estimators through calibration variants.** Reprojection error
   (px, median) of the four-view triangulation of OpenPose's and MediaPipe's keypoints, with
   the left/right check, without outlier rejection and with the default 15 px rejection
   (used / all views), for: the QCA as read (each camera fitted to its frame), without
   fitting (the old reading), without distortion, with the distortion not divided by 64,
   and Pose2Sim's independent ``Calib_scene.toml``.
3. **What kind of calibration error is left.** Per-camera corrections fitted to OpenPose's
   keypoints (soft-L1 least squares, the points re-triangulated at each step) and scored on
   MediaPipe's (the other estimator): principal-point shifts (8 parameters), focal scale (4),
   roll about the optical axis (4), rotation (12). A correction that helps the other estimator
   is a property of the cameras, not of one estimator's keypoints.
4. **Self-calibration the other way round.** ``read_views``' ``refine_calibration``
   (:func:`visprim.io.refine.refine_rotations`) fitted on MediaPipe's keypoints, scored on
   OpenPose's.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import io
import json
import os
import subprocess
import sys
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
from _harness import commit, cpu_model
from numpy.typing import NDArray
from visprim import kernels
from visprim.atomic import write_text
from visprim.io.calibration import Camera, read_qca, read_toml, rodrigues
from visprim.io.refine import refine_rotations
from visprim.io.video_pose import video_poses
from visprim.io.views import SIDE_PAIRS, triangulate_keypoints

Array = NDArray[np.float64]
NAMES = ("cam01", "cam02", "cam03", "cam04")
#: BlazePose / BODY_25B indices of nose, shoulders, elbows, wrists, hips, knees, ankles (for
#: picking, per frame, the OpenPose person nearest MediaPipe's).
MP_CORE = [0, 11, 12, 13, 14, 15, 16, 23, 24, 25, 26, 27, 28]
OP_CORE = [0, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]
#: BODY_25B left/right pairs (eyes, ears, shoulders, elbows, wrists, hips, knees, ankles, feet).
OP_PAIRS = ((1, 2), (3, 4), (5, 6), (7, 8), (9, 10), (11, 12), (13, 14), (15, 16), (19, 22))
OP_PAIRS += ((20, 23), (21, 24))
OPENPOSE_COMMIT = "bd9bbb6"
OPENPOSE_DIR = "Pose2Sim/S01_Demo_SingleTrial/pose"
SCENE_COMMIT = "eca0229"
#: Pose2Sim's likelihood threshold for OpenPose keypoints (its Config.toml), and ours.
OP_MIN_CONF, MP_MIN_CONF = 0.3, 0.5


def git_show(git_dir: Path, spec: str) -> bytes:
    return subprocess.run(
        ["git", "--git-dir", str(git_dir), "show", spec], check=True, capture_output=True
    ).stdout


def registration(git_dir: Path, folder: Path) -> None:
    import cv2

    print("\n## 1. how a calibrated pixel maps into each video (SIFT registration)\n")
    print(
        "| view | video size | matches | inliers | u' = a·u + b | v' = c·v + d | residual RMS "
        "(px) | rule: a, b, c, d |"
    )
    print("|---|---|---|---|---|---|---|---|")
    cams = {c.name: c for c in read_qca(folder / "Calib.qca.txt")}
    for name in NAMES:
        png = git_show(
            git_dir, f"HEAD:Pose2Sim/Demo_SinglePerson/calibration/extrinsics/{name}_ext.png"
        )
        ref = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_GRAYSCALE)
        cap = cv2.VideoCapture(str(folder / f"{name}.mp4"))
        ok, frame = cap.read()
        cap.release()
        if not ok:
            raise SystemExit(f"{name}: no first frame")
        vid = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        sift = cv2.SIFT_create(4000)
        k1, d1 = sift.detectAndCompute(ref, None)
        k2, d2 = sift.detectAndCompute(vid, None)
        good = [
            a for a, b in cv2.BFMatcher().knnMatch(d1, d2, k=2) if a.distance < 0.7 * b.distance
        ]
        p1 = np.float32([k1[g.queryIdx].pt for g in good])
        p2 = np.float32([k2[g.trainIdx].pt for g in good])
        _, inl = cv2.estimateAffine2D(p1, p2, ransacReprojThreshold=2.0)
        m = inl.ravel().astype(bool)
        q1, q2 = p1[m], p2[m]
        fu, fv = np.polyfit(q1[:, 0], q2[:, 0], 1), np.polyfit(q1[:, 1], q2[:, 1], 1)
        res = np.c_[np.polyval(fu, q1[:, 0]) - q2[:, 0], np.polyval(fv, q1[:, 1]) - q2[:, 1]]
        cam = cams[name]
        h, w = vid.shape
        fitted = cam.fitted_to((w, h))
        # The rule as a line: K maps normalised x to s·f·x + c', so u' = s·u + (c' − s·c).
        s = fitted.K[0, 0] / cam.K[0, 0]
        rb = fitted.K[0, 2] - s * cam.K[0, 2]
        rd = fitted.K[1, 2] - s * cam.K[1, 2]
        print(
            f"| {name} | {w}×{h} | {len(good)} | {int(m.sum())} | {fu[0]:.5f}·u {fu[1]:+.2f} | "
            f"{fv[0]:.5f}·v {fv[1]:+.2f} | {np.sqrt(np.mean(res**2)):.2f} | "
            f"{s:.5f}, {rb:+.2f}, {s:.5f}, {rd:+.2f} |"
        )


def openpose(git_dir: Path, mp_image: Array) -> tuple[Array, Array]:
    """(T, 25, V, 2) px and (T, 25, V) confidences; per frame the person nearest MediaPipe's."""
    t = mp_image.shape[0]
    pix = np.full((t, 25, len(NAMES), 2), np.nan)
    conf = np.zeros((t, 25, len(NAMES)))
    for v, name in enumerate(NAMES):
        for f in range(t):
            spec = f"{OPENPOSE_COMMIT}:{OPENPOSE_DIR}/{name}_json/{name}.{f:04d}.json"
            people = json.loads(git_show(git_dir, spec))["people"]
            ref = np.nanmean(mp_image[f, MP_CORE, v], axis=0)
            best, dist = None, np.inf
            for person in people:
                a = np.array(person["pose_keypoints_2d"], dtype=np.float64).reshape(-1, 3)
                ok = a[:, 2] > 0
                if ok.sum() < 5:
                    continue
                d = float(np.linalg.norm(a[ok, :2].mean(axis=0) - ref))
                if d < dist:
                    best, dist = a, d
            if best is not None:
                ok = best[:, 2] > 0
                pix[f, ok, v] = best[ok, :2]
                conf[f, ok, v] = best[ok, 2]
    return pix, conf


def all_views(cams: list[Camera], points: Array, pixels: Array, conf: Array, mc: float) -> Array:
    e = np.stack(
        [np.linalg.norm(c.project(points) - pixels[:, :, i], axis=-1) for i, c in enumerate(cams)],
        axis=2,
    )
    return np.where(conf >= mc, e, np.nan)


def row(label: str, cams: list[Camera], data: dict[str, tuple[Array, Array, tuple, float]]) -> str:
    cells = []
    for pix, conf, pairs, mc in data.values():
        loose = triangulate_keypoints(
            cams, pix, conf, min_confidence=mc, pairs=pairs, max_reprojection=None
        )
        robust = triangulate_keypoints(cams, pix, conf, min_confidence=mc, pairs=pairs)
        every = all_views(cams, robust.points, robust.pixels, robust.confidence, mc)
        cells += [
            f"{np.nanmedian(loose.reprojection):.2f}",
            f"{np.nanmedian(robust.reprojection):.2f}",
            f"{np.nanmedian(every):.2f}",
        ]
    return f"| {label} | " + " | ".join(cells) + " |"


def corrected(cams: list[Camera], x: Array, kind: str) -> list[Camera]:
    out = []
    for i, c in enumerate(cams):
        k, r, t = c.K.copy(), c.R.copy(), c.t.copy()
        if kind == "principal point":
            k[0, 2] += x[2 * i]
            k[1, 2] += x[2 * i + 1]
        elif kind == "focal scale":
            k[0, 0] *= 1 + 1e-2 * x[i]
            k[1, 1] *= 1 + 1e-2 * x[i]
        else:
            vec = np.array([0.0, 0.0, x[i]]) if kind == "roll" else x[3 * i : 3 * i + 3]
            d = rodrigues(1e-2 * vec)
            r, t = d @ r, d @ t
        out.append(dataclasses.replace(c, K=k, R=r, t=t))
    return out


PARAMS = {"principal point": 8, "focal scale": 4, "roll": 4, "rotation": 12}


def fit(cams: list[Camera], pix: Array, conf: Array, mc: float, kind: str) -> Array:
    from scipy.optimize import least_squares

    def resid(x: Array) -> Array:
        cc = corrected(cams, x, kind)
        tr = triangulate_keypoints(cc, pix, conf, min_confidence=mc, max_reprojection=None)
        r = np.stack([cc[i].project(tr.points) - pix[:, :, i] for i in range(len(cc))], axis=2)
        ok = (conf >= mc) & np.isfinite(r).all(axis=-1)
        return np.concatenate([r[ok].ravel(), 0.01 * x])

    return np.asarray(
        least_squares(
            resid, np.zeros(PARAMS[kind]), loss="soft_l1", f_scale=5.0, diff_step=1e-3, max_nfev=40
        ).x
    )


def report(git_dir: Path, folder: Path) -> str:
    buf = io.StringIO()
    with redirect_stdout(buf):
        load = os.getloadavg()
        print(f"# calibration check — {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}")
        print(
            f"commit {commit()} · CPU {cpu_model()} · {os.cpu_count()} cores · instruction set "
            f"{kernels.instruction_set()} · load average {load[0]:.1f} / {load[1]:.1f} / "
            f"{load[2]:.1f} · Pose2Sim at {git_show(git_dir, 'HEAD').decode()[7:19]}"
        )
        registration(git_dir, folder)
        qca = read_qca(folder / "Calib.qca.txt")
        poses = [video_poses(folder / f"{n}.mp4") for n in NAMES]
        sizes = [q.size for q in poses]
        mp_pix = np.stack([q.image for q in poses], axis=2)
        mp_conf = np.stack([np.where(q.found[:, None], q.confidence, 0.0) for q in poses], axis=2)
        op_pix, op_conf = openpose(git_dir, mp_pix)
        data = {
            "openpose": (op_pix, op_conf, OP_PAIRS, OP_MIN_CONF),
            "mediapipe": (mp_pix, mp_conf, SIDE_PAIRS["blazepose33"], MP_MIN_CONF),
        }
        fitted = [c.fitted_to(s) for c, s in zip(qca, sizes, strict=True)]
        scene = read_toml_scene(git_dir)
        print(
            "\n## 2. four-view triangulation of two estimators, calibration variants\n\n"
            "reprojection error, median (px), with the left/right check: no outlier rejection | "
            "default (15 px) over the observations used | default over all views"
        )
        print(
            "| calibration | OpenPose: none | OpenPose: used | OpenPose: all views | "
            "MediaPipe: none | MediaPipe: used | MediaPipe: all views |"
        )
        print("|---|---|---|---|---|---|---|")
        unfitted = [dataclasses.replace(c, size=s) for c, s in zip(qca, sizes, strict=True)]
        variants = {
            "QCA, each camera fitted to its frame (as read_views)": fitted,
            "QCA, not fitted (the 1088-px calibration used on the 1080-px videos)": unfitted,
            "QCA fitted, no distortion": [dataclasses.replace(c, dist=np.zeros(5)) for c in fitted],
            "QCA fitted, distortion not divided by 64": [
                dataclasses.replace(c, dist=c.dist * np.array([64.0, 64, 64, 64, 1]))
                for c in fitted
            ],
            "Pose2Sim's Calib_scene.toml (checkerboard + 8 scene points), fitted": [
                c.fitted_to(s) for c, s in zip(scene, sizes, strict=True)
            ],
        }
        for label, cams in variants.items():
            print(row(label, cams, data))
        print(
            "\n## 3. per-camera corrections fitted on OpenPose, scored on both (MediaPipe: the "
            "held-out estimator)\n"
        )
        print(
            "| correction (parameters) | fitted values | OpenPose: none | OpenPose: used | "
            "OpenPose: all views | MediaPipe: none | MediaPipe: used | MediaPipe: all views |"
        )
        print("|---|---|---|---|---|---|---|---|")
        swapfix = triangulate_keypoints(
            fitted,
            op_pix,
            op_conf,
            min_confidence=OP_MIN_CONF,
            pairs=OP_PAIRS,
            max_reprojection=None,
        )
        for kind, npar in PARAMS.items():
            x = fit(fitted, swapfix.pixels, swapfix.confidence, OP_MIN_CONF, kind)
            scale = np.rad2deg(1e-2) if kind in ("roll", "rotation") else 1.0  # x: 1e-2 rad
            shown = np.round(x * scale, 2).tolist()
            r = row(f"{kind} ({npar})", corrected(fitted, x, kind), data)
            unit = "px" if kind == "principal point" else ("%" if kind == "focal scale" else "°")
            print(r.replace(" | ", f" | {shown} {unit} | ", 1))
        mp_swapfix = triangulate_keypoints(
            fitted,
            mp_pix,
            mp_conf,
            min_confidence=MP_MIN_CONF,
            pairs=SIDE_PAIRS["blazepose33"],
            max_reprojection=None,
        )
        ref = refine_rotations(fitted, mp_swapfix.pixels, mp_swapfix.confidence)
        print(
            "\n## 4. self-calibration fitted on MediaPipe (read_views(..., "
            "refine_calibration=True), visprim.io.refine), scored on OpenPose (the held-out "
            "estimator)\n"
        )
        print(
            "| calibration | rotation per camera (°) | OpenPose: none | OpenPose: used | "
            "OpenPose: all views | MediaPipe: none | MediaPipe: used | MediaPipe: all views |"
        )
        print("|---|---|---|---|---|---|---|---|")
        angles = np.round(np.linalg.norm(ref.rotation_deg, axis=1), 2).tolist()
        print(row("QCA fitted (as read)", fitted, data).replace(" | ", " | — | ", 1))
        print(
            row(f"refined (applied: {ref.applied})", ref.cameras, data).replace(
                " | ", f" | {angles} | ", 1
            )
        )
        print(f"\nload average at the end {' / '.join(f'{x:.1f}' for x in os.getloadavg())}")
    return buf.getvalue()


def read_toml_scene(git_dir: Path) -> list[Camera]:
    import tempfile

    text = git_show(
        git_dir, f"{SCENE_COMMIT}:Pose2Sim/Demo_SinglePerson/calibration/Calib_scene.toml"
    )
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "Calib_scene.toml"
        p.write_bytes(text)
        cams = read_toml(p)
    return [dataclasses.replace(c, name=n) for c, n in zip(cams, NAMES, strict=True)]


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--pose2sim", required=True, help="git directory of a Pose2Sim clone")
    ap.add_argument(
        "--data", default=str(Path(__file__).resolve().parents[1].parent / "shared" / "data")
    )
    ap.add_argument("--out", help="also write the report to this file (atomically)")
    args = ap.parse_args()
    folder = Path(args.data) / "video" / "pose2sim_single_person"
    if not folder.is_dir():
        print(f"video_calibration_check: {folder}: no such folder", file=sys.stderr)
        return 2
    text = report(Path(args.pose2sim), folder)
    print(text, end="")
    if args.out:
        write_text(args.out, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
