"""Video → pose per frame → :class:`visprim.Trial` (the optional extra ``visprim[video]``).

>>> from visprim.io import read
>>> trial = read("clip.mp4")                       # right arm; .avi, .mov, .webm, .mkv too
>>> from visprim.io.video import read_video_pieces
>>> pieces = read_video_pieces("clip.mp4", arm="both", max_frames=300)

* The pose of each frame comes from a :class:`~visprim.io.video_pose.PoseEstimator`
  (default: MediaPipe BlazePose, full model, shipped in the wheel — no network), cached by
  file content and estimator settings (:mod:`visprim.io.video_pose`).
* Its metric, hip-centred world landmarks become the trial through
  :func:`visprim.io.keypoints.trial_pieces_from_keypoints`: shoulder, elbow, wrist and hand
  of each arm, the torso frame from shoulders and hips, the subject turned to face +x.
* Times come from the video's own clock (each frame's presentation timestamp).
* Frames where the estimator took the person for their mirror image (left and right labels
  exchanged) are put back, found by the image continuity of the limbs
  (:mod:`visprim.io.video_sides`; ``repair_sides=False`` keeps the estimator's labels).
* Frames without a person, and landmarks below ``min_confidence`` visibility, are gaps with
  the C3D policy (:mod:`visprim.io.gaps`): short ones filled, long ones split or refused.

People. The estimator follows one person. With several people in view where someone first
appears, the largest (by the bounding box of their landmarks) is person 0, the next largest
person 1, and so on; ``person=`` chooses one, and a warning names the file, the number of
people and the one followed (:mod:`visprim.io.video_pose` explains how people are found and
followed). A video where nobody is found raises :class:`~visprim.io.errors.ReadError` ("no
person found"); when the followed body jumps across the image between consecutive frames
(another person taken over), a warning names the frame.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from visprim.io.errors import ReadError
from visprim.io.keypoints import read_error, trial_pieces_from_keypoints
from visprim.io.video_pose import PoseEstimator, VideoPoses, video_poses
from visprim.io.video_sides import repair_side_exchanges
from visprim.params import VIDEO_REPAIR_SIDES
from visprim.trial import Trial

#: A jump of the hips' image position by more than this fraction of the image diagonal
#: between consecutive frames is reported as a possible change of person.
PERSON_JUMP = 0.15


def person_jumps(poses: VideoPoses, hips: tuple[int, int] = (23, 24)) -> list[int]:
    """Frames where the hips' image centre jumps more than :data:`PERSON_JUMP` × diagonal
    from the previous frame with a person."""
    centre = poses.image[:, list(hips)].mean(axis=1)
    diag = float(np.hypot(*poses.size)) or 1.0
    idx = np.flatnonzero(poses.found)
    if idx.size < 2:
        return []
    step = np.linalg.norm(np.diff(centre[idx], axis=0), axis=1)
    return [int(i) for i in idx[1:][step > PERSON_JUMP * diag]]


def read_video_pieces(
    path: str | os.PathLike[str],
    arm: str = "right",
    *,
    mirror: bool = False,
    estimator: PoseEstimator | None = None,
    person: int | None = None,
    workers: int | None = None,
    min_confidence: float = 0.5,
    max_frames: int | None = None,
    cache: bool = True,
    max_gap: float = 0.2,
    on_gap: str = "split",
    gap_method: str = "cubic",
    min_duration: float = 0.5,
    repair_sides: bool = VIDEO_REPAIR_SIDES,
) -> list[Trial]:
    """Trials from a video (several when long gaps without a person split it).

    Parameters
    ----------
    path : video file
    arm, mirror, max_gap, on_gap, gap_method, min_duration : as :func:`visprim.io.read_pieces`
    estimator : a :class:`~visprim.io.video_pose.PoseEstimator` (default MediaPipe)
    person : which person to follow when there are several (module docstring; None: 0,
        the largest)
    workers : 2: the two halves of the video at once
        (:func:`~visprim.io.video_pose.video_poses`)
    min_confidence : landmarks with a lower visibility are missing in that frame
    max_frames : only the first frames
    cache : use the pose cache
    repair_sides : put back frames whose left/right labels the estimator exchanged
        (:mod:`visprim.io.video_sides`; default :data:`visprim.params.VIDEO_REPAIR_SIDES`)
    """
    p = Path(path)
    poses = video_poses(
        p, estimator, max_frames=max_frames, cache=cache, person=person, workers=workers
    )
    n = poses.times.shape[0]
    found = int(poses.found.sum())
    if found == 0:
        raise ReadError(p, f"no person found in any of the {n} frames")
    layout = str(poses.meta["layout"])
    exchanged = 0
    if repair_sides:
        poses, frames = repair_side_exchanges(poses, min_confidence=min_confidence)
        exchanged = int(frames.sum())
    people = int(poses.meta.get("people", 0))
    if people > 1:
        at = poses.times[int(poses.meta["people_frame"])]
        warnings.warn(
            f"{p}: {people} people in view at {at:.2f} s; following person "
            f"{poses.meta['person']} ({'the largest' if poses.meta['person'] == 0 else 'person='}"
            "; people are numbered largest first, choose another with person=)",
            stacklevel=2,
        )
    if layout == "blazepose33":
        for i in person_jumps(poses):
            warnings.warn(
                f"{p}: the tracked person jumps across the image at frame {i} "
                f"({poses.times[i]:.2f} s); several people in view?",
                stacklevel=2,
            )
    meta: dict[str, Any] = {
        "format": "video",
        "rate": poses.meta["rate"],
        "times_from": poses.meta["times_from"],
        "estimator": poses.meta["estimator"],
        "video_size": poses.meta["size"],
        "frames": n,
        "person_found": found / n,
        "person": poses.meta.get("person", 0),
        "people": people,
        "pose_passes": poses.meta.get("passes"),
        "pose_cache": poses.meta.get("cache"),
        "side_exchanges_repaired": exchanged if repair_sides else None,
    }
    try:
        return trial_pieces_from_keypoints(
            poses.world,
            layout,
            times=poses.times,
            confidence=np.where(poses.found[:, None], poses.confidence, 0.0),
            min_confidence=min_confidence,
            arm=arm,
            up_axis=str(poses.meta["up_axis"]),
            mirror=mirror,
            max_gap=max_gap,
            on_gap=on_gap,
            gap_method=gap_method,
            min_duration=min_duration,
            name=p.stem,
            source=p,
            meta=meta,
        )
    except ReadError:
        raise
    except ValueError as exc:
        raise read_error(p, exc) from None
