"""AMASS motions (SMPL-H and SMPL-X parameter files, ``.npz``) → an arm recording.

AMASS (Mahmood et al. 2019, https://amass.is.tue.mpg.de) stores each motion as the pose
parameters of a body model, not as marker or joint positions. Two layouts are read:

* **SMPL-H** (``*_poses.npz``): ``poses`` (T, 156) axis-angle rotations (radians) of the 52
  joints, ``trans`` (T, 3) metres, ``betas``, ``mocap_framerate`` (Hz);
* **SMPL-X** (``*_stageii.npz``): ``root_orient`` (T, 3), ``pose_body`` (T, 63) (joints 1–21),
  ``trans``, ``betas``, ``mocap_frame_rate`` (Hz).

The first 22 joints are the same in both (pelvis, hips, spine1–3, ..., collars, shoulders,
elbows, wrists). No body-model file is needed: the arm's angles depend only on the joint
rotations. Forward kinematics runs on a generic T-pose skeleton
(:data:`TEMPLATE_OFFSETS`, an average adult, arm bones along the body's lateral axis): the
global rotation of the chest (spine3) gives the torso frame, collar · shoulder turn the
upper arm, the elbow turns the forearm, the wrist turns the hand. The shape parameters
``betas`` (bone lengths) do not change the angles and are not used. Because the real SMPL
rest pose has the arms a few degrees below and behind the lateral axis, angles differ from
those of the model's own mesh joints by a few degrees, a constant per joint.

When the file holds joint positions (``joints`` or ``Jtr``, (T, J ≥ 22, 3) metres, SMPL
joint order, as exported with the body model) those positions are used for the shoulder,
elbow and wrist instead of the template (and the middle-finger knuckle when J covers the
hand joints); the torso frame still comes from the rotations.

AMASS's world frame is +Z up (override with ``up_axis``). ``shape.npz`` files (a subject's
body shape without motion) are refused with a clear error; point visprim at the motion
files (``**/*_poses.npz`` or ``**/*_stageii.npz``).

Bounds, checked from the archive's member headers and each array's ``.npy`` header before
any array is decompressed: at most :data:`MAX_FRAMES` frames, at most
:data:`MAX_ARRAY_BYTES` uncompressed bytes per array, numeric arrays only, and a frame rate
between 0.1 Hz and 100 kHz (the frame periods :mod:`visprim.io.assemble` accepts). Every
failure — a damaged or encrypted archive, a bad header, an array of the wrong shape — is a
:class:`~visprim.io.errors.ReadError` naming the file.
"""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.io.assemble import ArmRecording, check_up_axis, period_problem, up_rotation
from visprim.io.errors import MalformedFileError, ReadError
from visprim.io.text import MAX_RECORDING_BYTES, check_file_size

__all__ = ["JOINTS", "TEMPLATE_OFFSETS", "read_amass_arm", "rotations_from_axis_angle"]

#: SMPL joint indices used here (SMPL-H and SMPL-X share the first 22).
JOINTS: dict[str, int] = {
    "pelvis": 0,
    "spine1": 3,
    "spine2": 6,
    "spine3": 9,
    "left_collar": 13,
    "right_collar": 14,
    "left_shoulder": 16,
    "right_shoulder": 17,
    "left_elbow": 18,
    "right_elbow": 19,
    "left_wrist": 20,
    "right_wrist": 21,
}
#: Middle-finger first joint in the SMPL-H joint order (index into ``joints``/``Jtr``).
_KNUCKLE_SMPLH = {"left": 25, "right": 40}

#: Offsets of each joint from its parent in the rest pose, metres, in SMPL's body axes
#: (x = subject's left, y = up, z = forward), for the right arm (the left arm mirrors x).
#: An average adult; only their directions matter for the angles.
TEMPLATE_OFFSETS: dict[str, tuple[float, float, float]] = {
    "spine1": (0.0, 0.11, -0.02),
    "spine2": (0.0, 0.13, 0.0),
    "spine3": (0.0, 0.05, 0.02),
    "collar": (-0.07, 0.11, -0.01),
    "shoulder": (-0.12, 0.04, -0.01),
    "elbow": (-0.26, 0.0, 0.0),
    "wrist": (-0.25, 0.0, 0.0),
    "knuckle": (-0.10, 0.0, 0.0),
}

#: Most frames a motion may have: 35 min at 120 Hz (AMASS's longest motions last minutes);
#: reading one that long needs about 0.5 GB.
MAX_FRAMES = 250_000
#: Largest uncompressed array read from a motion file (bytes).
MAX_ARRAY_BYTES = 400 << 20
#: Arrays read, by name (the others in the archive are never decompressed).
_USED = (
    "poses",
    "root_orient",
    "pose_body",
    "trans",
    "joints",
    "Jtr",
    "mocap_framerate",
    "mocap_frame_rate",
    "header",
    "eigenvectors",
)

#: Body frame (columns forward, left, up) in SMPL body axes: forward = +z, left = +x, up = +y.
_BODY_AXES = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def rotations_from_axis_angle(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotation matrices (..., 3, 3) of axis-angle vectors (..., 3) (angle = norm, radians;
    Rodrigues' formula, exact at 0)."""
    v = np.asarray(v, dtype=np.float64)
    theta = np.linalg.norm(v, axis=-1)
    small = theta < 1e-8
    safe = np.where(small, 1.0, theta)
    # sin(θ)/θ and (1 − cos θ)/θ², with their series near 0.
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    zero = np.zeros_like(x)
    k = np.stack(
        [
            np.stack([zero, -z, y], -1),
            np.stack([z, zero, -x], -1),
            np.stack([-y, x, zero], -1),
        ],
        -2,
    )
    eye = np.broadcast_to(np.eye(3), k.shape)
    return eye + a[..., None, None] * k + b[..., None, None] * (k @ k)


def _declared(path: Path) -> dict[str, tuple[int, ...]]:
    """Shapes of the used arrays of the archive ``path``, from its headers alone; a
    :class:`MalformedFileError` for an encrypted, non-numeric, oversized or too-long one."""
    shapes: dict[str, tuple[int, ...]] = {}
    with zipfile.ZipFile(path) as zf:
        for info in zf.infolist():
            name = info.filename.removesuffix(".npy")
            if name not in _USED:
                continue
            if info.flag_bits & 0x1:
                raise MalformedFileError(path, f"the array {name!r} is encrypted")
            if info.file_size > MAX_ARRAY_BYTES:
                raise MalformedFileError(
                    path,
                    f"the array {name!r} holds {info.file_size / 2**20:.0f} MiB, more than "
                    f"{MAX_ARRAY_BYTES / 2**20:.0f} MiB",
                )
            with zf.open(info) as fh:
                version = np.lib.format.read_magic(fh)
                if version == (1, 0):
                    shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
                else:
                    shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
            if dtype.hasobject or dtype.kind not in "biuf":
                raise MalformedFileError(path, f"the array {name!r} is not numeric ({dtype})")
            nbytes = int(np.prod(shape, dtype=object)) * dtype.itemsize
            if nbytes > info.file_size:
                raise MalformedFileError(
                    path,
                    f"the array {name!r} declares {shape} but the archive holds "
                    f"{info.file_size} bytes of it",
                )
            if len(shape) >= 1 and name not in ("header", "eigenvectors") and shape[0] > MAX_FRAMES:
                raise MalformedFileError(
                    path, f"{name} has {shape[0]:,} frames, more than {MAX_FRAMES:,}"
                )
            shapes[name] = tuple(int(k) for k in shape)
    return shapes


def _scalar(npz: Any, keys: tuple[str, ...]) -> float | None:
    for key in keys:
        if key in npz.files:
            value = np.asarray(npz[key], dtype=np.float64)
            if value.size == 1 and np.isfinite(value).all():
                return float(value.reshape(()))
    return None


def _pose(path: Path, npz: Any) -> tuple[NDArray[np.float64], str]:
    """(T, 22, 3) axis-angle of the body joints (root included) and the layout's name."""
    files = set(npz.files)
    if {"root_orient", "pose_body"} <= files:
        root = np.asarray(npz["root_orient"], dtype=np.float64)
        body = np.asarray(npz["pose_body"], dtype=np.float64)
        if root.ndim != 2 or root.shape[1] != 3 or body.shape != (root.shape[0], 63):
            raise MalformedFileError(
                path,
                f"root_orient must be (T, 3) and pose_body (T, 63), got {root.shape} and "
                f"{body.shape}",
            )
        return np.concatenate([root, body], axis=1).reshape(-1, 22, 3), "SMPL-X"
    if "poses" in files:
        poses = np.asarray(npz["poses"], dtype=np.float64)
        if poses.ndim != 2 or poses.shape[1] < 66 or poses.shape[1] % 3:
            raise MalformedFileError(
                path, f"poses must be (T, 3 J) with J >= 22 joints, got {poses.shape}"
            )
        layout = {156: "SMPL-H", 165: "SMPL-X", 72: "SMPL"}.get(poses.shape[1], "SMPL family")
        return poses[:, :66].reshape(-1, 22, 3), layout
    if "betas" in files:
        raise ReadError(
            path,
            "holds a body shape (betas) but no motion; read the motion files "
            "(*_poses.npz or *_stageii.npz)",
        )
    raise ReadError(
        path,
        "not an AMASS motion: needs 'poses' (SMPL-H) or 'root_orient' + 'pose_body' (SMPL-X); "
        f"found {', '.join(sorted(files)) or 'no arrays'}",
    )


def _joint_positions(path: Path, npz: Any, n: int) -> NDArray[np.float64] | None:
    for key in ("joints", "Jtr"):
        if key in npz.files:
            j = np.asarray(npz[key], dtype=np.float64)
            if j.ndim != 3 or j.shape[0] != n or j.shape[1] < 22 or j.shape[2] != 3:
                raise MalformedFileError(
                    path, f"{key} must be (T={n}, J >= 22, 3) joint positions, got {j.shape}"
                )
            if not np.isfinite(j).all():
                raise MalformedFileError(path, f"{key} contains NaN or infinity")
            return j
    return None


def read_amass_arm(
    path: str | Path, arm: str = "right", *, up_axis: str | None = None
) -> ArmRecording:
    """One AMASS motion file as an arm recording (see the module docstring).

    Raises
    ------
    ReadError
        Not a readable ``.npz``, a shape-only file, missing frame rate, bad shapes, NaN.
    """
    p = Path(path)
    if arm not in ("right", "left"):
        raise ValueError(f"arm must be 'right' or 'left', got {arm!r}")
    up = check_up_axis(up_axis) if up_axis is not None else "+z"
    check_file_size(p, MAX_RECORDING_BYTES)
    try:
        return _read(p, arm, up, up_axis is not None)
    except ReadError:
        raise
    except MemoryError:
        raise MalformedFileError(p, "too large to read in the memory available") from None
    except (zipfile.BadZipFile, EOFError) as exc:
        raise MalformedFileError(p, f"not a readable .npz archive ({exc})") from None
    except Exception as exc:  # zlib.error, numpy's ValueError, an encrypted member ...
        raise MalformedFileError(
            p, f"not a readable AMASS motion ({type(exc).__name__}: {exc})"
        ) from None


def _read(p: Path, arm: str, up: str, up_given: bool) -> ArmRecording:
    _declared(p)
    with np.load(p, allow_pickle=False) as npz:
        if {"header", "eigenvectors"} <= set(npz.files):
            raise ReadError(p, "a visprim model file, not a recording")
        pose, layout = _pose(p, npz)
        n = pose.shape[0]
        if n < 2:
            raise MalformedFileError(p, f"needs at least 2 frames, got {n}")
        if not np.isfinite(pose).all():
            raise MalformedFileError(p, "pose parameters contain NaN or infinity")
        rate = _scalar(npz, ("mocap_framerate", "mocap_frame_rate"))
        if rate is None or rate <= 0:
            raise MalformedFileError(
                p, "no positive frame rate (mocap_framerate or mocap_frame_rate)"
            )
        problem = period_problem(1.0 / rate)
        if problem is not None:
            raise MalformedFileError(p, f"frame rate {rate:g} Hz: a frame period of {problem}")
        trans = np.zeros((n, 3))
        if "trans" in npz.files:
            trans = np.asarray(npz["trans"], dtype=np.float64)
            if trans.shape != (n, 3) or not np.isfinite(trans).all():
                raise MalformedFileError(
                    p, f"trans must be (T={n}, 3) finite metres, got {trans.shape}"
                )
        positions = _joint_positions(p, npz, n)
    joints, finger, body = _forward_kinematics(pose, trans, arm)
    if positions is not None:
        side = arm + "_"
        joints = positions[:, [JOINTS[side + "shoulder"], JOINTS[side + "elbow"]]]
        joints = np.concatenate([joints, positions[:, [JOINTS[side + "wrist"]]]], axis=1)
        if positions.shape[1] > _KNUCKLE_SMPLH[arm]:
            finger = positions[:, _KNUCKLE_SMPLH[arm]]
    rec = ArmRecording(
        times=np.arange(n, dtype=np.float64) / rate,
        joints=joints,
        finger=finger,
        body_frame=body,
        meta={
            "format": "amass",
            "layout": layout,
            "rate_hz": rate,
            "n_frames_file": n,
            "up_axis_in_file": up,
            "up_axis_from": "argument" if up_given else "AMASS convention (+Z)",
            "joints_from": "file joint positions" if positions is not None else "template",
            "body_frame_from": "rotation of spine3",
        },
    )
    rec.transform(up_rotation(up))
    return rec


def _forward_kinematics(
    pose: NDArray[np.float64], trans: NDArray[np.float64], arm: str
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Shoulder, elbow, wrist (T, 3, 3), knuckle (T, 3) and torso frame (T, 3, 3) in the
    file's world frame, from the template skeleton."""
    used = [JOINTS[n] for n in ("pelvis", "spine1", "spine2", "spine3")]
    used += [JOINTS[f"{arm}_{n}"] for n in ("collar", "shoulder", "elbow", "wrist")]
    rot = dict(zip(used, rotations_from_axis_angle(pose[:, used]).swapaxes(0, 1), strict=True))
    sign = np.array([-1.0 if arm == "left" else 1.0, 1.0, 1.0])

    def offset(name: str, mirror: bool = False) -> NDArray[np.float64]:
        o = np.asarray(TEMPLATE_OFFSETS[name])
        return o * sign if mirror else o

    glob = rot[JOINTS["pelvis"]]
    pos = trans.copy()
    for name in ("spine1", "spine2", "spine3"):
        pos = pos + glob @ offset(name)
        glob = glob @ rot[JOINTS[name]]
    body = glob @ _BODY_AXES
    points = []
    for name in ("collar", "shoulder", "elbow", "wrist"):
        pos = pos + glob @ offset(name, True)
        glob = glob @ rot[JOINTS[f"{arm}_{name}"]]
        points.append(pos)
    knuckle = pos + glob @ offset("knuckle", True)
    return np.stack(points[1:], axis=1), knuckle, body
