"""From a source's arm points to :class:`visprim.trial.Trial`: axes, units, placement.

The readers produce an :class:`ArmRecording` per piece of a recording: joint centres (and
optionally the file's own sensor markers and the torso frame) in the common frame — metres,
+z up, right-handed — and this module turns it into a ``Trial``.

Common frame. The source's up axis becomes +z by a proper rotation (for +Y up, as in BVH:
``(x, y, z)_trial = (z, x, y)_source``). Then, when the torso orientation is known, the whole
recording is turned about the vertical so that the subject faces +x at the first frame
(``meta["heading_deg"]`` records the turn); +y is then the subject's left. Without a torso
frame the source's horizontal axes are kept.

Virtual marker placement (the method's four sensors, consistent with inverse kinematics,
which recovers ``wrist = m3``, ``elbow = 2 m2 - m3``, ``shoulder = 2 m1 - elbow``):
``upper_arm = (shoulder + elbow) / 2``, ``forearm = (elbow + wrist) / 2``,
``wrist = wrist centre``, ``finger = middle-finger knuckle`` (or the extrapolated hand end).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim import params
from visprim.io.errors import MalformedFileError
from visprim.io.rotations import axis_rotation, nearest_rotation

#: Finger point of rigs without a finger joint: wrist + FINGER_RATIO × forearm length along
#: the hand's axis. 0.45 is the wrist-to-middle-knuckle distance of the CC3 rig (11.5 cm)
#: over its forearm (25.7 cm); anthropometric tables give 0.40–0.45 (hand-to-knuckle
#: ≈ 0.47 of hand length, hand ≈ 0.108 H, forearm ≈ 0.146 H; Drillis & Contini 1966).
FINGER_RATIO = 0.45

UP_AXES = params.UP_AXES

#: Frame periods (seconds) a recording may have: 10 µs (100 kHz) to 10 s (0.1 Hz). Anything
#: outside is a damaged header or a unit mistake (milliseconds given as seconds).
MIN_FRAME_PERIOD = 1e-5
MAX_FRAME_PERIOD = 10.0
#: Most frames a resampled trial may have (about 2.8 h at 1 kHz): refused before allocating.
MAX_FRAMES = 10_000_000


def period_problem(period: float) -> str | None:
    """Why ``period`` (seconds) is not a plausible frame period, or None if it is."""
    if not np.isfinite(period) or period <= 0:
        return f"{period!r} s is not a positive number of seconds"
    if not MIN_FRAME_PERIOD <= period <= MAX_FRAME_PERIOD:
        return (
            f"{period:g} s is outside {MIN_FRAME_PERIOD:g}–{MAX_FRAME_PERIOD:g} s "
            f"(rates of {1 / MAX_FRAME_PERIOD:g} Hz to {1 / MIN_FRAME_PERIOD:g} Hz)"
        )
    return None


def check_frame_period(path: str, period: float, what: str) -> float:
    """``period`` if plausible, else a :class:`MalformedFileError` naming ``what`` (the
    field of the file that gave it)."""
    problem = period_problem(float(period))
    if problem is not None:
        raise MalformedFileError(path, f"{what} gives a frame period of {problem}")
    return float(period)


def check_up_axis(up: str, argument: str = "up_axis") -> str:
    """Normalise an up-axis spelling ('y', '+Y', '-z', ...) to one of :data:`UP_AXES`."""
    value = str(up).strip().lower()
    if value in {"x", "y", "z"}:
        value = "+" + value
    if value not in UP_AXES:
        raise ValueError(f"{argument} must be one of {', '.join(UP_AXES)}, got {up!r}")
    return value


def up_rotation(up: str) -> NDArray[np.float64]:
    """Rotation ``A`` (3×3, det +1) with ``A @ up_vector = +z``; the other two source axes
    follow cyclically (``+y`` up: source z → x, source x → y)."""
    up = check_up_axis(up)
    axis = "xyz".index(up[1])
    a = np.zeros((3, 3))
    # Cyclic permutation: source axis (axis+1) -> x, (axis+2) -> y, axis -> z.
    a[0, (axis + 1) % 3] = 1.0
    a[1, (axis + 2) % 3] = 1.0
    a[2, axis] = 1.0
    if up[0] == "-":
        a = np.diag([1.0, -1.0, -1.0]) @ a
    return a


def heading_rotation(body_frame0: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
    """Rotation about z that turns the body's forward axis (column 0 of a 3×3 frame) to the
    +x half of the x–z plane, and the heading angle it removes (radians)."""
    fwd = body_frame0[:, 0]
    heading = float(np.arctan2(fwd[1], fwd[0]))
    return axis_rotation("z", -heading), heading


def torso_frame(
    low: NDArray[np.float64],
    high: NDArray[np.float64],
    right: NDArray[np.float64] | None = None,
    left: NDArray[np.float64] | None = None,
    *,
    back: NDArray[np.float64] | None = None,
    front: NDArray[np.float64] | None = None,
    chest_rotation: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Torso orientation per frame (T, 3, 3), columns = body x (forward), y (left), z (up).

    ``z`` follows ``high - low``; then ``x`` follows ``front - back`` or ``y`` follows
    ``left - right``. With ``chest_rotation`` (T, 3, 3), the global rotation of a chest
    joint, the result is rigidly attached to that joint: ``B(t) = R(t) @ B0`` with ``B0`` the
    rotation closest to the average of ``R(t).T @ G(t)`` (``G`` the landmark frame), so that
    shoulder shrugs and clavicle motion do not tilt it.
    """
    from visprim.io.rotations import frame_from_axes

    up = high - low
    if front is not None and back is not None:
        g = frame_from_axes(up, front - back, "zx")
    elif left is not None and right is not None:
        g = frame_from_axes(up, left - right, "zy")
    else:
        raise ValueError("torso_frame needs back/front or right/left points")
    if chest_rotation is None:
        return g
    local = np.einsum("tji,tjk->tik", chest_rotation, g)
    ok = np.isfinite(local).all(axis=(1, 2))
    if not np.any(ok):
        return g
    b0 = nearest_rotation(local[ok].mean(axis=0))
    return chest_rotation @ b0


def virtual_markers(
    shoulder: NDArray[np.float64],
    elbow: NDArray[np.float64],
    wrist: NDArray[np.float64],
    finger: NDArray[np.float64],
) -> NDArray[np.float64]:
    """The method's four sensors (T, 4, 3) from the joint centres (see module docstring)."""
    return np.stack([(shoulder + elbow) / 2, (elbow + wrist) / 2, wrist, finger], axis=1)


def extend_hand(
    elbow: NDArray[np.float64],
    wrist: NDArray[np.float64],
    hand_axis: NDArray[np.float64],
    ratio: float = FINGER_RATIO,
) -> NDArray[np.float64]:
    """Finger point of a rig without finger joints: ``wrist + ratio × |wrist − elbow| ×
    hand_axis`` (``hand_axis`` (T, 3) unit vectors: the hand's long axis, e.g. the hand
    joint's rotation applied to the forearm's rest direction)."""
    length = np.linalg.norm(wrist - elbow, axis=-1, keepdims=True)
    # A zero axis (coinciding markers) gives NaN, which the readers refuse with the file's name.
    with np.errstate(invalid="ignore", divide="ignore"):
        axis = hand_axis / np.linalg.norm(hand_axis, axis=-1, keepdims=True)
    return wrist + ratio * length * axis


@dataclass
class ArmRecording:
    """One contiguous piece of a recording, in the common frame (metres, +z up).

    ``joints`` (T, 3, 3): shoulder, elbow, wrist centres; ``finger`` (T, 3);
    ``file_markers`` (T, 4, 3): the file's own four sensors when it has them;
    ``body_frame`` (T, 3, 3) or None.
    """

    times: NDArray[np.float64]
    joints: NDArray[np.float64]
    finger: NDArray[np.float64]
    body_frame: NDArray[np.float64] | None = None
    file_markers: NDArray[np.float64] | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    def transform(self, rot: NDArray[np.float64]) -> None:
        """Apply a rotation (3×3) to every point and to the torso frame, in place."""
        self.joints = self.joints @ rot.T
        self.finger = self.finger @ rot.T
        if self.file_markers is not None:
            self.file_markers = self.file_markers @ rot.T
        if self.body_frame is not None:
            self.body_frame = rot @ self.body_frame

    def mirror(self) -> None:
        """Reflect left ↔ right (y → −y), so a left arm looks like a right arm."""
        d = np.diag([1.0, -1.0, 1.0])
        self.joints = self.joints @ d
        self.finger = self.finger @ d
        if self.file_markers is not None:
            self.file_markers = self.file_markers @ d
        if self.body_frame is not None:
            self.body_frame = d @ self.body_frame @ d

    def markers(self, placement: str) -> NDArray[np.float64]:
        """(T, 4, 3) sensors: ``"virtual"`` (from joint centres) or ``"file"``."""
        if placement == "file":
            if self.file_markers is None:
                raise ValueError("this recording has no sensor markers of its own")
            return self.file_markers
        return virtual_markers(self.joints[:, 0], self.joints[:, 1], self.joints[:, 2], self.finger)


def align_heading(pieces: list[ArmRecording]) -> float | None:
    """Turn all pieces about z so the subject faces +x at the first frame of the first piece
    with a torso frame; returns the removed heading in degrees (None: no torso frame)."""
    for piece in pieces:
        if piece.body_frame is not None and np.isfinite(piece.body_frame[0]).all():
            rot, heading = heading_rotation(piece.body_frame[0])
            for p in pieces:
                p.transform(rot)
            return float(np.rad2deg(heading))
    return None
