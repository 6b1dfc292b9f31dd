"""Acclaim ASF (skeleton) + AMC (motion): parsing, forward kinematics, arm trials.

Conventions (Acclaim format as written by Vicon BodyBuilder for the CMU database):

* ASF ``:units``: ``length L`` means one file length unit is ``1/L`` inches, so metres =
  value / L × 0.0254 (CMU: L = 0.45); ``angle deg|rad`` applies to the ``axis`` and
  ``orientation`` values and, unless the AMC says ``:DEGREES``/``:RADIANS``, to the motion.
* Each bone has a rest ``direction`` (world axes), a ``length``, an ``axis ax ay az ORDER``
  giving its local frame ``C`` (``ORDER`` read left to right is the order the rotations are
  applied: ``XYZ`` → ``C = Rz Ry Rx``), and ``dof`` (rx, ry, rz, and for the root the
  ``order`` list with TX TY TZ). A frame's motion rotation ``M`` applies the dofs in the
  listed order (``rx ry rz`` → ``M = Rz Ry Rx``).
* Forward kinematics: ``L = L_parent C M C⁻¹``; a bone starts where its parent ends and ends
  at ``start + length × L × direction``. The root sits at ``position + (TX, TY, TZ)`` with
  ``L_root = C_root M_root C_root⁻¹`` (``C_root`` from ``orientation`` and ``axis``).
* A bone's *start* is its proximal joint, so arm roles name bones whose start is the joint:
  ``rhumerus`` (shoulder), ``rradius`` (elbow), ``rhand`` (wrist), ``rfingers`` (knuckle).
* AMC frames: a frame number line then one ``bone v1 v2 ...`` line per moving bone; the
  rate is not stored (``rate`` argument, CMU default 120 Hz). Up axis +Y.
"""

from __future__ import annotations

import functools
import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.io.assemble import (
    FINGER_RATIO,
    MAX_FRAME_PERIOD,
    MIN_FRAME_PERIOD,
    ArmRecording,
    check_up_axis,
    extend_hand,
    period_problem,
    torso_frame,
    up_rotation,
)
from visprim.io.errors import (
    FrameCountError,
    MalformedFileError,
    MissingPointError,
    ReadError,
    TruncatedFileError,
)
from visprim.io.rotations import euler_matrix
from visprim.io.skeleton import resolve_rig
from visprim.io.text import MAX_SKELETON_BYTES, file_stamp, read_text

_DOFS = ("rx", "ry", "rz", "tx", "ty", "tz", "l")
DEFAULT_AMC_RATE = 120.0


@dataclass
class AsfBone:
    """One ASF bone. ``direction`` is a unit vector (world axes, rest pose); ``axis`` in
    radians; ``dof`` lower-case names in file order."""

    name: str
    direction: NDArray[np.float64]
    length: float
    axis: NDArray[np.float64]
    axis_order: str
    dof: tuple[str, ...] = ()
    parent: int = -1


@dataclass
class AsfSkeleton:
    """A parsed ASF file. Bone 0 is the root (zero length)."""

    path: str
    name: str
    length_unit: float  # the ASF ``:units length`` value
    angle_unit: str  # "deg" or "rad"
    bones: list[AsfBone]
    root_order: tuple[str, ...]
    root_position: NDArray[np.float64]
    _index: dict[str, int] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self._index = {b.name: i for i, b in enumerate(self.bones)}

    @property
    def names(self) -> list[str]:
        return [b.name for b in self.bones]

    @property
    def metres_per_unit(self) -> float:
        """Metres per ASF length unit (1 unit = 1/length inches)."""
        return 0.0254 / self.length_unit

    def index(self, name: str) -> int:
        try:
            return self._index[name]
        except KeyError:
            raise ReadError(self.path, f"no bone named {name!r}") from None

    def ancestors(self, i: int) -> list[int]:
        chain = []
        while i >= 0:
            chain.append(i)
            i = self.bones[i].parent
        return chain[::-1]


def _read_lines(path: str, **bound: Any) -> list[str]:
    return read_text(path, **bound)[0].splitlines()


def _floats(path: str, line_no: int, tokens: Sequence[str], n: int, what: str) -> list[float]:
    if len(tokens) < n:
        raise MalformedFileError(
            path, f"line {line_no}: {what} needs {n} numbers, got {len(tokens)}"
        )
    try:
        vals = [float(t) for t in tokens[:n]]
    except ValueError:
        raise MalformedFileError(
            path, f"line {line_no}: {what} needs {n} numbers, got {' '.join(tokens[:n])!r}"
        ) from None
    if not all(math.isfinite(v) for v in vals):
        raise MalformedFileError(path, f"line {line_no}: {what} is not finite")
    return vals


def parse_asf(path: str | os.PathLike[str]) -> AsfSkeleton:
    """Parse an ASF skeleton file.

    Raises
    ------
    MalformedFileError, TruncatedFileError
        Naming the file and line (missing section, bad number, unknown dof, a hierarchy
        entry naming an undefined bone, a bone without a parent).
    """
    path = os.fspath(path)
    lines = _read_lines(path, limit=MAX_SKELETON_BYTES, what="skeleton (.asf)")
    section = None
    name = ""
    length_unit = 1.0
    angle_unit = "deg"
    root_order: tuple[str, ...] = ("tx", "ty", "tz", "rx", "ry", "rz")
    root_axis = "XYZ"
    root_position = np.zeros(3)
    root_orientation = np.zeros(3)
    raw_bones: list[dict[str, Any]] = []
    current: dict[str, Any] | None = None
    hierarchy: list[tuple[int, list[str]]] = []
    in_hier = False
    seen: set[str] = set()
    for n, raw in enumerate(lines, start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        toks = line.split()
        if toks[0].startswith(":"):
            section = toks[0][1:].lower()
            seen.add(section)
            if section == "name" and len(toks) > 1:
                name = toks[1]
            continue
        key = toks[0].lower()
        if section == "units":
            if key == "length":
                (length_unit,) = _floats(path, n, toks[1:], 1, "units length")
                if length_unit <= 0:
                    raise MalformedFileError(path, f"line {n}: units length must be positive")
            elif key == "angle":
                if len(toks) < 2 or toks[1].lower() not in {"deg", "rad"}:
                    raise MalformedFileError(path, f"line {n}: units angle must be 'deg' or 'rad'")
                angle_unit = toks[1].lower()
        elif section == "root":
            if key == "order":
                root_order = tuple(t.lower() for t in toks[1:])
                bad = [t for t in root_order if t not in _DOFS[:6]]
                if bad or len(set(root_order)) != len(root_order):
                    raise MalformedFileError(path, f"line {n}: bad root order {' '.join(toks[1:])}")
            elif key == "axis":
                root_axis = toks[1].upper() if len(toks) > 1 else ""
                if sorted(root_axis) != ["X", "Y", "Z"]:
                    raise MalformedFileError(path, f"line {n}: root axis must order X, Y, Z")
            elif key == "position":
                root_position = np.array(_floats(path, n, toks[1:], 3, "root position"))
            elif key == "orientation":
                root_orientation = np.array(_floats(path, n, toks[1:], 3, "root orientation"))
        elif section == "bonedata":
            if key == "begin":
                if current is not None:
                    raise MalformedFileError(
                        path, f"line {n}: 'begin' inside a bone (missing 'end')"
                    )
                current = {"line": n}
            elif key == "end":
                if current is None:
                    raise MalformedFileError(path, f"line {n}: 'end' without 'begin'")
                raw_bones.append(current)
                current = None
            elif current is None:
                raise MalformedFileError(path, f"line {n}: {toks[0]!r} outside a bone block")
            elif key == "name":
                if len(toks) < 2:
                    raise MalformedFileError(path, f"line {n}: bone without a name")
                current["name"] = toks[1]
            elif key == "direction":
                current["direction"] = _floats(path, n, toks[1:], 3, "direction")
            elif key == "length":
                current["length"] = _floats(path, n, toks[1:], 1, "length")[0]
            elif key == "axis":
                current["axis"] = _floats(path, n, toks[1:], 3, "axis")
                order = toks[4].upper() if len(toks) > 4 else "XYZ"
                if sorted(order) != ["X", "Y", "Z"]:
                    raise MalformedFileError(
                        path, f"line {n}: axis order {order!r} is not XYZ-like"
                    )
                current["axis_order"] = order
            elif key == "dof":
                dof = tuple(t.lower() for t in toks[1:])
                bad = [t for t in dof if t not in _DOFS]
                if bad:
                    raise MalformedFileError(path, f"line {n}: unknown dof {bad[0]!r}")
                current["dof"] = dof
            # id, limits, bodymass, cofmass: not needed
        elif section == "hierarchy":
            if key == "begin":
                in_hier = True
            elif key == "end":
                in_hier = False
            elif in_hier:
                hierarchy.append((n, toks))
    if current is not None:
        raise TruncatedFileError(path, "the file ends inside a bone block (no 'end')")
    for needed in ("bonedata", "hierarchy"):
        if needed not in seen:
            raise TruncatedFileError(path, f"no :{needed} section")
    to_rad = np.pi / 180.0 if angle_unit == "deg" else 1.0
    bones = [
        AsfBone(
            name="root",
            direction=np.zeros(3),
            length=0.0,
            axis=root_orientation * to_rad,
            axis_order=root_axis,
            dof=tuple(t for t in root_order),
        )
    ]
    names_seen = {"root"}
    for blk in raw_bones:
        at = blk["line"]
        for attr in ("name", "direction", "length"):
            if attr not in blk:
                raise MalformedFileError(path, f"line {at}: bone block without {attr!r}")
        d = np.array(blk["direction"], dtype=float)
        norm = math.hypot(*blk["direction"])
        length = float(blk["length"])
        bname = str(blk["name"])
        if length < 0:
            raise MalformedFileError(path, f"line {at}: bone {bname} has negative length")
        if norm == 0.0 and length > 0:
            raise MalformedFileError(path, f"line {at}: bone {bname} has a zero direction")
        if bname in names_seen:
            raise MalformedFileError(path, f"line {at}: bone name {bname!r} is repeated")
        names_seen.add(bname)
        bones.append(
            AsfBone(
                name=bname,
                direction=d / norm if norm > 0 else d,
                length=length,
                axis=np.array(blk.get("axis", [0.0, 0.0, 0.0]), dtype=float) * to_rad,
                axis_order=str(blk.get("axis_order", "XYZ")),
                dof=tuple(blk.get("dof", ())),
            )
        )
    index = {bone.name: i for i, bone in enumerate(bones)}
    for at, toks in hierarchy:
        for t in toks:
            if t not in index:
                raise MalformedFileError(path, f"line {at}: hierarchy names unknown bone {t!r}")
        parent = index[toks[0]]
        for child in toks[1:]:
            c = index[child]
            if c == 0 or bones[c].parent >= 0:
                raise MalformedFileError(path, f"line {at}: bone {child!r} has two parents")
            bones[c].parent = parent
    orphans = [bone.name for bone in bones[1:] if bone.parent < 0]
    if orphans:
        raise MalformedFileError(path, f"bones not in the hierarchy: {', '.join(orphans)}")
    # Parents must precede children for forward kinematics: reorder breadth-first.
    topo = [0]
    children: dict[int, list[int]] = {}
    for i, bone in enumerate(bones[1:], start=1):
        children.setdefault(bone.parent, []).append(i)
    k = 0
    while k < len(topo):
        topo.extend(children.get(topo[k], []))
        k += 1
    if len(topo) != len(bones):
        raise MalformedFileError(path, "the hierarchy has a cycle")
    remap = {old: new for new, old in enumerate(topo)}
    sorted_bones = [bones[i] for i in topo]
    for bone in sorted_bones:
        bone.parent = remap[bone.parent] if bone.parent >= 0 else -1
    return AsfSkeleton(
        path=path,
        name=name,
        length_unit=length_unit,
        angle_unit=angle_unit,
        bones=sorted_bones,
        root_order=root_order,
        root_position=root_position,
    )


@dataclass
class AmcMotion:
    """Parsed AMC frames: per bone a (F, n_dof) array in file units (angles as written)."""

    path: str
    n_frames: int
    values: dict[str, NDArray[np.float64]]
    angle_unit: str | None  # from ':DEGREES' / ':RADIANS', if present
    first_frame: int


def _parse_amc_regular(path: str, lines: list[str], dof_count: dict[str, int]) -> AmcMotion | None:
    """The common case in a few array operations: every frame lists the same bones in the
    same order, no comment in the body. ``None`` for anything else (or anything wrong): the
    line-by-line parser then reads the file and names the line at fault."""
    header = 0
    angle_unit = None
    for line in lines:
        text = line.strip()
        if text.isdigit():
            break
        if text.startswith(":"):
            word = text[1:].split()[0].upper() if len(text) > 1 else ""
            angle_unit = {"DEGREES": "deg", "RADIANS": "rad"}.get(word, angle_unit)
        elif text and not text.startswith("#"):
            return None
        header += 1
    body = lines[header:]
    if not body:
        return None
    layout: list[tuple[str, int]] = []
    for line in body[1:]:
        toks = line.split()
        if not toks or toks[0].isdigit():
            break
        layout.append((toks[0], len(toks) - 1))
    if sorted(layout) != sorted(dof_count.items()):
        return None
    width = 1 + sum(1 + k for _, k in layout)
    tokens = np.array(" ".join(body).split(), dtype=object)
    if tokens.size == 0 or tokens.size % width:
        return None
    table = tokens.reshape(-1, width)
    name_cols, value_cols = [], []
    col = 1
    for _, k in layout:
        name_cols.append(col)
        value_cols.append(np.arange(col + 1, col + 1 + k))
        col += 1 + k
    names = np.array([name for name, _ in layout])
    if np.any(table[:, name_cols] != names):
        return None
    cols = np.concatenate(value_cols)
    try:
        frames = np.fromiter(map(int, table[:, 0]), np.int64, count=table.shape[0])
        numbers = np.fromiter(
            map(float, table[:, cols].ravel()), np.float64, count=table.shape[0] * cols.size
        )
    except (ValueError, OverflowError):  # the careful parser says what is wrong
        return None
    numbers = numbers.reshape(table.shape[0], cols.size)
    if np.any(np.diff(frames) != 1) or not np.all(np.isfinite(numbers)):
        return None
    values, start = {}, 0
    for name, k in layout:
        values[name] = np.ascontiguousarray(numbers[:, start : start + k])
        start += k
    return AmcMotion(
        path=path,
        n_frames=int(frames.size),
        values=values,
        angle_unit=angle_unit,
        first_frame=int(frames[0]),
    )


def parse_amc(path: str | os.PathLike[str], skeleton: AsfSkeleton) -> AmcMotion:
    """Parse an AMC file against ``skeleton`` (bone names and dof counts are checked).

    Raises
    ------
    MalformedFileError, TruncatedFileError, FrameCountError
        Naming the file and line: unknown bone, wrong number of values, non-numeric or
        non-finite value, frame numbers not consecutive, a frame missing a bone (the last
        frame missing bones means the file was cut short).
    """
    path = os.fspath(path)
    lines = _read_lines(path)
    dof_count = {b.name: len(b.dof) for b in skeleton.bones if b.dof}
    fast = _parse_amc_regular(path, lines, dof_count)
    if fast is not None:
        return fast
    angle_unit = None
    rows: dict[str, list[list[str]]] = {name: [] for name in dof_count}
    row_lines: dict[str, list[int]] = {name: [] for name in dof_count}
    frame_numbers: list[int] = []
    frame_lines: list[int] = []
    seen_in_frame: set[str] = set()

    def close_frame(line: int) -> None:
        missing = [b for b in dof_count if b not in seen_in_frame]
        if missing:
            raise FrameCountError(
                path,
                f"frame {frame_numbers[-1]} (line {frame_lines[-1]}) has no values for "
                f"{', '.join(missing[:5])}{' ...' if len(missing) > 5 else ''}",
            )

    for n, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith(":"):
            word = line[1:].split()[0].upper() if len(line) > 1 else ""
            if word == "DEGREES":
                angle_unit = "deg"
            elif word == "RADIANS":
                angle_unit = "rad"
            continue
        toks = line.split()
        if len(toks) == 1 and re.fullmatch(r"[+-]?\d+", toks[0]):
            if len(toks[0]) > 15:
                too_large = f"line {n}: frame number {toks[0][:20]} is too large"
                raise MalformedFileError(path, too_large)
            if frame_numbers:
                close_frame(n)
                if int(toks[0]) != frame_numbers[-1] + 1:
                    raise FrameCountError(
                        path,
                        f"line {n}: frame {toks[0]} follows frame {frame_numbers[-1]} "
                        "(frames must be consecutive)",
                    )
            frame_numbers.append(int(toks[0]))
            frame_lines.append(n)
            seen_in_frame = set()
            continue
        if not frame_numbers:
            raise MalformedFileError(path, f"line {n}: bone values before the first frame number")
        bone = toks[0]
        if bone not in dof_count:
            known = bone in {b.name for b in skeleton.bones}
            why = "has no dof in" if known else "is not a bone of"
            raise MalformedFileError(path, f"line {n}: {bone!r} {why} {skeleton.path}")
        if bone in seen_in_frame:
            raise MalformedFileError(path, f"line {n}: {bone!r} twice in frame {frame_numbers[-1]}")
        if len(toks) - 1 != dof_count[bone]:
            raise MalformedFileError(
                path,
                f"line {n}: {bone!r} has {len(toks) - 1} values, its dof needs {dof_count[bone]}",
            )
        seen_in_frame.add(bone)
        rows[bone].append(toks[1:])
        row_lines[bone].append(n)
    if not frame_numbers:
        raise TruncatedFileError(path, "no frames")
    missing = [b for b in dof_count if b not in seen_in_frame]
    if missing:
        raise TruncatedFileError(
            path,
            f"the last frame {frame_numbers[-1]} (line {frame_lines[-1]}) lacks "
            f"{', '.join(missing[:5])}{' ...' if len(missing) > 5 else ''} (file cut short?)",
        )
    values: dict[str, NDArray[np.float64]] = {}
    for bone, r in rows.items():
        try:
            arr = np.array(r, dtype=np.float64)
        except ValueError:
            for toks, n in zip(r, row_lines[bone], strict=True):
                for t in toks:
                    try:
                        float(t)
                    except ValueError:
                        raise MalformedFileError(path, f"line {n}: {t!r} is not a number") from None
            raise  # pragma: no cover
        if not np.all(np.isfinite(arr)):
            k = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
            raise MalformedFileError(path, f"line {row_lines[bone][k]}: non-finite value")
        values[bone] = arr.reshape(len(frame_numbers), dof_count[bone])
    return AmcMotion(
        path=path,
        n_frames=len(frame_numbers),
        values=values,
        angle_unit=angle_unit,
        first_frame=frame_numbers[0],
    )


def _axis_matrix(bone: AsfBone) -> NDArray[np.float64]:
    order = bone.axis_order.lower()
    angles = np.array([bone.axis["xyz".index(a)] for a in order])
    # Applied in the listed order: the last listed is the outermost factor.
    return euler_matrix(order[::-1], angles[::-1])


def _motion_matrix(dof: Sequence[str], angles: NDArray[np.float64]) -> NDArray[np.float64]:
    rot = [(d[1], k) for k, d in enumerate(dof) if d in ("rx", "ry", "rz")]
    if not rot:
        return np.broadcast_to(np.eye(3), (angles.shape[0], 3, 3))
    axes = [a for a, _ in rot][::-1]
    cols = np.stack([angles[:, k] for _, k in rot][::-1], axis=-1)
    return euler_matrix(axes, cols)


def forward_kinematics(
    skeleton: AsfSkeleton, motion: AmcMotion, angle_unit: str | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Bone start and end positions and global rotations for every frame.

    Returns
    -------
    starts, ends : (F, n_bones, 3) float arrays, ASF length units, file axes
    rotations : (F, n_bones, 3, 3); ``L`` of each bone (see the module docstring)
    """
    unit = angle_unit or motion.angle_unit or skeleton.angle_unit
    scale = np.pi / 180.0 if unit == "deg" else 1.0
    n = motion.n_frames
    nb = len(skeleton.bones)
    starts = np.zeros((n, nb, 3))
    ends = np.zeros((n, nb, 3))
    rots = np.zeros((n, nb, 3, 3))
    for i, bone in enumerate(skeleton.bones):
        c = _axis_matrix(bone)
        vals = motion.values.get(bone.name)
        if vals is None:
            m = np.broadcast_to(np.eye(3), (n, 3, 3))
            trans = np.zeros((n, 3))
        else:
            ang = np.zeros_like(vals)
            trans = np.zeros((n, 3))
            for k, d in enumerate(bone.dof):
                if d in ("rx", "ry", "rz"):
                    ang[:, k] = vals[:, k] * scale
                elif d in ("tx", "ty", "tz"):
                    trans[:, "xyz".index(d[1])] = vals[:, k]
            m = _motion_matrix(bone.dof, ang)
        local = c @ m @ c.T
        if bone.parent < 0:
            rots[:, i] = local
            starts[:, i] = skeleton.root_position + trans
            ends[:, i] = starts[:, i]
        else:
            rots[:, i] = rots[:, bone.parent] @ local
            starts[:, i] = ends[:, bone.parent]
            ends[:, i] = starts[:, i] + bone.length * np.einsum(
                "fij,j->fi", rots[:, i], bone.direction
            )
    return starts, ends, rots


@functools.lru_cache(maxsize=2)
def _kinematics(
    path: str, asf_path: str, stamp: tuple[int, ...]
) -> tuple[AsfSkeleton, AmcMotion, NDArray[np.float64], NDArray[np.float64]]:
    """Parsed skeleton and motion, bone starts and rotations (read-only arrays). Cached for
    the last two files (``stamp``: their sizes and modification times), so reading both
    arms parses and poses a file once."""
    skel = parse_asf(asf_path)
    motion = parse_amc(path, skel)
    starts, _, rots = forward_kinematics(skel, motion)
    starts.flags.writeable = False
    rots.flags.writeable = False
    return skel, motion, starts, rots


def find_skeleton(amc_path: str | os.PathLike[str]) -> Path:
    """The ASF for an AMC: the same stem, else the only .asf in its folder, else the one
    whose stem starts the AMC's stem (``charleston1.amc`` → ``charleston.asf``)."""
    amc = Path(amc_path)
    same = amc.with_suffix(".asf")
    if same.is_file():
        return same
    folder = amc.parent
    asfs = sorted(p for p in folder.iterdir() if p.suffix.lower() == ".asf")
    if len(asfs) == 1:
        return asfs[0]
    prefixed = [p for p in asfs if amc.stem.startswith(p.stem)]
    if prefixed:
        return max(prefixed, key=lambda p: len(p.stem))
    if not asfs:
        raise ReadError(amc, "no .asf skeleton next to it; pass skeleton=PATH")
    raise ReadError(
        amc,
        f"{len(asfs)} .asf files in its folder and none named {same.name}; pass skeleton=PATH",
    )


def read_amc_arm(
    path: str | os.PathLike[str],
    arm: str = "right",
    *,
    skeleton: str | os.PathLike[str] | None = None,
    rate: float | None = None,
    preset: str | None = None,
    mapping: Mapping[str, str | Sequence[str]] | None = None,
    up_axis: str | None = None,
    finger_ratio: float = FINGER_RATIO,
) -> ArmRecording:
    """The arm of an AMC file (with its ASF skeleton) as an ArmRecording.

    ``rate`` in Hz (default 120, the CMU capture rate; AMC files do not store it).
    """
    path = os.fspath(path)
    asf_path = Path(skeleton) if skeleton is not None else find_skeleton(path)
    skel, motion, starts, rots = _kinematics(path, os.fspath(asf_path), file_stamp(path, asf_path))
    if motion.n_frames < 2:
        raise ReadError(path, f"a trial needs at least 2 frames, the file has {motion.n_frames}")
    hz = DEFAULT_AMC_RATE if rate is None else float(rate)
    problem = period_problem(1.0 / hz) if np.isfinite(hz) and hz > 0 else "not positive"
    if problem is not None:
        raise ValueError(
            f"rate must be a number of frames per second with a period of "
            f"{MIN_FRAME_PERIOD:g}–{MAX_FRAME_PERIOD:g} s, got {rate!r}"
        )
    try:
        roles = resolve_rig(path, skel.names, arm, preset, mapping, kind="bone")
    except MissingPointError as exc:
        raise MissingPointError(path, f"{exc.reason} (skeleton {asf_path})") from None

    def p(role: str) -> NDArray[np.float64]:
        i = roles.index[role]
        assert i is not None
        return starts[:, i]

    shoulder, elbow, wrist = p("shoulder"), p("elbow"), p("wrist")
    if roles.has("finger"):
        finger = p("finger")
        finger_from = f"start of bone {roles.names['finger']}"
    else:
        i_w = roles.index["wrist"]
        assert i_w is not None
        hand_axis = np.einsum("fij,j->fi", rots[:, i_w], skel.bones[i_w].direction)
        finger = extend_hand(elbow, wrist, hand_axis, finger_ratio)
        finger_from = f"extrapolated along bone {roles.names['wrist']} (ratio {finger_ratio})"
    body = None
    if roles.has("trunk_low", "trunk_high", "lateral_right", "lateral_left"):
        chest = rots[:, roles.index["chest"]] if roles.has("chest") else None
        body = torso_frame(
            p("trunk_low"),
            p("trunk_high"),
            p("lateral_right"),
            p("lateral_left"),
            chest_rotation=chest,
        )
    up = check_up_axis(up_axis) if up_axis is not None else "+y"
    scale = skel.metres_per_unit
    rec = ArmRecording(
        times=np.arange(motion.n_frames) / hz,
        joints=np.stack([shoulder, elbow, wrist], axis=1) * scale,
        finger=finger * scale,
        body_frame=body,
        meta={
            "format": "amc",
            "skeleton": os.fspath(asf_path),
            "skeleton_name": skel.name,
            "rate_hz": hz,
            "rate_from": "argument" if rate is not None else "CMU default (not stored in AMC)",
            "n_frames_file": motion.n_frames,
            "first_frame_number": motion.first_frame,
            "units_in_file": f"1/{skel.length_unit:g} inch, {motion.angle_unit or skel.angle_unit}",
            "metres_per_unit": scale,
            "up_axis_in_file": up,
            "up_axis_from": "argument" if up_axis is not None else "ASF convention (+Y)",
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
    rec.transform(up_rotation(up))
    return rec
