"""How the shared clip's frames map to its calibration, and what the views' disagreement is.

    PYTHONPATH=python python benches/video_frame_fit.py [--data DIR] [--cache-dir DIR] [--out FILE]

cam01/cam02's videos of the shared Pose2Sim clip are 1080 × 1920 px, their calibration
1088 × 1920. H.264 codes 1080 as 1088 and crops, so the frame could be the calibrated image
*cropped* (no scaling) rather than *scaled and centred* (letterbox, what
:meth:`visprim.io.calibration.Camera.fitted_to` assumes). Prints (and with ``--out`` writes
atomically) stamped tables (date, commit, CPU, instruction set, load average):

1. **The pixels.** Per view, the rows and columns at each edge of the median of the first
   :data:`BAND_FRAMES` frames whose mean grey level is below :data:`DARK_LEVEL` (black
   padding). A letterbox of 1088 → 1080 px leaves ``(1920 − 1920·1080/1088)/2 ≈ 7`` black
   rows above and below and no black columns; a crop leaves none.
2. **Frame-mapping hypotheses, held out.** For the views whose frame size differs from the
   calibration: letterbox (``fitted_to``), crop at the right/bottom (``K`` unchanged), crop
   at the left/top (principal point − 8 px in u), crop centred (− 4 px). Also the
   principal-point convention (every camera): as read, + ½ px, − ½ px. Each hypothesis is
   *chosen* on frames 0–49 by the all-views reprojection median of ``read_views``' default
   triangulation (calibration as read, 15 px outlier rule) and *scored* on frames 50–99,
   and the other way round; every hypothesis's medians on both halves are listed too.
3. **Leave one view out.** Each view's keypoints against the points triangulated from the
   other three (default pipeline, calibration as read): the median residual (px), one
   constant shift per view, a shift plus a time offset (``residual ≈ c + τ·velocity``,
   τ in frames: a synchronisation error shows as τ ≠ 0), and an affine map of the image
   (6 parameters: shift, scale, rotation, shear) fitted on one half of the frames and scored
   on the other (held out, both folds).
4. **Pairs.** Every pair of views triangulated alone (plain DLT, no outlier rule) and
   reprojected into each of the two other views: which views agree with which.
5. **How far a calibration can go.** A bundle adjustment of everything per camera but the
   lens distortion (rotation, centre, principal point, focal scale: 9 parameters each, 36 in
   all) fitted to MediaPipe's keypoints as :mod:`visprim.io.refine` fits rotations (soft-L1
   loss of scale :data:`visprim.io.refine.REFINE_LOSS_SCALE_PX`, points re-triangulated at
   every step, a weak prior of :data:`BA_PRIOR` per parameter for the gauge), then the
   default triangulation's medians: in-sample (fitted and scored on all frames: an estimate
   of the floor any calibration of these cameras reaches with these keypoints; not a strict
   bound, since the fit minimises the robust cost, not the median) and cross-fitted (fitted
   on one half, scored on the other). scipy's status 1–4 is convergence, 0 the evaluation
   limit (100, not counting the numeric Jacobian's).

The poses come from MediaPipe through the pose cache (``--cache-dir``: reuse one; else a
fresh temporary folder, the network runs once per view).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import io
import os
import sys
import tempfile
from collections.abc import Callable
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
from _harness import commit, cpu_model
from numpy.typing import NDArray
from video_accuracy import MIN_CONFIDENCE, window
from visprim import kernels
from visprim.atomic import write_text
from visprim.io.calibration import Camera, read_calibration
from visprim.io.video_pose import VideoPoses, video_poses
from visprim.io.views import _reproject, triangulate_poses

Array = NDArray[np.float64]
#: Mean grey level (0–255) below which an edge row or column counts as black padding
#: (the padding of these videos is 0–4 after compression; the picture's darkest edge rows
#: are above 60).
DARK_LEVEL = 20.0
#: Frames whose per-pixel median the band count is made on.
BAND_FRAMES = 10
HALVES = ((0, 50), (50, 100))


def dark_bands(path: Path) -> dict[str, int]:
    """Black rows/columns (top, bottom, left, right) at the edges of a video's first frames."""
    import cv2

    cap = cv2.VideoCapture(str(path))
    frames = []
    for _ in range(BAND_FRAMES):
        ok, f = cap.read()
        if not ok:
            break
        frames.append(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY).astype(np.float64))
    cap.release()
    g = np.median(np.stack(frames), axis=0)

    def run(levels: Array) -> int:
        n = 0
        while n < levels.size and levels[n] < DARK_LEVEL:
            n += 1
        return n

    rows, cols = g.mean(axis=1), g.mean(axis=0)
    return {
        "top": run(rows),
        "bottom": run(rows[::-1]),
        "left": run(cols),
        "right": run(cols[::-1]),
    }


def shifted(c: Camera, du: float, dv: float, size: tuple[int, int] | None = None) -> Camera:
    """The camera with its principal point moved by (du, dv) px (and its size set)."""
    k = c.K.copy()
    k[0, 2] += du
    k[1, 2] += dv
    return dataclasses.replace(c, K=k, size=(int(size[0]), int(size[1])) if size else c.size)


def cropped(where: str) -> Callable[[Camera, tuple[int, int]], Camera]:
    """A frame that is the calibrated image cropped (no scaling): ``where`` the rows/columns
    were cut: "right" (right/bottom: K unchanged), "left" (left/top), "centred"."""

    def fit(c: Camera, size: tuple[int, int]) -> Camera:
        if tuple(size) == tuple(c.size):
            return c
        cut = np.subtract(c.size, size).astype(np.float64)
        part = {"right": 0.0, "left": 1.0, "centred": 0.5}[where]
        return shifted(c, -part * cut[0], -part * cut[1], size)

    return fit


FRAME_MAPS: dict[str, Callable[[Camera, tuple[int, int]], Camera]] = {
    "letterbox (fitted_to, scaled 1080/1088 and centred)": lambda c, s: c.fitted_to(s),
    "crop at the right (K unchanged)": cropped("right"),
    "crop at the left (u − 8 px)": cropped("left"),
    "crop centred (u − 4 px)": cropped("centred"),
}
PRINCIPAL_POINT: dict[str, float] = {"as read": 0.0, "+ ½ px": 0.5, "− ½ px": -0.5}


def medians(poses: list[VideoPoses], cams: list[Camera]) -> tuple[float, float, list[float]]:
    """Used median, all-views median and all-views median per view (px) of the default
    triangulation with the calibration as read (the cameras already fitted to the frames)."""
    mv = triangulate_poses(poses, cams, refine_calibration=False)
    e = _reproject(mv.cameras, mv.points, mv.pixels)
    alle = np.where(mv.confidence >= MIN_CONFIDENCE, e, np.nan)
    per = [float(np.nanmedian(alle[:, :, i])) for i in range(len(cams))]
    return float(np.nanmedian(mv.reprojection)), float(np.nanmedian(alle)), per


def hypothesis_table(
    title: str, variants: dict[str, list[Camera]], poses: list[VideoPoses]
) -> None:
    """Every variant's medians on both halves, then the choice on one half scored on the other."""
    print(f"\n### {title}\n")
    print("| hypothesis | frames | used median | all views median | all views per view |")
    print("|---|---|---|---|---|")
    got: dict[tuple[str, int], float] = {}
    for name, cams in variants.items():
        for h, (a, b) in enumerate(HALVES):
            u, al, per = medians([window(q, a, b) for q in poses], cams)
            got[(name, h)] = al
            print(
                f"| {name} | {a}–{b - 1} | {u:.2f} | {al:.2f} | "
                f"{', '.join(f'{x:.1f}' for x in per)} |"
            )
    print(
        "\n| chosen on | chosen (lowest all-views median there) | scored on "
        "| its all-views median there | best there |"
    )
    print("|---|---|---|---|---|")
    for h in (0, 1):
        pick = min(variants, key=lambda n: got[(n, h)])
        o = 1 - h
        best = min(variants, key=lambda n: got[(n, o)])
        a, b = HALVES[h]
        c, d = HALVES[o]
        print(
            f"| {a}–{b - 1} | {pick} | {c}–{d - 1} | {got[(pick, o)]:.2f} | "
            f"{best}: {got[(best, o)]:.2f} |"
        )


def leave_one_out(poses: list[VideoPoses], cams: list[Camera]) -> None:
    """Each view against the other three's triangulation (see the module docstring, 3.)."""
    full = triangulate_poses(poses, cams, refine_calibration=False)
    fc = full.cameras
    print("\n## 3. each view against the other three (leave one view out; px)\n")
    print(
        "| view | observations | median residual | constant shift (u, v) | median after it | "
        "shift + time offset: τ (frames) | median after it | affine, held out: before → after "
        "(fit 0–49 / fit 50–99) | affine scale, rotation (°) (fit 0–49 / 50–99) |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for v in range(len(poses)):
        others = [i for i in range(len(poses)) if i != v]
        mv = triangulate_poses(
            [poses[i] for i in others], [cams[i] for i in others], refine_calibration=False
        )
        pred = fc[v].project(mv.points)
        obs = full.pixels[:, :, v]
        vel = np.full_like(obs, np.nan)
        vel[1:-1] = (obs[2:] - obs[:-2]) / 2
        ok = (
            (full.confidence[:, :, v] >= MIN_CONFIDENCE)
            & np.isfinite(pred).all(-1)
            & np.isfinite(obs).all(-1)
        )
        okv = ok & np.isfinite(vel).all(-1)
        res = obs - pred
        r, ve = res[okv], vel[okv]
        x = np.zeros((2 * len(r), 3))
        x[0::2, 0] = 1.0
        x[1::2, 1] = 1.0
        x[0::2, 2] = ve[:, 0]
        x[1::2, 2] = ve[:, 1]
        full_sol = np.asarray(np.linalg.lstsq(x, r.ravel(), rcond=None)[0], dtype=np.float64)
        shift_sol = np.asarray(
            np.linalg.lstsq(x[:, :2], r.ravel(), rcond=None)[0], dtype=np.float64
        )

        def after(xx: Array, sol: Array, rr: Array = r) -> float:
            return float(np.median(np.linalg.norm((rr.ravel() - xx @ sol).reshape(-1, 2), axis=1)))

        c0 = fc[v].K[:2, 2]
        held, shape = [], []
        for h, (a, b) in enumerate(HALVES):
            fit = ok.copy()
            fit[:a] = False
            fit[b:] = False
            c, d = HALVES[1 - h]
            test = ok.copy()
            test[:c] = False
            test[d:] = False
            p_fit, o_fit = pred[fit] - c0, obs[fit] - c0
            m = np.linalg.lstsq(np.c_[p_fit, np.ones(len(p_fit))], o_fit, rcond=None)[0]
            p_t, o_t = pred[test] - c0, obs[test] - c0
            before = np.median(np.linalg.norm(o_t - p_t, axis=1))
            aft = np.median(np.linalg.norm(np.c_[p_t, np.ones(len(p_t))] @ m - o_t, axis=1))
            held.append(f"{before:.1f} → {aft:.1f}")
            lin = m[:2].T
            scale = np.sqrt(abs(np.linalg.det(lin)))
            rot = np.degrees(np.arctan2(lin[1, 0] - lin[0, 1], lin[0, 0] + lin[1, 1]))
            shape.append(f"{scale:.3f}, {rot:+.2f}")
        print(
            f"| {fc[v].name} | {int(ok.sum())} | "
            f"{np.median(np.linalg.norm(res[ok], axis=1)):.1f} | "
            f"({shift_sol[0]:+.1f}, {shift_sol[1]:+.1f}) | {after(x[:, :2], shift_sol):.1f} | "
            f"{full_sol[2]:+.2f} | {after(x, full_sol):.1f} | {' / '.join(held)} | "
            f"{' / '.join(shape)} |"
        )


def pairs_table(poses: list[VideoPoses], cams: list[Camera]) -> None:
    """Each pair of views triangulated alone, reprojected into the others (see 4.)."""
    full = triangulate_poses(poses, cams, refine_calibration=False)
    fc = full.cameras
    v = len(poses)
    print("\n## 4. each pair of views alone, reprojected into the other views (px)\n")
    print(
        "| pair | the pair's own median | "
        + " | ".join(f"{c.name}: median, median (u, v)" for c in fc)
        + " |"
    )
    print("|---|---|" + "---|" * v)
    for a in range(v):
        for b in range(a + 1, v):
            mv = triangulate_poses(
                [poses[a], poses[b]],
                [cams[a], cams[b]],
                refine_calibration=False,
                max_reprojection=None,
            )
            cells = []
            for w in range(v):
                if w in (a, b):
                    cells.append("—")
                    continue
                pred = fc[w].project(mv.points)
                obs = full.pixels[:, :, w]
                ok = (full.confidence[:, :, w] >= MIN_CONFIDENCE) & np.isfinite(pred).all(-1)
                r = obs[ok] - pred[ok]
                m = np.median(r, axis=0)
                cells.append(
                    f"{np.median(np.linalg.norm(r, axis=1)):.1f}, ({m[0]:+.1f}, {m[1]:+.1f})"
                )
            print(
                f"| {fc[a].name} + {fc[b].name} | {np.nanmedian(mv.reprojection):.1f} | "
                + " | ".join(cells)
                + " |"
            )


#: Prior standard deviations of the bundle adjustment (§5), per parameter: rotation (deg),
#: centre (m), principal point (px), focal scale (fraction). Weak: they fix the gauge (the
#: scene's position, turn and scale, which reprojection cannot see), hardly more.
BA_PRIOR = {"rotation": 2.0, "centre": 0.1, "principal point": 30.0, "focal": 0.05}


def adjusted(cams: list[Camera], x: Array) -> list[Camera]:
    """The cameras with the bundle-adjustment parameters ``x`` (V·9, in prior units)."""
    from visprim.io.calibration import rodrigues

    out = []
    for c, p in zip(cams, x.reshape(len(cams), 9), strict=True):
        rot = rodrigues(np.deg2rad(p[:3] * BA_PRIOR["rotation"])) @ c.R
        centre = c.centre + p[3:6] * BA_PRIOR["centre"]
        k = c.K.copy()
        k[0, 0] *= 1 + p[8] * BA_PRIOR["focal"]
        k[1, 1] *= 1 + p[8] * BA_PRIOR["focal"]
        k[0, 2] += p[6] * BA_PRIOR["principal point"]
        k[1, 2] += p[7] * BA_PRIOR["principal point"]
        out.append(dataclasses.replace(c, R=rot, t=-rot @ centre, K=k))
    return out


def bundle_adjust(cams: list[Camera], poses: list[VideoPoses]) -> tuple[list[Camera], str]:
    """§5: every camera parameter but the distortion fitted to the poses' keypoints; the
    cameras and the solver's iterations and status."""
    from scipy.optimize import least_squares
    from visprim.io.refine import REFINE_LOSS_SCALE_PX, _observations, _residuals

    first = triangulate_poses(poses, cams, refine_calibration=False, max_reprojection=None)
    pix, w = _observations(first.pixels, first.confidence, MIN_CONFIDENCE)
    used = w > 0
    base = first.cameras
    scale = REFINE_LOSS_SCALE_PX

    def resid(x: Array) -> Array:
        moved = adjusted(base, x)
        r = _residuals(moved, pix, w)  # undistorts with the moved K: K is a parameter
        return np.concatenate([r[used].ravel(), scale * x])

    sol = least_squares(resid, np.zeros(9 * len(cams)), loss="soft_l1", f_scale=scale, max_nfev=100)
    return adjusted(base, np.asarray(sol.x)), f"{sol.nfev} ({sol.status})"


def bound_table(poses: list[VideoPoses], cams: list[Camera]) -> None:
    """§5: the default triangulation's medians with the bundle-adjusted cameras."""
    print(
        "\n## 5. how far a calibration can go: every camera parameter but the distortion fitted\n"
    )
    print(
        "| cameras | fitted on | scored on | used median | all views median | all views per view "
        "| evaluations (scipy status) |"
    )
    print("|---|---|---|---|---|---|---|")
    fitted = [c.fitted_to(q.size) for c, q in zip(cams, poses, strict=True)]
    u, al, per = medians(poses, fitted)
    row = ", ".join(f"{x:.1f}" for x in per)
    print(f"| as read | — | 0–99 | {u:.2f} | {al:.2f} | {row} | — |")
    ba, info = bundle_adjust(fitted, poses)
    u, al, per = medians(poses, ba)
    row = ", ".join(f"{x:.1f}" for x in per)
    print(f"| bundle-adjusted (in-sample) | 0–99 | 0–99 | {u:.2f} | {al:.2f} | {row} | {info} |")
    for h, (a, b) in enumerate(HALVES):
        c, d = HALVES[1 - h]
        ba, info = bundle_adjust(fitted, [window(q, a, b) for q in poses])
        u, al, per = medians([window(q, c, d) for q in poses], ba)
        row = ", ".join(f"{x:.1f}" for x in per)
        print(
            f"| bundle-adjusted | {a}–{b - 1} | {c}–{d - 1} | {u:.2f} | {al:.2f} | {row} | {info} |"
        )


def report(folder: Path) -> str:
    names = [f"cam0{i}" for i in (1, 2, 3, 4)]
    calib = read_calibration(folder / "Calib.qca.txt")
    poses = [video_poses(folder / f"{n}.mp4") for n in names]
    buf = io.StringIO()
    with redirect_stdout(buf):
        print(f"# video frame fit — {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M UTC}")
        la = os.getloadavg()
        print(
            f"commit {commit()} · CPU {cpu_model()} · instruction set {kernels.instruction_set()} "
            f"· load average {la[0]:.1f} / {la[1]:.1f} / {la[2]:.1f} (1/5/15 min; shared machine)"
        )
        print(
            "\n## 1. black padding at the frame edges (rows / columns darker than "
            f"{DARK_LEVEL:g} of 255, median of the first {BAND_FRAMES} frames)\n"
        )
        print(
            "| view | video size | calibrated size | top | bottom | left | right "
            "| letterbox predicts (rows top/bottom) |"
        )
        print("|---|---|---|---|---|---|---|---|")
        for n, q, c in zip(names, poses, calib, strict=True):
            b = dark_bands(folder / f"{n}.mp4")
            s = min(q.size[0] / c.size[0], q.size[1] / c.size[1])
            pad = (q.size[1] - s * c.size[1]) / 2
            print(
                f"| {n} | {q.size[0]}×{q.size[1]} | {c.size[0]}×{c.size[1]} | {b['top']} | "
                f"{b['bottom']} | {b['left']} | {b['right']} | {pad:.2f} |"
            )
        print("\n## 2. hypotheses, chosen on one half of the frames, scored on the other")
        maps = {
            k: [f(c, q.size) for c, q in zip(calib, poses, strict=True)]
            for k, f in FRAME_MAPS.items()
        }
        hypothesis_table("how a 1080-px frame maps to the 1088-px calibration", maps, poses)
        fitted = maps[next(iter(FRAME_MAPS))]
        pps = {k: [shifted(c, d, d) for c in fitted] for k, d in PRINCIPAL_POINT.items()}
        hypothesis_table("principal-point convention (every camera; letterbox)", pps, poses)
        leave_one_out(poses, calib)
        pairs_table(poses, calib)
        bound_table(poses, calib)
        la = os.getloadavg()
        print(f"\nload average at the end {la[0]:.1f} / {la[1]:.1f} / {la[2]:.1f}")
    return buf.getvalue()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--data", default=str(Path(__file__).resolve().parents[1].parent / "shared" / "data")
    )
    ap.add_argument("--out", help="also write the report to this file (atomically)")
    ap.add_argument("--cache-dir", help="reuse the pose cache in this folder")
    args = ap.parse_args()
    folder = Path(args.data) / "video" / "pose2sim_single_person"
    if not folder.is_dir():
        print(f"video_frame_fit: {folder}: no such folder (the shared clip)", file=sys.stderr)
        return 2
    if args.cache_dir:
        os.environ["VISPRIM_CACHE_DIR"] = args.cache_dir
        text = report(folder)
    else:
        with tempfile.TemporaryDirectory(prefix="visprim-frame-fit-") as tmp:
            os.environ["VISPRIM_CACHE_DIR"] = tmp
            text = report(folder)
    print(text, end="")
    if args.out:
        write_text(args.out, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
