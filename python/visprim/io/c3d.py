"""C3D marker files: arm landmarks → joint centres → arm trials.

The file is decoded by :mod:`visprim.io.c3d_format` (checked, pure numpy).

* Units from ``POINT:UNITS`` (m, cm, mm); rate from ``POINT:RATE``; analog channels (EMG,
  force plates) are ignored (their count and rate go to ``meta``).
* Marker names may carry a subject prefix (``Derrick:RSHO``): matching ignores it and
  ``Trial.subject`` gets it.
* Up axis: the ``up_axis`` argument; else ``POINT:Y_SCREEN`` when the file has it (Vicon
  writes the lab's vertical there); else detected from anatomy — the average of thorax
  vectors low → high (``up_low``/``up_high``, e.g. T10 → C7, XIPH → STER) must point clearly
  (≥ 1.5× the next component) along one axis; else the preset's documented default;
  else a :class:`~visprim.io.errors.ReadError` asks for ``up_axis``.
* Joint centres. Shoulder: a ``shoulder`` marker as is, or the ``acromion`` moved
  ``shoulder_drop`` metres down the thorax axis when thorax markers give one, else along the
  acromion → elbow line (the glenohumeral centre lies near the humeral axis below the
  acromion; the lab vertical is no substitute for a leaning trunk — in the Kinetics Toolkit
  racing file the acromion-to-elbow distance stays within 2 mm, as if the probed landmark
  moved with the arm). The drop is by default 17 % of the biacromial width when both acromia
  are marked (Rab et al. 2002, Gait & Posture 15:113), else 0.06 m (17 % of a typical
  0.36 m).
  Elbow and wrist: centroid of the listed landmarks (mid-epicondyles, mid-styloids; Plug-in
  Gait marks only the lateral epicondyle, RELB, so its elbow centre is ~3–4 cm lateral).
  Finger: the listed marker(s) (RFIN = 3rd metacarpal head); without one, the wrist plus
  0.45 × forearm length along the forearm.
* Torso frame (``body_frame``): z from the thorax (``up_low`` → ``up_high``) or the lab
  vertical, then x from ``back`` → ``front`` or y from ``lateral_right`` → ``lateral_left``.
* Cluster roles (``lateral_*``, file ``upper_arm``/``forearm``, multi-marker
  ``finger``) use a gap-tolerant centroid: each visible marker minus its mean offset from the
  cluster centroid (measured where all are visible). Then gaps are filled or split (see
  :mod:`visprim.io.gaps`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.io.assemble import (
    FINGER_RATIO,
    ArmRecording,
    check_frame_period,
    check_up_axis,
    extend_hand,
    torso_frame,
    up_rotation,
)
from visprim.io.c3d_format import read_c3d
from visprim.io.errors import MalformedFileError, MissingPointError, ReadError
from visprim.io.gaps import fill_and_split
from visprim.io.presets import (
    MARKER_PRESETS,
    MARKER_ROLES,
    MarkerPreset,
    NameIndex,
    fill_side,
    normalise_mapping,
    strip_namespace,
)

#: Shoulder drop below the acromion as a fraction of the biacromial width (Rab et al. 2002).
SHOULDER_DROP_RATIO = 0.17
#: Shoulder drop (m) when only one acromion is marked.
DEFAULT_SHOULDER_DROP = 0.06
#: Documented conventions of marker sets whose files carry no axis information.
PRESET_DEFAULT_UP: dict[str, tuple[str, str]] = {
    "anatomical_landmarks": ("+y", "Kinetics Toolkit / ISB convention (+Y up)"),
}
_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}
_CLUSTER_ROLES = frozenset({"lateral_right", "lateral_left", "upper_arm", "forearm", "finger"})
_TORSO_ROLES = ("up_low", "up_high", "back", "front", "lateral_right", "lateral_left")


def _resolve(
    path: str,
    labels: Sequence[str],
    arm: str,
    preset: str | None,
    mapping: Mapping[str, str | Sequence[str]] | None,
) -> tuple[str, dict[str, list[int]], dict[str, list[str]]]:
    """Role → marker indices (empty list: role absent), and the role → name templates used."""
    idx = NameIndex(labels)
    user = normalise_mapping(mapping) if mapping else {}
    unknown = set(user) - set(MARKER_ROLES)
    if unknown:
        raise ValueError(
            f"mapping has unknown role(s) {sorted(unknown)}; roles are {', '.join(MARKER_ROLES)}"
        )
    if preset is not None and preset not in MARKER_PRESETS:
        raise ValueError(f"unknown marker preset {preset!r}; known: {', '.join(MARKER_PRESETS)}")

    def templates(p: MarkerPreset | None) -> dict[str, list[str]]:
        roles = {k: list(v) for k, v in (p.roles if p is not None else {}).items()}
        roles.update(user)
        if "shoulder" in user:
            roles.pop("acromion", None)
        if "acromion" in user:
            roles.pop("shoulder", None)
        return roles

    def attempt(p: MarkerPreset | None) -> tuple[dict[str, list[int]], list[str]]:
        roles = templates(p)
        found: dict[str, list[int]] = {}
        missing: list[str] = []
        for role in MARKER_ROLES:
            names = [fill_side(n, arm) for n in roles.get(role, [])]
            try:
                hits = [idx.find(n) for n in names]
            except LookupError as exc:
                raise MissingPointError(path, str(exc)) from None
            present = [h for h in hits if h is not None]
            if role in _CLUSTER_ROLES and len(names) > 1:
                ok = bool(present)
            else:
                ok = bool(names) and len(present) == len(names)
            found[role] = present if ok else []
            if not ok and names and role in ("shoulder", "acromion", "elbow", "wrist"):
                absent = [n for n, h in zip(names, hits, strict=True) if h is None]
                missing.append(f"{role} ({', '.join(absent)})")
        if not found["shoulder"] and not found["acromion"] and not missing:
            missing.append("shoulder or acromion (no name given)")
        for role in ("elbow", "wrist"):
            if not found[role] and not any(m.startswith(role) for m in missing):
                missing.append(f"{role} (no name given)")
        return found, missing

    if preset is not None:
        tries: list[tuple[str, MarkerPreset | None]] = [(preset, MARKER_PRESETS[preset])]
    elif (
        user and ("shoulder" in user or "acromion" in user) and "elbow" in user and "wrist" in user
    ):
        tries = [("mapping", None), *MARKER_PRESETS.items()]
    else:
        tries = list(MARKER_PRESETS.items())
    report = []
    for name, p in tries:
        found, missing = attempt(p)
        if not missing:
            if name == "mapping":
                # Torso markers from a matching preset, when the mapping gives none.
                for other in MARKER_PRESETS.values():
                    extra, miss = attempt(other)
                    if not miss:
                        for role in _TORSO_ROLES:
                            if role not in user:
                                found[role] = extra[role]
                        break
            return name, found, templates(p)
        report.append(f"{name}: missing {'; '.join(missing)}")
    sample = ", ".join(strip_namespace(x) for x in list(labels)[:15])
    raise MissingPointError(
        path,
        f"cannot find the {arm} arm's markers; tried "
        + " | ".join(report)
        + f". The file's markers: {sample}{' ...' if len(labels) > 15 else ''}. "
        "Pass mapping={'acromion' or 'shoulder': ..., 'elbow': [...], 'wrist': [...], "
        "'finger': ...} to name them.",
    )


def _centroid(points: NDArray[np.float64], tolerant: bool) -> NDArray[np.float64]:
    """Centroid (T, 3) of (T, k, 3) markers; NaN where any (strict) / all (tolerant) missing."""
    if points.shape[1] == 1:
        return points[:, 0]
    if not tolerant:
        return points.mean(axis=1)
    vis = np.asarray(np.isfinite(points).all(axis=2), dtype=bool)
    full = np.asarray(vis.all(axis=1), dtype=bool)
    if full.any():
        centre = points[full].mean(axis=1, keepdims=True)
        offsets = (points[full] - centre).mean(axis=0)  # (k, 3)
    else:
        offsets = np.zeros(points.shape[1:])
    shifted = np.where(vis[:, :, None], points - offsets[None], np.nan)
    with np.errstate(invalid="ignore"):
        count = vis.sum(axis=1)
        total = np.nansum(shifted, axis=1)
        return np.where(count[:, None] > 0, total / np.maximum(count, 1)[:, None], np.nan)


def _detect_up(
    role_pts: Mapping[str, NDArray[np.float64]], preset_name: str
) -> tuple[str, str] | None:
    """Up axis from anatomy (thorax low → high), if clear; else the preset's default."""
    for low, high, label in (("up_low", "up_high", "thorax markers"),):
        if low in role_pts and high in role_pts:
            with np.errstate(invalid="ignore"):
                d = np.nanmean(role_pts[high] - role_pts[low], axis=0)
            if not np.all(np.isfinite(d)):
                continue
            order = np.argsort(-np.abs(d))
            if abs(d[order[0]]) >= 1.5 * abs(d[order[1]]) and abs(d[order[0]]) > 0.02:
                axis = int(order[0])
                sign = "+" if d[axis] > 0 else "-"
                return sign + "xyz"[axis], f"detected from {label} ({low} → {high})"
    if preset_name in PRESET_DEFAULT_UP:
        up, why = PRESET_DEFAULT_UP[preset_name]
        return up, f"preset default: {why}"
    return None


def read_c3d_arm(
    path: str | os.PathLike[str],
    arm: str = "right",
    *,
    preset: str | None = None,
    mapping: Mapping[str, str | Sequence[str]] | None = None,
    up_axis: str | None = None,
    shoulder_drop: float | None = None,
    markers: str = "virtual",
    max_gap: float = 0.2,
    on_gap: str = "split",
    gap_method: str = "cubic",
    min_duration: float = 0.5,
) -> list[ArmRecording]:
    """The arm of a C3D file as ArmRecording pieces (one unless long gaps split it).

    See the module docstring for units, up axis, joint centres and gaps; ``markers="file"``
    also keeps the file's own upper-arm / forearm sensors (``upper_arm``/``forearm`` roles)
    for ``Trial.markers``.
    """
    path = os.fspath(path)
    c3d = read_c3d(path)
    pts = c3d.points  # (T, N, 3) file units, NaN where missing
    n_frames, n_points = pts.shape[0], pts.shape[1]
    labels = c3d.labels("POINT", n_points)
    if len(labels) != n_points:
        raise MalformedFileError(
            path, f"POINT:LABELS names {len(labels)} markers but the data has {n_points}"
        )
    if n_frames < 2:
        raise ReadError(path, f"a trial needs at least 2 frames, the file has {n_frames}")
    rate_param = c3d.param("POINT", "RATE")
    rate = (
        float(np.ravel(rate_param)[0])
        if rate_param is not None and not isinstance(rate_param, list) and np.size(rate_param)
        else c3d.header_rate
    )
    check_frame_period(path, 1.0 / rate if rate > 0 else float("inf"), "POINT:RATE")
    unit_raw = c3d.param("POINT", "UNITS")
    unit = str(unit_raw[0]).strip().lower() if isinstance(unit_raw, list) and unit_raw else ""
    if unit not in _UNITS:
        raise MalformedFileError(
            path, f"POINT:UNITS is {unit!r}; expected one of {', '.join(_UNITS)}"
        )
    scale = _UNITS[unit]
    xyz = pts * scale  # (T, N, 3) metres, file axes

    preset_name, roles, role_names = _resolve(path, labels, arm, preset, mapping)
    width = _biacromial_width(labels, xyz, role_names.get("acromion", []), arm)
    if markers not in ("virtual", "file"):
        raise ValueError(f"markers must be 'virtual' or 'file', got {markers!r}")
    if markers == "file":
        for role in ("upper_arm", "forearm", "finger"):
            if not roles[role]:
                raise MissingPointError(
                    path, f"markers='file' needs the {role} marker(s), not found for the {arm} arm"
                )
    used_roles = [r for r, ix in roles.items() if ix]
    if markers == "virtual":
        used_roles = [r for r in used_roles if r not in ("upper_arm", "forearm")]
    role_pts = {r: _centroid(xyz[:, roles[r]], tolerant=r in _CLUSTER_ROLES) for r in used_roles}

    # Up axis.
    if up_axis is not None:
        up, up_from = check_up_axis(up_axis), "argument"
    else:
        screen = c3d.param("POINT", "Y_SCREEN")
        s = str(screen[0]).strip().lower() if isinstance(screen, list) and screen else ""
        if s in {"+x", "-x", "+y", "-y", "+z", "-z"}:
            up, up_from = s, "POINT:Y_SCREEN"
        else:
            found = _detect_up(role_pts, preset_name)
            if found is None:
                raise ReadError(
                    path,
                    "cannot tell the vertical axis (no POINT:Y_SCREEN, no thorax markers); "
                    "pass up_axis='+z' (or '+y', ...)",
                )
            up, up_from = found
    rot = up_rotation(up)
    role_pts = {r: v @ rot.T for r, v in role_pts.items()}

    # Gaps, on the points actually used.
    gap_roles = list(role_pts)
    stacked = np.stack([role_pts[r] for r in gap_roles], axis=1)
    times = np.arange(n_frames) / rate
    pieces, report = fill_and_split(
        path,
        times,
        stacked,
        gap_roles,
        max_gap=max_gap,
        on_gap=on_gap,
        method=gap_method,
        min_duration=min_duration,
    )

    # Subject prefix and fixed meta.
    used_labels = sorted({labels[i] for r in gap_roles for i in roles[r]})
    prefixes = sorted({lab.rsplit(":", 1)[0] for lab in used_labels if ":" in lab})
    analog_labels = c3d.param("ANALOG", "LABELS")
    analog_rate = c3d.param("ANALOG", "RATE")
    meta_base: dict[str, Any] = {
        "format": "c3d",
        "rate_hz": rate,
        "n_frames_file": n_frames,
        "units_in_file": unit,
        "up_axis_in_file": up,
        "up_axis_from": up_from,
        "preset": preset_name,
        "marker_names": {r: [labels[i] for i in roles[r]] for r in gap_roles},
        "subject": prefixes[0] if len(prefixes) == 1 else None,
        "n_markers_file": len(labels),
        "n_analog_channels": 0 if analog_labels is None else len(analog_labels),
        "analog_rate_hz": (
            float(np.ravel(analog_rate)[0])
            if analog_rate is not None
            and not isinstance(analog_rate, list)
            and np.size(analog_rate)
            else None
        ),
        "gaps": report.as_dict(),
        "markers": markers,
    }
    out = []
    for a, b, filled in pieces:
        rp = {r: filled[:, k] for k, r in enumerate(gap_roles)}
        rec = _piece(rp, times[a:b], shoulder_drop, width, markers)
        rec.meta = {**meta_base, **rec.meta, "frame_range": [a, b]}
        out.append(rec)
    return out


def _biacromial_width(
    labels: Sequence[str], xyz: NDArray[np.float64], templates: Sequence[str], arm: str
) -> float | None:
    """Median distance (m) between the two acromion markers, when both sides are marked."""
    if len(templates) != 1:
        return None
    idx = NameIndex(labels)
    try:
        here = idx.find(fill_side(templates[0], arm))
        other = idx.find(fill_side(templates[0], "left" if arm == "right" else "right"))
    except LookupError:
        return None
    if here is None or other is None or here == other:
        return None
    with np.errstate(invalid="ignore"):
        d = np.linalg.norm(xyz[:, here] - xyz[:, other], axis=1)
    width = float(np.nanmedian(d)) if np.isfinite(d).any() else float("nan")
    return width if 0.2 <= width <= 0.6 else None


def _piece(
    rp: Mapping[str, NDArray[np.float64]],
    times: NDArray[np.float64],
    shoulder_drop: float | None,
    width: float | None,
    markers: str,
) -> ArmRecording:
    """Joint centres, torso frame and sensors of one gap-free piece (common axes, metres)."""
    meta: dict[str, Any] = {}
    body = None
    thorax_z = "up_low" in rp and "up_high" in rp
    if thorax_z:
        low, high = rp["up_low"], rp["up_high"]
    else:
        low = np.zeros_like(rp["elbow"])
        high = low + np.array([0.0, 0.0, 1.0])
    if "back" in rp and "front" in rp:
        body = torso_frame(low, high, back=rp["back"], front=rp["front"])
    elif "lateral_right" in rp and "lateral_left" in rp:
        body = torso_frame(low, high, rp["lateral_right"], rp["lateral_left"])
    if body is not None and not np.isfinite(body).all():
        body = None
        meta["body_frame_note"] = "torso markers degenerate (parallel axes); no body frame"
    meta["body_frame_from"] = (
        None
        if body is None
        else ("thorax markers" if thorax_z else "lab vertical + lateral markers")
    )

    if "shoulder" in rp:
        shoulder = rp["shoulder"]
        meta["shoulder_from"] = "shoulder marker"
    else:
        acro = rp["acromion"]
        if body is not None and thorax_z:
            down = -body[:, :, 2]
        else:
            arm_axis = rp["elbow"] - acro
            down = arm_axis / np.linalg.norm(arm_axis, axis=1, keepdims=True)
        if shoulder_drop is not None:
            drop = float(shoulder_drop)
            why = "argument"
        elif width is not None:
            drop = SHOULDER_DROP_RATIO * width
            why = f"{SHOULDER_DROP_RATIO} × biacromial width {width:.3f} m (Rab et al. 2002)"
        else:
            drop = DEFAULT_SHOULDER_DROP
            why = "default (one acromion marked)"
        shoulder = acro + drop * down
        meta["shoulder_from"] = (
            f"acromion moved {drop:.3f} m down the "
            + ("thorax axis" if (body is not None and thorax_z) else "acromion → elbow line")
            + f" ({why})"
        )
    elbow, wrist = rp["elbow"], rp["wrist"]
    if "finger" in rp:
        finger = rp["finger"]
        meta["finger_from"] = "finger marker(s)"
    else:
        finger = extend_hand(elbow, wrist, wrist - elbow, FINGER_RATIO)
        meta["finger_from"] = f"extrapolated along the forearm (ratio {FINGER_RATIO})"
    file_markers = None
    if markers == "file":
        file_markers = np.stack([rp["upper_arm"], rp["forearm"], wrist, finger], axis=1)
    return ArmRecording(
        times=times,
        joints=np.stack([shoulder, elbow, wrist], axis=1),
        finger=finger,
        body_frame=body,
        file_markers=file_markers,
        meta=meta,
    )
