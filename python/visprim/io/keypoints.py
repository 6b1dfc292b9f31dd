"""Keypoints from any pose estimator → :class:`visprim.Trial`.

>>> from visprim.io.keypoints import trial_from_keypoints
>>> trial = trial_from_keypoints(points, layout="coco17", rate=30.0, confidence=scores,
...                              up_axis="-y", arm="right")          # doctest: +SKIP

``points`` are 3-D keypoints per frame, ``(T, K, 3)`` (or a ``{name: (T, 3)}`` mapping), in
the estimator's order. The *layout* says which keypoint is which:

* ``"blazepose33"`` — MediaPipe / BlazePose, 33 landmarks (11/12 shoulders, 13/14 elbows,
  15/16 wrists, 17–22 pinky/index/thumb, 23/24 hips; even = right);
* ``"coco17"`` — COCO / MMPose / YOLO-pose, 17 keypoints (5/6 shoulders, 7/8 elbows,
  9/10 wrists, 11/12 hips; even = right);
* ``"h36m17"`` — Human3.6M 17 joints as VideoPose3D / MotionBERT output them (1 right hip,
  4 left hip, 11–13 left shoulder/elbow/wrist, 14–16 right shoulder/elbow/wrist);
* a mapping ``{role: name or index, or a list of them (their centroid)}`` with the roles of
  :data:`ROLES`, e.g. ``{"right_shoulder": "RShoulder", ..., "right_hand": ["RIndex",
  "RPinky"]}`` (names need ``names=`` or a ``{name: array}`` input);
* ``"names"`` — match keypoint names against the usual spellings (``RShoulder``,
  ``right_shoulder``, ``R_Shoulder``...; what the TRC reader uses).

What the trial gets
-------------------
* joints: each arm's shoulder, elbow and wrist keypoints as the joint centres (estimators
  are trained to put them on the joint centres, not on the skin);
* hand (the method's finger sensor, the middle-finger knuckle): the centroid of the
  estimator's hand points when the layout has them (BlazePose: index and pinky knuckles,
  17–20), else extrapolated along the forearm, ``wrist + FINGER_RATIO × forearm``
  (:data:`visprim.io.assemble.FINGER_RATIO`; the method has no wrist degree of freedom, so
  this loses nothing IK uses);
* torso frame: z from mid-hip to mid-shoulder, y from the right side (mean of right shoulder
  and right hip) to the left side; then the recording is turned so the subject faces +x at
  the first frame, as for every reader (:func:`visprim.io.assemble.align_heading`). Without
  both hips in the layout there is no torso frame (``body_frame`` None);
* axes and units: ``up_axis`` names the estimator's vertical (MediaPipe world landmarks:
  ``"-y"``, image y points down; OpenSim TRC: ``"+y"``), ``units`` its length unit.

Confidence and gaps
-------------------
A keypoint whose ``confidence`` (MediaPipe ``visibility``, COCO score; (T, K) in [0, 1]) is
below ``min_confidence`` (default 0.5), or which is NaN, is missing in that frame. Missing
frames are handled exactly as C3D marker gaps (:mod:`visprim.io.gaps`): gaps up to
``max_gap`` seconds are interpolated, longer ones split the recording (``on_gap="split"``),
keep the longest piece (``"longest"``) or raise :class:`~visprim.io.errors.GapError`
(``"raise"``). Every point the requested arms and the torso need counts.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim.io.assemble import (
    FINGER_RATIO,
    ArmRecording,
    align_heading,
    check_frame_period,
    check_up_axis,
    extend_hand,
    torso_frame,
    up_rotation,
)
from visprim.io.errors import GapError, MalformedFileError, MissingPointError, ReadError
from visprim.io.gaps import check_gap_options, fill_and_split
from visprim.io.presets import check_arm
from visprim.trial import Trial, TrialError

__all__ = [
    "LAYOUTS",
    "ROLES",
    "resolve_layout",
    "trial_from_keypoints",
    "smooth_keypoints",
    "trial_pieces_from_keypoints",
]

#: The roles a layout may fill. Shoulder, elbow and wrist of the requested arm(s) are
#: required; the hand and the hips are optional (see the module docstring).
ROLES: tuple[str, ...] = tuple(
    f"{side}_{part}"
    for side in ("right", "left")
    for part in ("shoulder", "elbow", "wrist", "hand", "hip")
)

Index = int | str
RoleSpec = Index | Sequence[Index]

#: Built-in layouts: role → keypoint index (or indices, whose centroid is used).
LAYOUTS: dict[str, dict[str, RoleSpec]] = {
    "blazepose33": {
        "right_shoulder": 12,
        "right_elbow": 14,
        "right_wrist": 16,
        "right_hand": (18, 20),
        "right_hip": 24,
        "left_shoulder": 11,
        "left_elbow": 13,
        "left_wrist": 15,
        "left_hand": (17, 19),
        "left_hip": 23,
    },
    "coco17": {
        "right_shoulder": 6,
        "right_elbow": 8,
        "right_wrist": 10,
        "right_hip": 12,
        "left_shoulder": 5,
        "left_elbow": 7,
        "left_wrist": 9,
        "left_hip": 11,
    },
    "h36m17": {
        "right_shoulder": 14,
        "right_elbow": 15,
        "right_wrist": 16,
        "right_hip": 1,
        "left_shoulder": 11,
        "left_elbow": 12,
        "left_wrist": 13,
        "left_hip": 4,
    },
}
#: Keypoint counts of the built-in layouts.
LAYOUT_SIZES: dict[str, int] = {"blazepose33": 33, "coco17": 17, "h36m17": 17}

#: Spellings matched by ``layout="names"`` (after lower-casing and removing ``_``, ``-``,
#: ``.`` and spaces). Hands: one hand point, or index and pinky knuckles (their centroid).
_NAME_WORDS: dict[str, tuple[str, ...]] = {
    "shoulder": ("shoulder", "sho"),
    "elbow": ("elbow", "elb"),
    "wrist": ("wrist", "wri"),
    "hand": ("hand", "middle", "fin"),
    "hip": ("hip",),
}


def _aliases(side: str, part: str) -> list[tuple[str, ...]]:
    """Normalised name groups that may stand for ``side_part`` (first match wins)."""
    prefixes = (side[0], side)
    out: list[tuple[str, ...]] = [(s + w,) for s in prefixes for w in _NAME_WORDS[part]]
    if part == "hand":
        out += [(s + "index", s + "pinky") for s in prefixes]
    return out


_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}


def _normal(name: str) -> str:
    return re.sub(r"[\s_\-.]", "", str(name)).lower()


def resolve_layout(
    layout: str | Mapping[str, RoleSpec], names: Sequence[str] | None, n_points: int
) -> dict[str, tuple[int, ...]]:
    """Role → keypoint indices for ``layout`` (see the module docstring).

    Raises ValueError naming the layout, role or name that does not fit ``n_points``
    keypoints called ``names``.
    """
    if isinstance(layout, str):
        if layout == "names":
            if names is None:
                raise ValueError("layout='names' needs the keypoint names")
            index = {_normal(n): i for i, n in enumerate(names)}
            found: dict[str, tuple[int, ...]] = {}
            for role in ROLES:
                side, part = role.split("_")
                for option in _aliases(side, part):
                    if all(o in index for o in option):
                        found[role] = tuple(index[o] for o in option)
                        break
            return found
        if layout not in LAYOUTS:
            raise ValueError(
                f"unknown layout {layout!r}; built-in: {', '.join(LAYOUTS)}, 'names', or a "
                "{role: keypoint} mapping"
            )
        if n_points != LAYOUT_SIZES[layout]:
            raise ValueError(
                f"layout {layout!r} has {LAYOUT_SIZES[layout]} keypoints, the points have "
                f"{n_points}"
            )
        spec: Mapping[str, RoleSpec] = LAYOUTS[layout]
    else:
        spec = layout
    out: dict[str, tuple[int, ...]] = {}
    lookup = {str(n): i for i, n in enumerate(names)} if names is not None else None
    for role, value in spec.items():
        if role not in ROLES:
            raise ValueError(f"unknown keypoint role {role!r}; roles: {', '.join(ROLES)}")
        items = [value] if isinstance(value, (int, str, np.integer)) else list(value)
        if not items:
            raise ValueError(f"role {role!r} maps to no keypoint")
        idx = []
        for item in items:
            if isinstance(item, str):
                if lookup is None:
                    raise ValueError(f"role {role!r} names {item!r} but the points have no names")
                if item not in lookup:
                    raise ValueError(f"role {role!r}: no keypoint named {item!r}")
                idx.append(lookup[item])
            else:
                k = int(item)
                if not 0 <= k < n_points:
                    raise ValueError(f"role {role!r}: index {k} outside 0..{n_points - 1}")
                idx.append(k)
        out[role] = tuple(idx)
    return out


def _as_array(
    points: ArrayLike | Mapping[str, ArrayLike], names: Sequence[str] | None
) -> tuple[NDArray[np.float64], list[str] | None]:
    if isinstance(points, Mapping):
        keys = [str(k) for k in points]
        arr = np.stack([np.asarray(points[k], dtype=np.float64) for k in points], axis=1)
        return arr, keys
    arr = np.asarray(points, dtype=np.float64)
    return arr, (None if names is None else [str(n) for n in names])


def _times(where: str, n: int, times: ArrayLike | None, rate: float | None) -> NDArray[np.float64]:
    if times is not None:
        t = np.asarray(times, dtype=np.float64)
        if t.shape != (n,):
            raise ValueError(f"{where}: times must have shape ({n},), got {t.shape}")
        if not np.isfinite(t).all() or np.any(np.diff(t) <= 0):
            raise ValueError(f"{where}: times must be finite and strictly increasing")
        return t - t[0]
    if rate is None:
        raise ValueError(f"{where}: give times= (seconds) or rate= (frames per second)")
    period = check_frame_period(where, 1.0 / float(rate), "rate=")
    return np.arange(n, dtype=np.float64) * period


def smooth_keypoints(
    times: NDArray[np.float64], points: NDArray[np.float64], cutoff_hz: float, where: str = ""
) -> NDArray[np.float64]:
    """Zero-phase Butterworth low-pass (order :data:`visprim.params.VIDEO_LOWPASS_ORDER`) of
    gap-free keypoints ``points`` (T, ...) sampled at ``times`` (s); ``cutoff_hz`` must lie
    below the Nyquist frequency of the median frame rate. Short series are filtered with
    reduced padding (:func:`visprim.filtering.lowpass`, ``short="reduce"``)."""
    from visprim.filtering import lowpass
    from visprim.params import VIDEO_LOWPASS_ORDER

    n = points.shape[0]
    if n < 3:
        return points
    rate = 1.0 / float(np.median(np.diff(times)))
    nyquist = rate / 2
    if not (np.isfinite(cutoff_hz) and 0 < cutoff_hz < nyquist):
        raise ValueError(
            f"{where}: lowpass_hz={cutoff_hz!r} must be in (0, {nyquist:g}) Hz (the Nyquist "
            f"frequency of {rate:g} frames/s)"
        )
    flat = points.reshape(n, -1)
    out = lowpass(flat, order=VIDEO_LOWPASS_ORDER, cutoff=cutoff_hz / nyquist, short="reduce")
    return np.asarray(out).reshape(points.shape)


def trial_pieces_from_keypoints(
    points: ArrayLike | Mapping[str, ArrayLike],
    layout: str | Mapping[str, RoleSpec] = "blazepose33",
    *,
    names: Sequence[str] | None = None,
    times: ArrayLike | None = None,
    rate: float | None = None,
    confidence: ArrayLike | None = None,
    min_confidence: float = 0.5,
    arm: str = "right",
    up_axis: str = "+z",
    units: str | float = "m",
    mirror: bool = False,
    max_gap: float = 0.2,
    on_gap: str = "split",
    gap_method: str = "cubic",
    min_duration: float = 0.5,
    name: str = "keypoints",
    source: str | os.PathLike[str] | None = None,
    repetitions: int = 1,
    meta: Mapping[str, Any] | None = None,
    lowpass_hz: float | None = None,
) -> list[Trial]:
    """Trials (several when long gaps split the recording) from 3-D keypoints.

    Parameters
    ----------
    points : (T, K, 3) array or ``{name: (T, 3) array}``, in ``units``
    layout : ``"blazepose33"``, ``"coco17"``, ``"h36m17"``, ``"names"`` or a role mapping
        (see the module docstring)
    names : K keypoint names (for name mappings and ``"names"``)
    times : (T,) seconds (strictly increasing; shifted to start at 0), or
    rate : frames per second when there are no timestamps
    confidence : (T, K) scores; a keypoint below ``min_confidence`` is missing in that frame
    arm : 'right', 'left' or 'both'
    up_axis : the keypoints' vertical axis ('+z' default, '-y' for image-like axes)
    units : 'm', 'cm', 'mm' or metres per unit
    mirror : reflect left ↔ right (one arm only), as :func:`visprim.io.read`
    max_gap, on_gap, gap_method, min_duration : gap policy of :mod:`visprim.io.gaps`
    name, source, repetitions, meta : copied into the trials (``source`` also names the data
        in error messages)
    lowpass_hz : zero-phase Butterworth low-pass of the keypoints (order
        :data:`visprim.params.VIDEO_LOWPASS_ORDER`, cutoff in Hz, below the Nyquist
        frequency of the frame rate), applied to each piece after its gaps are filled;
        None (default) leaves them as they are. The video readers pass
        :data:`visprim.params.VIDEO_LOWPASS_HZ`.

    Raises
    ------
    ValueError
        Bad arguments (shapes, layout, options).
    ReadError
        :class:`~visprim.io.errors.MissingPointError` when the layout lacks a needed role,
        :class:`~visprim.io.errors.GapError` when no piece is left, or
        :class:`~visprim.io.errors.MalformedFileError` for degenerate points.
    """
    where = os.fspath(source) if source is not None else name
    arm = check_arm(arm)
    check_gap_options(max_gap, on_gap, gap_method)
    up = check_up_axis(up_axis)
    if isinstance(units, str):
        if units not in _UNITS:
            raise ValueError(f"units must be one of {', '.join(_UNITS)} or a number, got {units!r}")
        scale = _UNITS[units]
    else:
        scale = float(units)
        if not np.isfinite(scale) or scale <= 0:
            raise ValueError(f"units must be a positive number of metres, got {units!r}")
    if arm == "both" and mirror:
        raise ValueError("mirror= does not apply to arm='both' (the left arm is mirrored by IK)")
    if not 0.0 <= float(min_confidence) <= 1.0:
        raise ValueError(f"min_confidence must be in [0, 1], got {min_confidence!r}")
    arr, keys = _as_array(points, names)
    if arr.ndim != 3 or arr.shape[2] != 3:
        raise ValueError(
            f"{where}: points must have shape (T, K, 3) (3-D keypoints; triangulate 2-D ones "
            f"with visprim.io.read_views), got {arr.shape}"
        )
    n, k, _ = arr.shape
    if keys is not None and len(keys) != k:
        raise ValueError(f"{where}: {len(keys)} names for {k} keypoints")
    roles = resolve_layout(layout, keys, k)
    t = _times(where, n, times, rate)
    arr = arr.copy()
    if confidence is not None:
        conf = np.asarray(confidence, dtype=np.float64)
        if conf.shape != (n, k):
            raise ValueError(f"{where}: confidence must have shape ({n}, {k}), got {conf.shape}")
        arr[~(conf >= float(min_confidence))] = np.nan
    arr[~np.isfinite(arr).all(axis=2)] = np.nan

    sides = ("right", "left") if arm == "both" else (arm,)
    need = [f"{s}_{p}" for s in sides for p in ("shoulder", "elbow", "wrist")]
    missing = [r for r in need if r not in roles]
    if missing:
        raise MissingPointError(where, f"the layout has no {', '.join(missing)} keypoint")
    has_torso = all(f"{s}_{p}" in roles for s in ("right", "left") for p in ("shoulder", "hip"))
    used = list(need)
    used += [f"{s}_hand" for s in sides if f"{s}_hand" in roles]
    if has_torso:
        used += [
            r for r in ("right_shoulder", "left_shoulder", "right_hip", "left_hip") if r not in used
        ]
    stacked = np.stack([arr[:, list(roles[r])].mean(axis=1) for r in used], axis=1)
    stacked = stacked @ up_rotation(up).T * scale
    pieces, report = fill_and_split(
        where,
        t,
        stacked,
        used,
        max_gap=max_gap,
        on_gap=on_gap,
        method=gap_method,
        min_duration=min_duration,
    )
    recordings: list[list[ArmRecording]] = []
    for a, b, filled in pieces:
        if lowpass_hz is not None:
            filled = smooth_keypoints(t[a:b], filled, lowpass_hz, where)
        rp = {r: filled[:, i] for i, r in enumerate(used)}
        body = None
        if has_torso:
            low = (rp["right_hip"] + rp["left_hip"]) / 2
            high = (rp["right_shoulder"] + rp["left_shoulder"]) / 2
            right = (rp["right_shoulder"] + rp["right_hip"]) / 2
            left = (rp["left_shoulder"] + rp["left_hip"]) / 2
            body = torso_frame(low, high, right, left)
            if not np.isfinite(body).all():
                raise MalformedFileError(where, "the shoulders and hips are degenerate (no torso)")
        per_side = []
        for s in sides:
            sh, el, wr = rp[f"{s}_shoulder"], rp[f"{s}_elbow"], rp[f"{s}_wrist"]
            if f"{s}_hand" in rp:
                finger, finger_from = rp[f"{s}_hand"], "the estimator's hand point(s)"
            else:
                finger = extend_hand(el, wr, wr - el, FINGER_RATIO)
                finger_from = f"extrapolated along the forearm (ratio {FINGER_RATIO})"
            per_side.append(
                ArmRecording(
                    times=t[a:b],
                    joints=np.stack([sh, el, wr], axis=1),
                    finger=finger,
                    body_frame=body,
                    meta={"frame_range": [a, b], "finger_from": finger_from},
                )
            )
        recordings.append(per_side)
    heading = align_heading([r for piece in recordings for r in piece])
    if mirror:
        for piece in recordings:
            for r in piece:
                r.mirror()
    base = {
        **(dict(meta) if meta else {}),
        "layout": layout if isinstance(layout, str) else "mapping",
        "keypoints": {r: [keys[i] if keys else i for i in roles[r]] for r in used},
        "up_axis": up,
        "units_m": scale,
        "min_confidence": float(min_confidence),
        "body_frame_from": "shoulders and hips" if has_torso else None,
        "gaps": report.as_dict(),
        "arm": arm,
        "mirrored": bool(mirror),
        "heading_deg": heading,
        "lowpass_hz": None if lowpass_hz is None else float(lowpass_hz),
    }
    trials = []
    for i, piece in enumerate(recordings):
        rec = piece[0]
        try:
            trials.append(
                Trial(
                    times=rec.times,
                    markers=np.concatenate([r.markers("virtual") for r in piece], axis=1),
                    joints=np.concatenate([r.joints for r in piece], axis=1),
                    body_frame=rec.body_frame,
                    name=name if len(recordings) == 1 else f"{name}_part{i + 1}",
                    repetitions=int(repetitions),
                    source=None if source is None else os.fspath(source),
                    meta={**base, **rec.meta, "piece": [i + 1, len(recordings)]},
                    arms=sides,
                )
            )
        except TrialError as exc:
            raise MalformedFileError(where, f"the arm's points are degenerate ({exc})") from None
    return trials


def trial_from_keypoints(
    points: ArrayLike | Mapping[str, ArrayLike],
    layout: str | Mapping[str, RoleSpec] = "blazepose33",
    **options: Any,
) -> Trial:
    """One :class:`~visprim.trial.Trial` from 3-D keypoints.

    Options are those of :func:`trial_pieces_from_keypoints`. When long gaps split the
    keypoints into several pieces, raises :class:`~visprim.io.errors.GapError` (use
    :func:`trial_pieces_from_keypoints`, or ``on_gap="longest"``).
    """
    trials = trial_pieces_from_keypoints(points, layout, **options)
    if len(trials) > 1:
        where = os.fspath(options.get("source") or options.get("name", "keypoints"))
        spans = ", ".join(f"{tr.times[0]:.2f}–{tr.times[-1]:.2f} s" for tr in trials)
        raise GapError(
            where,
            f"long gaps split the keypoints into {len(trials)} pieces ({spans}); use "
            "trial_pieces_from_keypoints() or on_gap='longest'",
        )
    return trials[0]


def read_error(path: str | os.PathLike[str], exc: Exception) -> ReadError:
    """A ValueError from the functions above as a :class:`ReadError` naming ``path``."""
    if isinstance(exc, ReadError):
        return exc
    text = str(exc)
    p = os.fspath(path)
    return MalformedFileError(p, text[len(p) :].lstrip(":, ") if text.startswith(p) else text)


def read_keypoint_file(
    path: Path,
    fmt: str,
    arm: str,
    mapping: Mapping[str, Any] | None,
    up_axis: str | None,
    mirror: bool,
    repetitions: int | None,
    gaps: Mapping[str, Any],
    *,
    person: int | None = None,
) -> list[Trial]:
    """:func:`visprim.io.read_pieces` for keypoint files: ``fmt`` ``"trc"``
    (:mod:`visprim.io.trc`) or ``"video"`` (:mod:`visprim.io.video`, following ``person``)."""
    if fmt == "trc":
        from visprim.io.trc import read_trc_pieces

        trials = read_trc_pieces(path, arm, mapping=mapping, up_axis=up_axis, mirror=mirror, **gaps)
    else:
        from visprim.io.video import read_video_pieces

        trials = read_video_pieces(path, arm, mirror=mirror, person=person, **gaps)
    if repetitions is not None:
        for tr in trials:
            tr.repetitions = int(repetitions)
    return trials
