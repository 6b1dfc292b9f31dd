"""Biovision BVH: parsing, forward kinematics (vectorised over frames), and arm trials.

Conventions implemented (the common reading of the format):

* Rotation channels are in degrees and compose in the order listed:
  ``CHANNELS 3 Zrotation Xrotation Yrotation`` gives ``R = Rz @ Rx @ Ry`` (any order and any
  subset of the three axes is accepted). A joint's global rotation is its parent's global
  rotation times its local one; its position is the parent's position plus the parent's
  global rotation applied to its local translation.
* Local translation: the ``OFFSET`` for joints without position channels. For the ROOT,
  position channels are added to the offset (a root offset is a constant shift). For other
  joints, position channels *replace* the offset components they cover (exporters such as
  Bandai-Namco's write the full local translation there, equal to the offset).
* ``Frame Time`` is the sampling period in seconds; times start at 0.
* Lengths are in the file's unit (``units`` argument; centimetres by default, as in almost
  every BVH exporter) and the world's up axis is +Y unless told otherwise.

Malformed files (unbalanced braces, unknown channel, bad number, a row with the wrong number
of values, fewer or more rows than ``Frames:``, NaN/inf values) raise a
:class:`~visprim.io.errors.ReadError` subclass naming the file and the line.
"""

from __future__ import annotations

import functools
import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from visprim.io.assemble import (
    FINGER_RATIO,
    ArmRecording,
    check_up_axis,
    extend_hand,
    period_problem,
    torso_frame,
    up_rotation,
)
from visprim.io.errors import FrameCountError, MalformedFileError, ReadError, TruncatedFileError
from visprim.io.rotations import axis_rotation
from visprim.io.skeleton import resolve_rig
from visprim.io.text import file_stamp, read_text

_CHANNELS = {
    "xposition": ("pos", 0),
    "yposition": ("pos", 1),
    "zposition": ("pos", 2),
    "xrotation": ("rot", 0),
    "yrotation": ("rot", 1),
    "zrotation": ("rot", 2),
}


@dataclass
class BvhJoint:
    """One joint of the hierarchy (file order: parents precede their children)."""

    name: str
    parent: int
    offset: NDArray[np.float64]
    channels: tuple[str, ...] = ()
    first_channel: int = 0
    end_site: NDArray[np.float64] | None = None


@dataclass
class BvhData:
    """A parsed BVH file: hierarchy, motion rows (frames × channels) and frame period (s)."""

    path: str
    joints: list[BvhJoint]
    frame_time: float
    motion: NDArray[np.float64]
    _index: dict[str, int] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self._index = {j.name: i for i, j in enumerate(self.joints)}

    @property
    def names(self) -> list[str]:
        """Joint names in file order."""
        return [j.name for j in self.joints]

    @property
    def n_frames(self) -> int:
        return int(self.motion.shape[0])

    def index(self, name: str) -> int:
        """Index of joint ``name`` (exact match)."""
        try:
            return self._index[name]
        except KeyError:
            raise ReadError(self.path, f"no joint named {name!r}") from None

    def ancestors(self, j: int) -> list[int]:
        """``j`` and all its ancestors, root first."""
        chain = []
        while j >= 0:
            chain.append(j)
            j = self.joints[j].parent
        return chain[::-1]


_TOKEN = re.compile(r"[{}]|[^\s{}]+")


class _Tokens:
    """Whitespace tokens of the HIERARCHY section, with line numbers for error messages."""

    def __init__(self, path: str, lines: list[str]) -> None:
        self.path = path
        self.items: list[tuple[str, int]] = []
        for number, line in enumerate(lines, start=1):
            # Braces may touch names ("Hips{"): they are tokens of their own.
            self.items.extend((tok, number) for tok in _TOKEN.findall(line))
        self.pos = 0
        self.last_line = len(lines)

    def next(self, what: str) -> tuple[str, int]:
        if self.pos >= len(self.items):
            raise TruncatedFileError(
                self.path, f"HIERARCHY ends at line {self.last_line} while expecting {what}"
            )
        tok = self.items[self.pos]
        self.pos += 1
        return tok

    def peek(self) -> str | None:
        return self.items[self.pos][0] if self.pos < len(self.items) else None

    def expect(self, word: str) -> int:
        tok, line = self.next(repr(word))
        if tok != word:
            raise MalformedFileError(self.path, f"line {line}: expected {word!r}, found {tok!r}")
        return line

    def numbers(self, n: int, what: str) -> NDArray[np.float64]:
        vals = []
        for _ in range(n):
            tok, line = self.next(what)
            try:
                v = float(tok)
            except ValueError:
                raise MalformedFileError(
                    self.path, f"line {line}: {what} needs {n} numbers, found {tok!r}"
                ) from None
            if not math.isfinite(v):
                raise MalformedFileError(self.path, f"line {line}: {what} is not finite ({tok})")
            vals.append(v)
        return np.array(vals)


def _parse_hierarchy(path: str, lines: list[str]) -> list[BvhJoint]:
    toks = _Tokens(path, lines)
    toks.expect("HIERARCHY")
    tok, line = toks.next("ROOT")
    if tok != "ROOT":
        raise MalformedFileError(path, f"line {line}: expected ROOT, found {tok!r}")
    joints: list[BvhJoint] = []
    n_channels = 0
    # Stack of open blocks: joint index, or -2 for an End Site (of joint `end_parent`).
    end_parent = -1
    name, line = toks.next("the root's name")
    stack: list[int] = []
    seen: set[str] = set()
    pending: tuple[str, int] | None = (name, -1)
    while True:
        if pending is not None:
            name, parent = pending
            pending = None
            if name in {"{", "}"}:
                raise MalformedFileError(path, f"line {line}: joint without a name")
            if name in seen:
                raise MalformedFileError(path, f"line {line}: joint name {name!r} is repeated")
            seen.add(name)
            toks.expect("{")
            joints.append(BvhJoint(name=name, parent=parent, offset=np.zeros(3)))
            stack.append(len(joints) - 1)
        tok, line = toks.next("'}'")
        current = stack[-1]
        if tok == "OFFSET":
            off = toks.numbers(3, "OFFSET")
            if current == -2:
                parent_joint = joints[end_parent]
                if parent_joint.end_site is None:
                    parent_joint.end_site = off
            else:
                joints[current].offset = off
        elif tok == "CHANNELS":
            if current == -2:
                raise MalformedFileError(path, f"line {line}: an End Site cannot have CHANNELS")
            count_tok, _ = toks.next("the channel count")
            try:
                count = int(count_tok)
            except ValueError:
                raise MalformedFileError(
                    path, f"line {line}: CHANNELS needs a count, found {count_tok!r}"
                ) from None
            if not 0 <= count <= 6:
                raise MalformedFileError(path, f"line {line}: CHANNELS count {count} not in 0..6")
            chans = []
            for _ in range(count):
                ch, ch_line = toks.next("a channel name")
                if ch.lower() not in _CHANNELS:
                    raise MalformedFileError(
                        path,
                        f"line {ch_line}: unknown channel {ch!r} (joint {joints[current].name})",
                    )
                chans.append(ch.lower())
            if len(set(chans)) != len(chans):
                raise MalformedFileError(path, f"line {line}: repeated channel in {chans}")
            joints[current].channels = tuple(chans)
            joints[current].first_channel = n_channels
            n_channels += count
        elif tok == "JOINT":
            if current == -2:
                raise MalformedFileError(path, f"line {line}: an End Site cannot have children")
            child, line = toks.next("a joint name")
            pending = (child, current)
        elif tok == "End":
            if current == -2:
                raise MalformedFileError(path, f"line {line}: nested End Site")
            site, line = toks.next("'Site'")
            if site != "Site":
                raise MalformedFileError(path, f"line {line}: expected 'End Site', found {site!r}")
            toks.expect("{")
            end_parent = current
            stack.append(-2)
        elif tok == "}":
            stack.pop()
            if not stack:
                break
        else:
            raise MalformedFileError(path, f"line {line}: unexpected {tok!r} in HIERARCHY")
    if toks.peek() is not None:
        tok, line = toks.next("")
        raise MalformedFileError(
            path, f"line {line}: {tok!r} after the hierarchy's closing brace (one ROOT only)"
        )
    return joints


def parse_bvh(path: str | os.PathLike[str]) -> BvhData:
    """Parse a BVH file (hierarchy + motion) without interpreting it.

    Raises
    ------
    MalformedFileError, TruncatedFileError, FrameCountError
        With the file name and line number of the problem.
    """
    path = os.fspath(path)
    text, _ = read_text(path)
    lines = text.splitlines()
    motion_at = next((i for i, ln in enumerate(lines) if ln.strip().upper() == "MOTION"), None)
    if motion_at is None:
        if lines and lines[0].strip() == "HIERARCHY":
            raise TruncatedFileError(path, "no MOTION section (file ends in the hierarchy)")
        raise MalformedFileError(path, "not a BVH file: no HIERARCHY/MOTION sections")
    joints = _parse_hierarchy(path, lines[:motion_at])
    n_channels = sum(len(j.channels) for j in joints)
    if n_channels == 0:
        raise MalformedFileError(path, "the hierarchy declares no channels")

    # MOTION header: "Frames: N" and "Frame Time: dt".
    header: dict[str, tuple[str, int]] = {}
    i = motion_at + 1
    while i < len(lines) and len(header) < 2:
        raw = lines[i].strip()
        i += 1
        if not raw:
            continue
        m = re.match(r"^(Frames|Frame\s+Time)\s*:\s*(\S+)\s*$", raw, flags=re.IGNORECASE)
        if m is None:
            raise MalformedFileError(
                path, f"line {i}: expected 'Frames:' and 'Frame Time:' after MOTION, found {raw!r}"
            )
        key = "frames" if m.group(1).lower() == "frames" else "time"
        header[key] = (m.group(2), i)
    if "frames" not in header or "time" not in header:
        raise TruncatedFileError(path, "the MOTION header ('Frames:', 'Frame Time:') is incomplete")
    frames_tok, frames_line = header["frames"]
    try:
        n_frames = int(frames_tok)
    except ValueError:
        raise MalformedFileError(
            path, f"line {frames_line}: 'Frames:' needs an integer, found {frames_tok!r}"
        ) from None
    if n_frames < 0:
        raise MalformedFileError(path, f"line {frames_line}: negative frame count {n_frames}")
    time_tok, time_line = header["time"]
    try:
        frame_time = float(time_tok)
    except ValueError:
        frame_time = float("nan")
    problem = period_problem(frame_time)
    if problem is not None:
        raise MalformedFileError(path, f"line {time_line}: 'Frame Time:' {problem}")

    rows: list[list[str]] = []
    row_lines: list[int] = []
    for number in range(i, len(lines)):
        toks = lines[number].split()
        if toks:
            rows.append(toks)
            row_lines.append(number + 1)
    for r, (toks, number) in enumerate(zip(rows, row_lines, strict=True)):
        if len(toks) != n_channels:
            if r == len(rows) - 1 and len(toks) < n_channels and len(rows) <= n_frames:
                raise TruncatedFileError(
                    path,
                    f"line {number}: the last frame has {len(toks)} of {n_channels} values "
                    f"(file cut short; {n_frames} frames declared)",
                )
            raise MalformedFileError(
                path, f"line {number}: frame {r} has {len(toks)} values, expected {n_channels}"
            )
    if len(rows) < n_frames:
        raise TruncatedFileError(
            path, f"'Frames: {n_frames}' declared but only {len(rows)} complete frame rows"
        )
    if len(rows) > n_frames:
        raise FrameCountError(
            path,
            f"'Frames: {n_frames}' declared but the file has {len(rows)} frame rows "
            f"(extra data from line {row_lines[n_frames]})",
        )
    try:
        motion = np.array(rows, dtype=np.float64).reshape(n_frames, n_channels)
    except ValueError:
        for toks, number in zip(rows, row_lines, strict=True):
            for tok in toks:
                try:
                    float(tok)
                except ValueError:
                    raise MalformedFileError(
                        path, f"line {number}: {tok!r} is not a number"
                    ) from None
        raise  # pragma: no cover - numpy refused something float() accepts
    if not np.all(np.isfinite(motion)):
        r = int(np.flatnonzero(~np.isfinite(motion).all(axis=1))[0])
        raise MalformedFileError(path, f"line {row_lines[r]}: frame {r} has NaN or infinite values")
    return BvhData(path=path, joints=joints, frame_time=frame_time, motion=motion)


def _local_transforms(
    data: BvhData, j: int
) -> tuple[NDArray[np.float64] | None, NDArray[np.float64]]:
    """Local rotation (F, 3, 3) or None (identity) and translation (F, 3) of joint ``j``."""
    joint = data.joints[j]
    n = data.n_frames
    translation = np.broadcast_to(joint.offset, (n, 3)).copy()
    rotation: NDArray[np.float64] | None = None
    for k, ch in enumerate(joint.channels):
        kind, axis = _CHANNELS[ch]
        col = data.motion[:, joint.first_channel + k]
        if kind == "pos":
            if joint.parent < 0:
                translation[:, axis] += col
            else:
                translation[:, axis] = col
        else:
            r = axis_rotation("xyz"[axis], np.deg2rad(col))
            rotation = r if rotation is None else rotation @ r
    return rotation, translation


def forward_kinematics(
    data: BvhData, joints: list[int] | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Global joint positions and rotations for every frame.

    Parameters
    ----------
    data : BvhData
    joints : list of joint indices, optional
        Only these (and their ancestors) are computed; default all.

    Returns
    -------
    positions : (F, len(joints), 3) float array, file units, file axes
    rotations : (F, len(joints), 3, 3) float array; column k is the joint's local axis k
        in world coordinates.
    """
    wanted = list(range(len(data.joints))) if joints is None else list(joints)
    needed = sorted({a for j in wanted for a in data.ancestors(j)})
    n = data.n_frames
    pos: dict[int, NDArray[np.float64]] = {}
    rot: dict[int, NDArray[np.float64]] = {}
    eye = np.broadcast_to(np.eye(3), (n, 3, 3))
    for j in needed:  # file order: parents first
        local_r, local_t = _local_transforms(data, j)
        parent = data.joints[j].parent
        if parent < 0:
            pos[j] = local_t
            rot[j] = eye.copy() if local_r is None else local_r
        else:
            pos[j] = pos[parent] + np.einsum("fij,fj->fi", rot[parent], local_t)
            rot[j] = rot[parent] if local_r is None else rot[parent] @ local_r
    return (
        np.stack([pos[j] for j in wanted], axis=1),
        np.stack([rot[j] for j in wanted], axis=1),
    )


def rest_positions(data: BvhData) -> NDArray[np.float64]:
    """Joint positions (J, 3) in the rest pose (all rotations zero, offsets only)."""
    out = np.zeros((len(data.joints), 3))
    for j, joint in enumerate(data.joints):
        out[j] = joint.offset if joint.parent < 0 else out[joint.parent] + joint.offset
    return out


def write_bvh(path: str | os.PathLike[str], data: BvhData, precision: int = 6) -> None:
    """Write ``data`` as a BVH file (used for round-trip tests and for exporting edits).

    Values are written with ``precision`` decimals.
    """
    children: dict[int, list[int]] = {}
    for j, joint in enumerate(data.joints):
        children.setdefault(joint.parent, []).append(j)
    pretty = {ch: ch[0].upper() + ch[1:] for ch in _CHANNELS}  # 'xrotation' -> 'Xrotation'
    out: list[str] = ["HIERARCHY"]

    def emit(j: int, depth: int) -> None:
        joint = data.joints[j]
        pad = "\t" * depth
        out.append(f"{pad}{'ROOT' if joint.parent < 0 else 'JOINT'} {joint.name}")
        out.append(f"{pad}{{")
        out.append(f"{pad}\tOFFSET " + " ".join(f"{v:.{precision}f}" for v in joint.offset))
        if joint.channels:
            chans = " ".join(pretty[c] for c in joint.channels)
            out.append(f"{pad}\tCHANNELS {len(joint.channels)} {chans}")
        for c in children.get(j, []):
            emit(c, depth + 1)
        if joint.end_site is not None:
            out.append(f"{pad}\tEnd Site")
            out.append(f"{pad}\t{{")
            site = " ".join(f"{v:.{precision}f}" for v in joint.end_site)
            out.append(f"{pad}\t\tOFFSET {site}")
            out.append(f"{pad}\t}}")
        out.append(f"{pad}}}")

    for root in children.get(-1, []):
        emit(root, 0)
    out.append("MOTION")
    out.append(f"Frames: {data.n_frames}")
    out.append(f"Frame Time: {data.frame_time:.{max(precision, 7)}f}")
    for row in data.motion:
        out.append(" ".join(f"{v:.{precision}f}" for v in row))
    Path(path).write_text("\n".join(out) + "\n", encoding="utf-8")


@functools.lru_cache(maxsize=2)
def _parsed(path: str, stamp: tuple[int, ...]) -> BvhData:
    """:func:`parse_bvh` with its motion read-only, cached for the last two files
    (``stamp``: size and modification time), so reading both arms parses a file once."""
    data = parse_bvh(path)
    data.motion.flags.writeable = False
    return data


def read_bvh_arm(
    path: str | os.PathLike[str],
    arm: str = "right",
    *,
    preset: str | None = None,
    mapping: Mapping[str, str | Sequence[str]] | None = None,
    up_axis: str | None = None,
    units: str | float | None = None,
    finger_ratio: float = FINGER_RATIO,
) -> ArmRecording:
    """The arm of a BVH file as an :class:`~visprim.io.assemble.ArmRecording`.

    ``up_axis`` defaults to +Y (the BVH convention). ``units`` (the file's length unit:
    'm', 'cm', 'mm', 'in' or metres per unit) defaults to detection from the upper-arm
    length (the unit among m, cm, mm that makes it 0.1–0.6 m). Without a finger joint the
    finger point is extrapolated: wrist + ``finger_ratio`` × forearm length along the hand
    joint's rotation applied to the forearm's rest direction.
    """
    path = os.fspath(path)
    data = _parsed(path, file_stamp(path))
    if data.n_frames < 2:
        raise ReadError(path, f"a trial needs at least 2 frames, the file has {data.n_frames}")
    roles = resolve_rig(path, data.names, arm, preset, mapping, kind="joint")
    needed = [i for i in roles.index.values() if i is not None]
    order = sorted(set(needed))
    pos, rot = forward_kinematics(data, order)
    col = {j: k for k, j in enumerate(order)}

    def p(role: str) -> NDArray[np.float64]:
        i = roles.index[role]
        assert i is not None
        return pos[:, col[i]]

    shoulder, elbow, wrist = p("shoulder"), p("elbow"), p("wrist")
    rest = rest_positions(data)
    i_s, i_e, i_w = (roles.index[r] for r in ("shoulder", "elbow", "wrist"))
    assert i_s is not None and i_e is not None and i_w is not None
    upper_len = float(np.linalg.norm(rest[i_e] - rest[i_s]))
    scale, units_from = resolve_units(path, units, upper_len)

    if roles.has("finger"):
        finger = p("finger")
        finger_from = f"joint {roles.names['finger']}"
    else:
        rest_dir = rest[i_w] - rest[i_e]
        if not np.linalg.norm(rest_dir) > 0:
            raise ReadError(path, "the forearm has zero length in the rest pose")
        hand_axis = np.einsum("fij,j->fi", rot[:, col[i_w]], rest_dir / np.linalg.norm(rest_dir))
        finger = extend_hand(elbow, wrist, hand_axis, finger_ratio)
        finger_from = f"extrapolated from {roles.names['wrist']} (ratio {finger_ratio})"

    body = None
    if roles.has("trunk_low", "trunk_high", "lateral_right", "lateral_left"):
        chest = rot[:, col[roles.index["chest"]]] if roles.has("chest") else None  # type: ignore[index]
        body = torso_frame(
            p("trunk_low"),
            p("trunk_high"),
            p("lateral_right"),
            p("lateral_left"),
            chest_rotation=chest,
        )
    up = check_up_axis(up_axis) if up_axis is not None else "+y"
    a = up_rotation(up)
    rec = ArmRecording(
        times=np.arange(data.n_frames, dtype=np.float64) * data.frame_time,
        joints=np.stack([shoulder, elbow, wrist], axis=1) * scale,
        finger=finger * scale,
        body_frame=body,
        meta={
            "format": "bvh",
            "rate_hz": 1.0 / data.frame_time,
            "frame_time_s": data.frame_time,
            "n_frames_file": data.n_frames,
            "units_in_file": units_from[0],
            "units_from": units_from[1],
            "metres_per_unit": scale,
            "up_axis_in_file": up,
            "up_axis_from": "argument" if up_axis is not None else "BVH convention (+Y)",
            "preset": roles.preset,
            "joint_names": {k: v for k, v in roles.names.items() if v is not None},
            "finger_from": finger_from,
            "body_frame_from": (
                f"rotation of {roles.names['chest']}"
                if body is not None and roles.has("chest")
                else ("trunk landmarks" if body is not None else None)
            ),
        },
    )
    rec.transform(a)
    return rec


_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "inch": 0.0254, "ft": 0.3048}


def resolve_units(
    path: str, units: str | float | None, upper_arm_length: float
) -> tuple[float, tuple[str, str]]:
    """Metres per file unit, and (unit name, how it was chosen)."""
    if units is None:
        for name in ("m", "cm", "mm"):
            if 0.1 <= upper_arm_length * _UNITS[name] <= 0.6:
                return _UNITS[name], (name, "detected from the upper-arm length")
        raise ReadError(
            path,
            f"cannot tell the length unit: the upper arm is {upper_arm_length:.4g} file units "
            "long; pass units='m', 'cm', 'mm' or 'in'",
        )
    if isinstance(units, str):
        key = units.strip().lower()
        if key not in _UNITS:
            raise ValueError(f"units must be one of {', '.join(_UNITS)} or a number, got {units!r}")
        return _UNITS[key], (key, "argument")
    value = float(units)
    if not np.isfinite(value) or value <= 0:
        raise ValueError(f"units (metres per file unit) must be positive, got {units!r}")
    return value, (f"{value:g} m", "argument")
