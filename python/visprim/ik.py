"""Inverse kinematics: four arm markers (or joint centres) → the method's four angles.

Pipeline (stage 1 of the method), per frame:

1. **Joint centres.** A recording's own joint centres (``Trial.joints``) are used when
   present. Otherwise they are the centres the marker placement implies
   (:func:`implied_joint_centres`): the wrist marker sits on the wrist, the forearm marker
   midway between elbow and wrist, the upper-arm marker midway between shoulder and elbow, so
   ``wrist = m3``, ``elbow = 2 m2 − m3``, ``shoulder = 2 m1 − elbow``.
2. **Shoulder-origin frame.** Only the directions shoulder→elbow (upper arm, ``u``) and
   elbow→wrist (forearm, ``f``) enter the angles, so the shoulder's translation (the drift of
   the whole arm) drops out. With ``body_frame`` the directions are first expressed in the
   torso's axes (``v_B = body_frameᵀ v``); then they are mapped to the shoulder frame S of
   :mod:`visprim.arm` (x forward, y right, z down).
3. **Angles** (radians, the column order of :data:`visprim.arm.ANGLE_NAMES`). With
   ``R = Rz(γ) Ry(β) Rz(α)``, ``u = R e_z`` and ``f = R (sin θ, 0, cos θ)``:
   ``β = arccos(u_z)`` ∈ [0, π] (elevation from hanging), ``γ = atan2(u_y, u_x)``,
   ``θ = arccos(u · f)`` ∈ [0, π] (elbow flexion), and the humeral rotation α from the plane
   of the forearm: with ``Q = Rz(γ) Ry(β)``, ``Qᵀ f = (cos α sin θ, sin α sin θ, cos θ)``, so
   ``α = atan2((Qᵀf)_y, (Qᵀf)_x)``.

Continuity and singularities
----------------------------
γ and α are unwrapped in time (no 2π jumps), so they may leave (−π, π]; the first
well-defined frame of a trial lies in (−π, π]. β and θ are never negative (the branch
``β ≥ 0`` of the Z-Y-Z decomposition; the generator and the anatomy keep θ ≥ 0).

*Z-Y-Z singularity:* when the upper arm hangs (β ≈ 0) or points straight up (β ≈ π), γ is
undefined; only γ + α (resp. γ − α) is. On frames with ``β < singular_angle`` or
``β > π − singular_angle`` (default 5°), γ is not taken from ``atan2`` (which swings
wildly there) but **interpolated linearly in time** between the unwrapped γ of the nearest
well-defined frames before and after (held constant before the first / after the last one;
0 if a trial has none). α is then computed from the forearm plane *with that γ*, so the
whole rotation stays in α and all four angles stay continuous through the singularity. The
price: inside the cone of half-angle ``singular_angle`` around the singular axis, the
upper-arm direction rebuilt from (γ, β) can be off by up to about ``2 β`` (≤ 10° of
direction at the cone's edge when γ is far from the interpolated value, much less in practice).

*Straight elbow:* when ``θ < singular_angle`` (or ``θ > π − singular_angle``) the forearm
plane, hence α, is undefined; α is interpolated the same way.

Units: metres in, radians out; degrees only in reports.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim.arm import BODY_TO_SHOULDER
from visprim.trial import Trial

__all__ = [
    "DEFAULT_SINGULAR_ANGLE",
    "angles_from_directions",
    "arm_angles",
    "arm_angles_corpus",
    "implied_joint_centres",
]

#: Half-angle (radians; 5°) of the cones around the Z-Y-Z singular axes (β ≈ 0, β ≈ π) and
#: around the straight elbow (θ ≈ 0) inside which γ (resp. α) is interpolated in time.
DEFAULT_SINGULAR_ANGLE: float = float(np.deg2rad(5.0))

_EPS_LENGTH = 1e-9  # metres: shorter upper-arm/forearm vectors are degenerate


def implied_joint_centres(markers: ArrayLike) -> NDArray[np.float64]:
    """Joint centres implied by the marker placement of :data:`visprim.trial.MARKER_NAMES`.

    Parameters
    ----------
    markers : (..., 4, 3) array, metres
        Upper-arm, forearm, wrist and finger markers.

    Returns
    -------
    (..., 3, 3) array, metres: shoulder, elbow and wrist centres
    (``wrist = m3``, ``elbow = 2 m2 − m3``, ``shoulder = 2 m1 − elbow``).
    """
    m = np.asarray(markers, dtype=np.float64)
    if m.ndim < 2 or m.shape[-2:] != (4, 3):
        raise ValueError(f"markers must have shape (..., 4, 3), got {m.shape}")
    wrist = m[..., 2, :]
    elbow = 2.0 * m[..., 1, :] - wrist
    shoulder = 2.0 * m[..., 0, :] - elbow
    return np.stack([shoulder, elbow, wrist], axis=-2)


def arm_angles(
    markers_or_trial: Trial | ArrayLike,
    *,
    joints: ArrayLike | None = None,
    body_frame: ArrayLike | None = None,
    times: ArrayLike | None = None,
    singular_angle: float = DEFAULT_SINGULAR_ANGLE,
) -> NDArray[np.float64]:
    """The four arm angles of every frame of one trial (see the module docstring).

    Parameters
    ----------
    markers_or_trial : Trial or (T, 4, 3) array, metres
        A :class:`~visprim.trial.Trial` (its ``joints``, ``body_frame`` and ``times`` are
        used when present), or the marker positions alone.
    joints : (T, 3, 3) array, metres, optional
        Shoulder, elbow and wrist centres; override the trial's, and replace the centres
        implied by the markers.
    body_frame : (T, 3, 3) array, optional
        Torso orientation per frame (columns: body x, y, z axes in the recording frame);
        overrides the trial's. ``None``: the recording axes are the body axes.
    times : (T,) array, seconds, optional
        Timestamps used to interpolate γ / α across singular frames (default: the trial's
        times, else the frame index).
    singular_angle : float, radians
        Half-angle of the singular cones (default 5°; see the module docstring).

    Returns
    -------
    (T, 4) float64 array, radians: γ, β, α, elbow flexion (columns of
    :data:`visprim.arm.ANGLE_NAMES`), continuous in time.

    Raises
    ------
    ValueError
        On wrong shapes, NaN/inf, or a frame where shoulder and elbow (or elbow and wrist)
        coincide; the message names the trial (if any), the argument and the frame.
    """
    where = "markers"
    if isinstance(markers_or_trial, Trial) and markers_or_trial.n_arms > 1:
        if joints is not None or body_frame is not None or times is not None:
            raise ValueError("joints/body_frame/times overrides apply to one-arm trials only")
        return arm_angles_corpus([markers_or_trial], singular_angle=singular_angle)[0]
    if isinstance(markers_or_trial, Trial):
        trial = markers_or_trial
        where = f"trial {trial.name or trial.source or '?'!r}"
        markers = trial.markers
        if joints is None:
            joints = trial.joints
        if body_frame is None:
            body_frame = trial.body_frame
        if times is None:
            times = trial.times
    else:
        markers = np.asarray(markers_or_trial, dtype=np.float64)
    centres = _joint_centres(markers, joints, where)
    n = centres.shape[0]
    frame = _optional_array(body_frame, (n, 3, 3), "body_frame", where)
    t = _optional_array(times, (n,), "times", where)
    return _angles_concatenated(
        centres, frame, t, np.array([0], dtype=np.int64), singular_angle, [where]
    )


def arm_angles_corpus(
    trials: list[Trial], *, singular_angle: float = DEFAULT_SINGULAR_ANGLE
) -> list[NDArray[np.float64]]:
    """:func:`arm_angles` of many trials, computed on their concatenation (vectorised).

    Equivalent to ``[arm_angles(t) for t in trials]`` (each trial's joints/body_frame used
    when present) but with one numpy pass over all frames; only trials that touch a singular
    cone get a per-trial interpolation step. Trials of several arms (``trial.arms``, e.g.
    ``("right", "left")``) get 4 angles per arm, arm by arm; a left arm is mirrored in the
    body frame (y → −y) so that its angles follow the right arm's convention. All trials
    must have the same arms.

    Returns
    -------
    list of (T_i, 4 n_arms) float64 arrays, radians (views into one concatenated array).
    """
    if not trials:
        return []
    arms = trials[0].arms
    for t in trials:
        if t.arms != arms:
            raise ValueError(
                f"trial {t.name or t.source!r} has arms {list(t.arms)} where the first trial "
                f"has {list(arms)}; read all trials with the same arm= option"
            )
    names = [f"trial {t.name or t.source or i!r}" for i, t in enumerate(trials)]
    lengths = np.array([t.n_frames for t in trials], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    if any(t.body_frame is not None for t in trials):
        eye = np.eye(3)
        frame = np.concatenate(
            [
                t.body_frame
                if t.body_frame is not None
                else np.broadcast_to(eye, (t.n_frames, 3, 3))
                for t in trials
            ]
        )
    else:
        frame = None
    times = np.concatenate([t.times for t in trials])
    markers = np.concatenate([t.markers for t in trials])
    per_arm = []
    for a, side in enumerate(arms):
        # Trial validated its markers (shape, finite); implied centres for all frames at
        # once, then the recordings' own joint centres where they have them.
        centres = implied_joint_centres(markers[:, 4 * a : 4 * a + 4])
        for k, t in enumerate(trials):
            if t.joints is not None:
                centres[offsets[k] : offsets[k] + lengths[k]] = t.joints[:, 3 * a : 3 * a + 3]
        per_arm.append(
            _angles_concatenated(
                centres, frame, times, offsets, singular_angle, names, mirror=side == "left"
            )
        )
    angles = per_arm[0] if len(per_arm) == 1 else np.concatenate(per_arm, axis=1)
    return np.split(angles, offsets[1:])


def angles_from_directions(
    upper: ArrayLike,
    fore: ArrayLike,
    times: ArrayLike | None = None,
    *,
    singular_angle: float = DEFAULT_SINGULAR_ANGLE,
) -> NDArray[np.float64]:
    """The four angles of one arm from its bone directions in the body frame.

    Parameters
    ----------
    upper, fore : (T, 3) arrays
        Directions (any length > 0) of the upper arm (shoulder → elbow) and of the forearm
        (elbow → wrist), body frame.
    times : (T,) array, seconds, optional
        Timestamps for the interpolation through singular frames (default: frame index).

    Returns
    -------
    (T, 4) float64 array, radians (γ, β, α, elbow), continuous in time.
    """
    u = np.asarray(upper, dtype=np.float64)
    f = np.asarray(fore, dtype=np.float64)
    if u.ndim != 2 or u.shape[1] != 3 or f.shape != u.shape:
        raise ValueError(f"upper and fore must both have shape (T, 3), got {u.shape}, {f.shape}")
    centres = np.stack([np.zeros_like(u), u, u + f], axis=1)
    t = None if times is None else np.asarray(times, dtype=np.float64)
    return _angles_concatenated(
        centres, None, t, np.array([0], dtype=np.int64), singular_angle, ["directions"]
    )


# --------------------------------------------------------------------------------------------


def _optional_array(
    value: ArrayLike | None, shape: tuple[int, ...], name: str, where: str
) -> NDArray[np.float64] | None:
    if value is None:
        return None
    a = np.asarray(value, dtype=np.float64)
    if a.shape != shape:
        raise ValueError(f"{where}: {name} must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{where}: {name} contains NaN or infinity")
    return a


def _joint_centres(markers: ArrayLike, joints: ArrayLike | None, where: str) -> NDArray[np.float64]:
    m = np.asarray(markers, dtype=np.float64)
    if m.ndim != 3 or m.shape[1:] != (4, 3):
        raise ValueError(f"{where}: markers must have shape (T, 4, 3), got {m.shape}")
    if joints is not None:
        return _optional_array(joints, (m.shape[0], 3, 3), "joints", where)  # type: ignore[return-value]
    if not np.all(np.isfinite(m)):
        raise ValueError(f"{where}: markers contain NaN or infinity")
    return implied_joint_centres(m)


def _unit(
    v: NDArray[np.float64], what: str, names: list[str], offsets: NDArray[np.int64]
) -> NDArray[np.float64]:
    norm = np.linalg.norm(v, axis=-1)
    bad = norm < _EPS_LENGTH
    if np.any(bad):
        i = int(np.argmax(bad))
        k = int(np.searchsorted(offsets, i, side="right") - 1)
        raise ValueError(
            f"{names[k]}: the {what} has zero length at frame {i - offsets[k]} "
            f"(coincident joint centres); cannot compute arm angles"
        )
    return v / norm[:, None]


def _angles_concatenated(
    centres: NDArray[np.float64],
    body_frame: NDArray[np.float64] | None,
    times: NDArray[np.float64] | None,
    offsets: NDArray[np.int64],
    singular_angle: float,
    names: list[str],
    *,
    mirror: bool = False,
) -> NDArray[np.float64]:
    """Angles of concatenated trials (``offsets`` = first frame of each trial); ``mirror``
    reflects the body frame's y axis first (a left arm seen as a right arm)."""
    if not (0.0 <= singular_angle < np.pi / 4):
        raise ValueError(f"singular_angle must be in [0, π/4) radians, got {singular_angle!r}")
    n = centres.shape[0]
    upper = centres[:, 1] - centres[:, 0]
    fore = centres[:, 2] - centres[:, 1]
    if body_frame is not None:  # recording axes -> body axes: v_B = Fᵀ v
        upper = np.einsum("tji,tj->ti", body_frame, upper)
        fore = np.einsum("tji,tj->ti", body_frame, fore)
    if mirror:
        upper = upper * np.array([1.0, -1.0, 1.0])
        fore = fore * np.array([1.0, -1.0, 1.0])
    diag = np.diag(BODY_TO_SHOULDER)  # body -> shoulder frame (a diagonal sign flip)
    u = _unit(upper * diag, "upper arm (shoulder→elbow)", names, offsets)
    f = _unit(fore * diag, "forearm (elbow→wrist)", names, offsets)

    beta = np.arccos(np.clip(u[:, 2], -1.0, 1.0))
    elbow = np.arccos(np.clip(np.einsum("ti,ti->t", u, f), -1.0, 1.0))
    lengths = np.diff(np.append(offsets, n))
    trial_of = np.repeat(np.arange(offsets.size), lengths)
    t = times if times is not None else np.arange(n, dtype=np.float64)

    gamma_ok = (beta > singular_angle) & (beta < np.pi - singular_angle)
    gamma = _continuous(np.arctan2(u[:, 1], u[:, 0]), gamma_ok, offsets, lengths, trial_of, t)

    # Forearm in the frame Q = Rz(γ) Ry(β): v = Qᵀ f = Ry(-β) Rz(-γ) f.
    cg, sg, cb, sb = np.cos(gamma), np.sin(gamma), np.cos(beta), np.sin(beta)
    x1 = cg * f[:, 0] + sg * f[:, 1]
    y1 = -sg * f[:, 0] + cg * f[:, 1]
    vx = cb * x1 - sb * f[:, 2]
    alpha_ok = (elbow > singular_angle) & (elbow < np.pi - singular_angle)
    alpha = _continuous(np.arctan2(y1, vx), alpha_ok, offsets, lengths, trial_of, t)
    return np.ascontiguousarray(np.stack([gamma, beta, alpha, elbow], axis=1))


def _unwrap_ragged(
    x: NDArray[np.float64], offsets: NDArray[np.int64], lengths: NDArray[np.int64]
) -> NDArray[np.float64]:
    """np.unwrap of every trial of a concatenation, independently (no loop over trials)."""
    if x.size == 0:
        return x.copy()
    d = np.diff(x)
    correction = np.mod(d + np.pi, 2 * np.pi) - np.pi - d
    correction[np.abs(d) < np.pi] = 0.0
    cum = np.concatenate([[0.0], np.cumsum(correction)])
    return x + cum - np.repeat(cum[offsets], lengths)


def _continuous(
    raw: NDArray[np.float64],
    ok: NDArray[np.bool_],
    offsets: NDArray[np.int64],
    lengths: NDArray[np.int64],
    trial_of: NDArray[np.int64],
    t: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Unwrap ``raw`` over the well-defined frames ``ok`` of each trial; interpolate in time
    (hold at the ends) over the others."""
    if np.all(ok):
        return _unwrap_ragged(raw, offsets, lengths)
    out = np.empty_like(raw)
    good_lengths = np.bincount(trial_of[ok], minlength=offsets.size)
    good_offsets = np.concatenate([[0], np.cumsum(good_lengths)[:-1]])
    out[ok] = _unwrap_ragged(raw[ok], good_offsets, good_lengths)
    for k in np.unique(trial_of[~ok]):
        sl = slice(offsets[k], offsets[k] + lengths[k])
        good = ok[sl]
        if not np.any(good):
            out[sl] = 0.0
            continue
        tk = t[sl]
        out[sl][~good] = np.interp(tk[~good], tk[good], out[sl][good])
    return out


def human_arm_points(trial: Trial) -> NDArray[np.float64]:
    """The recorded arm(s) as (T, 4 n_arms, 3) points in metres — shoulder, elbow, wrist,
    finger of the right arm, then of the left for a two-arm trial — in body axes (+x
    forward, +y left, +z up), each arm with its own shoulder at the origin."""
    n_arms = trial.markers.shape[1] // 4
    out = []
    for arm in range(n_arms):
        markers = trial.markers[:, 4 * arm : 4 * arm + 4]
        joints = trial.joints
        if joints is not None and joints.shape[1] >= 3 * (arm + 1):
            centres = joints[:, 3 * arm : 3 * arm + 3]
        else:
            centres = implied_joint_centres(markers)
        points = np.concatenate([centres, markers[:, 3:4]], axis=1)
        out.append(points - points[:, :1])
    rel = np.concatenate(out, axis=1)
    if trial.body_frame is not None:
        rel = np.einsum("tji,tpj->tpi", trial.body_frame, rel)  # v_B = Fᵀ v
    return rel
