"""Left/right exchanges of a single view's keypoints, found by temporal continuity and put back.

A monocular pose estimator sometimes takes a person for their mirror image: seen from behind
(or side-on), MediaPipe BlazePose labels the left shoulder, elbow, wrist, hip, ... as the
right ones and the right as the left, for a run of frames, then switches back. The image
positions stay where the body is; only the labels exchange, abruptly, between two frames.
On the shared Pose2Sim clip it happens in 29 of cam02's 96 frames (the four-view check of
:mod:`visprim.io.views` sees it), and it is the largest single error of that camera.

The rule (:func:`side_exchanges`), per run of consecutive frames with a person:

1. Between each frame and the previous decisive one (``p``; see below), compare the image
   positions of the left/right pairs of the limbs and torso (:data:`CONTINUITY_PAIRS`:
   shoulders, elbows, wrists, hips, knees, ankles) both ways:
   ``keep = Σ w (‖L_t − L_p‖ + ‖R_t − R_p‖)`` and ``cross = Σ w (‖L_t − R_p‖ + ‖R_t − L_p‖)``,
   ``w`` the lower confidence of the two frames (pairs below
   ``min_confidence`` in either frame are left out). The labels exchanged between the two
   frames when ``cross < EXCHANGE_RATIO · keep`` (the points much nearer their opposites'
   previous places than their own), and were kept when ``keep < EXCHANGE_RATIO · cross``.
   Otherwise the frame is ambiguous (left and right overlap in the image: a person seen
   side-on, or turning): it keeps the previous labelling and the next frames are compared
   with the last decisive frame instead, so an exchange spread over a turn is still seen
   once the sides separate again.
2. Each exchange toggles a state; the frames of the run fall into two labellings. The
   estimator is taken to be right in the larger one (by frame count; ties keep the run's first
   labelling), and the frames of the smaller one are put back.

Put back (:func:`repair_side_exchanges`) means: the left/right keypoints of every pair of the
layout (:data:`visprim.io.views.SIDE_PAIRS`) exchanged in the image, the confidences and the
world landmarks, and the world landmarks' depth reflected (``z → −z`` about the hips: the
mirror body that projects to the same image is the true one reflected through the image
plane; exchanging the labels alone would leave a body facing backwards). MediaPipe's world
landmarks are hip-centred with camera-aligned axes, so depth is their z.

Limits: an exchange that happens while left and right overlap in the image is not seen
(continuity cannot tell), and a run where the estimator is wrong in most frames is put back
the wrong way (the majority rule). No clip-specific constant: the ratio is a property of the
rule (how much nearer the opposite side must be), not of a video.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from visprim.io.video_pose import VideoPoses

__all__ = [
    "CONTINUITY_PAIRS",
    "EXCHANGE_RATIO",
    "repair_side_exchanges",
    "side_exchanges",
]

#: Left/right pairs (left index, right index) whose image continuity decides, per layout:
#: shoulders, elbows, wrists, hips, knees, ankles.
CONTINUITY_PAIRS: dict[str, tuple[tuple[int, int], ...]] = {
    "blazepose33": ((11, 12), (13, 14), (15, 16), (23, 24), (25, 26), (27, 28)),
    "coco17": ((5, 6), (7, 8), (9, 10), (11, 12), (13, 14), (15, 16)),
    "h36m17": ((11, 14), (12, 15), (13, 16), (4, 1), (5, 2), (6, 3)),
}
#: The hips (left, right) per layout: the depth reflection's centre.
HIPS: dict[str, tuple[int, int]] = {"blazepose33": (23, 24), "coco17": (11, 12), "h36m17": (4, 1)}
#: An exchange between two frames: the cross distance below this fraction of the kept one.
EXCHANGE_RATIO = 0.5


def side_exchanges(
    image: NDArray[np.float64],
    confidence: NDArray[np.float64],
    found: NDArray[np.bool_],
    pairs: tuple[tuple[int, int], ...],
    *,
    min_confidence: float = 0.5,
) -> NDArray[np.bool_]:
    """Frames (T,) whose left/right labels are to be exchanged (see the module docstring).

    ``image`` (T, K, 2) px, ``confidence`` (T, K), ``found`` (T,) frames with a person,
    ``pairs`` the (left, right) indices that decide.
    """
    t = image.shape[0]
    out = np.zeros(t, dtype=bool)
    if not pairs or t == 0:
        return out
    left = np.array([a for a, _ in pairs])
    right = np.array([b for _, b in pairs])
    state = np.zeros(t, dtype=bool)
    runs: list[list[int]] = []
    prev: int | None = None
    for i in range(t):
        if not found[i]:
            prev = None
            continue
        if prev is None:
            runs.append([i])
            prev = i
            continue
        # prev: the last decisive frame of this run.
        lp, rp, lt, rt = image[prev, left], image[prev, right], image[i, left], image[i, right]
        w = np.minimum.reduce(
            [
                confidence[prev, left],
                confidence[prev, right],
                confidence[i, left],
                confidence[i, right],
            ]
        )
        ok = (w >= min_confidence) & np.isfinite(lp + rp + lt + rt).all(axis=1)
        runs[-1].append(i)
        state[i] = state[prev]
        if not ok.any():
            continue
        keep = np.sum(
            w[ok] * (np.linalg.norm(lt - lp, axis=1) + np.linalg.norm(rt - rp, axis=1))[ok]
        )
        cross = np.sum(
            w[ok] * (np.linalg.norm(lt - rp, axis=1) + np.linalg.norm(rt - lp, axis=1))[ok]
        )
        if cross < EXCHANGE_RATIO * keep:
            state[i] = ~state[prev]
        elif not keep < EXCHANGE_RATIO * cross:
            continue  # ambiguous: keep comparing with the last decisive frame
        prev = i
    for run in runs:
        s = state[run]
        minority = bool(s.sum() * 2 > s.size)  # True: the run's first labelling is the smaller
        out[run] = s != minority
    return out


def repair_side_exchanges(
    poses: VideoPoses,
    pairs: tuple[tuple[int, int], ...] | None = None,
    *,
    min_confidence: float = 0.5,
    reflect_depth: bool = True,
) -> tuple[VideoPoses, NDArray[np.bool_]]:
    """``poses`` with the frames of :func:`side_exchanges` put back (module docstring), and
    those frames (T,). ``pairs``: the deciding pairs (default: :data:`CONTINUITY_PAIRS` of the
    layout; a layout without them is returned unchanged); ``reflect_depth``: also reflect the
    world landmarks' depth about the hips (the default; False exchanges the labels only)."""
    from visprim.io.views import SIDE_PAIRS

    layout = str(poses.meta.get("layout", ""))
    decide = CONTINUITY_PAIRS.get(layout, ()) if pairs is None else pairs
    frames = side_exchanges(
        poses.image, poses.confidence, poses.found, decide, min_confidence=min_confidence
    )
    if not frames.any():
        return poses, frames
    image, world, conf = poses.image.copy(), poses.world.copy(), poses.confidence.copy()
    for a, b in SIDE_PAIRS.get(layout, decide):
        for arr in (image, world, conf):
            arr[frames, a], arr[frames, b] = arr[frames, b].copy(), arr[frames, a].copy()
    if reflect_depth:
        hips = HIPS.get(layout)
        centre = world[frames][:, list(hips), 2].mean(axis=1, keepdims=True) if hips else 0.0
        world[frames, :, 2] = 2 * centre - world[frames, :, 2]
    meta = dict(poses.meta)
    meta["side_exchanges"] = int(frames.sum())
    return (
        dataclasses.replace(poses, image=image, world=world, confidence=conf, meta=meta),
        frames,
    )
