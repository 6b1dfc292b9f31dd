"""The one data type every stage exchanges: a recorded (or generated) arm trial.

Frame convention (shared by the generator, the readers, inverse kinematics and the
simulation; see :mod:`visprim.arm`): right-handed, metres, **+z up**; for a subject facing
forward, +x is forward (anterior) and +y is to the subject's left. Readers convert every
source to this frame. When the torso turns during a recording, ``body_frame`` gives its
orientation per frame and inverse kinematics uses it instead of the world axes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

#: The four sensors of the method, in the order of ``Trial.markers[:, i]``.
MARKER_NAMES: tuple[str, ...] = ("upper_arm", "forearm", "wrist", "finger")
#: Joint centres in the order of ``Trial.joints[:, i]`` (when a recording provides them).
JOINT_NAMES: tuple[str, ...] = ("shoulder", "elbow", "wrist")


class TrialError(ValueError):
    """A trial's arrays are inconsistent or unusable (the message names the trial)."""


@dataclass(eq=False)
class Truth:
    """Ground truth of a generated trial.

    Attributes
    ----------
    angles : (T, 4) float array, radians
        The method's four angles per frame: shoulder Z-Y-Z Euler angles (γ, β, α) and elbow
        flexion, as defined in :mod:`visprim.arm`.
    boundaries : (n_strokes + 1,) float array, seconds
        Stroke boundary times on the trial's clock, including its first and last stroke's
        start and end.
    labels : (n_strokes,) int array
        Ground-truth stroke primitive of each stroke (an index into the generator's
        vocabulary).
    repetitions : int
        Number of repetitions of the stimulus's repeated sub-sequence (≥ 1).
    """

    angles: NDArray[np.float64]
    boundaries: NDArray[np.float64]
    labels: NDArray[np.int64]
    repetitions: int = 1


@dataclass(eq=False)
class Trial:
    """One arm recording.

    Attributes
    ----------
    times : (T,) float array, seconds
        Strictly increasing timestamps (need not be uniform).
    markers : (T, 4, 3) float array, metres
        Positions of the four sensors of the method (:data:`MARKER_NAMES`: mid upper arm,
        mid forearm, just above the wrist, middle finger / hand end), in the frame described
        in the module docstring. Finite everywhere (readers fill or split gaps first).
    joints : (T, 3, 3) float array, metres, optional
        Shoulder, elbow and wrist joint centres (:data:`JOINT_NAMES`) when the source has
        them (skeleton formats, anatomical landmarks). Inverse kinematics prefers them.
    body_frame : (T, 3, 3) float array, optional
        Torso orientation: column j is the body's x (forward), y (left), z (up) axis in the
        recording frame. ``None`` means the body axes are the recording axes.
    name : str
        A short human-readable identifier (file stem, or ``s03_m07`` for generated data).
    subject, stimulus : str or int or None
        Who performed it and what was performed (generated data: integer ids).
    repetitions : int
        How many times the movement repeats; SEG-2 tunes its threshold on it. Default 1.
    truth : Truth or None
        Ground truth, for generated data only.
    source : str or None
        Path of the file it was read from.
    meta : dict
        Anything else a reader knows (frame rate, units in the file, style label, ...).
    arms : tuple of str
        Which arm each block of markers belongs to, ``("right",)`` by default. A two-arm
        trial (``("right", "left")``, from ``visprim.io.read(..., arm="both")``) has
        ``markers`` (T, 8, 3) and ``joints`` (T, 6, 3), arm by arm, in the recording frame;
        inverse kinematics mirrors a ``"left"`` arm so its angles follow the right arm's
        convention.
    """

    times: NDArray[np.float64]
    markers: NDArray[np.float64]
    joints: NDArray[np.float64] | None = None
    body_frame: NDArray[np.float64] | None = None
    name: str = ""
    subject: str | int | None = None
    stimulus: str | int | None = None
    repetitions: int = 1
    truth: Truth | None = None
    source: str | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    arms: tuple[str, ...] = ("right",)

    def __post_init__(self) -> None:
        self.times = np.ascontiguousarray(self.times, dtype=np.float64)
        self.markers = np.ascontiguousarray(self.markers, dtype=np.float64)
        where = self.source or self.name or "trial"
        if self.times.ndim != 1:
            raise TrialError(f"{where}: times must be 1-D, got shape {self.times.shape}")
        n = self.times.shape[0]
        if n < 2:
            raise TrialError(f"{where}: a trial needs at least 2 frames, got {n}")
        self.arms = tuple(str(a) for a in self.arms)
        if not self.arms or any(a not in ("right", "left") for a in self.arms):
            raise TrialError(f"{where}: arms must be 'right'/'left' names, got {self.arms!r}")
        m = 4 * len(self.arms)
        if self.markers.shape != (n, m, 3):
            raise TrialError(
                f"{where}: markers must have shape (T, {m}, 3) = ({n}, {m}, 3), "
                f"got {self.markers.shape}"
            )
        if not np.all(np.isfinite(self.times)):
            raise TrialError(f"{where}: times contain NaN or infinity")
        steps = np.diff(self.times)
        if np.any(steps <= 0):
            i = int(np.argmax(steps <= 0))
            raise TrialError(
                f"{where}: timestamps must be strictly increasing; frame {i + 1} "
                f"({self.times[i + 1]:.6g} s) does not follow frame {i} ({self.times[i]:.6g} s)"
            )
        if not np.all(np.isfinite(self.markers)):
            bad = np.flatnonzero(~np.isfinite(self.markers).all(axis=(1, 2)))
            raise TrialError(
                f"{where}: markers contain NaN or infinity in {bad.size} frame(s), first at "
                f"frame {bad[0]} ({self.times[bad[0]]:.6g} s); fill or split gaps first"
            )
        for attr, shape in (("joints", (n, 3 * len(self.arms), 3)), ("body_frame", (n, 3, 3))):
            value = getattr(self, attr)
            if value is None:
                continue
            value = np.ascontiguousarray(value, dtype=np.float64)
            if value.shape != shape:
                raise TrialError(f"{where}: {attr} must have shape {shape}, got {value.shape}")
            if not np.all(np.isfinite(value)):
                raise TrialError(f"{where}: {attr} contain NaN or infinity")
            setattr(self, attr, value)
        if int(self.repetitions) < 1:
            raise TrialError(f"{where}: repetitions must be >= 1, got {self.repetitions}")
        self.repetitions = int(self.repetitions)

    @property
    def n_arms(self) -> int:
        """Number of arms recorded (1 or 2)."""
        return len(self.arms)

    @property
    def n_frames(self) -> int:
        """Number of frames T."""
        return int(self.times.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return float(self.times[-1] - self.times[0])

    @property
    def frame_period(self) -> float:
        """Median time between frames, in seconds."""
        return float(np.median(np.diff(self.times)))

    def __repr__(self) -> str:
        extra = ", with truth" if self.truth is not None else ""
        return (
            f"Trial({self.name!r}, {self.n_frames} frames, {self.duration:.2f} s, "
            f"repetitions={self.repetitions}{extra})"
        )


#: The ``arm`` choice that reads both arms of a recording as two one-arm trials
#: (:func:`split_arms`): ``visprim.io.Corpus(..., arm="each")``, ``visprim learn --arm each``.
EACH_ARM = "each"

#: Reflection through the body's sagittal plane in body coordinates (y, the body's left,
#: changes sign); the same reflection as ``visprim.io.read(..., mirror=True)``.
_MIRROR_Y: NDArray[np.float64] = np.diag([1.0, -1.0, 1.0])


def split_arms(trials: Trial | Sequence[Trial]) -> list[Trial]:
    """One-arm trials of each trial's arms, in order: a two-arm trial gives its right arm,
    then its left arm reflected through the body's sagittal plane so that it moves like a
    right arm (as ``visprim.io.read(path, "left", mirror=True)`` reads it).

    A model fitted on the result has one-arm primitives learned from both arms (twice the
    segments) that can rebuild either arm. One-arm trials are returned as they are. Names
    get ``"_right"``/``"_left"``, ``meta["arm"]`` says which arm each came from, and the
    split trials carry no ``truth``.
    """
    items = [trials] if isinstance(trials, Trial) else list(trials)
    out: list[Trial] = []
    for t in items:
        if t.n_arms == 1:
            out.append(t)
            continue
        for a, side in enumerate(t.arms):
            markers = t.markers[:, 4 * a : 4 * a + 4]
            joints = None if t.joints is None else t.joints[:, 3 * a : 3 * a + 3]
            frame = t.body_frame
            if side == "left":
                # A reflection of the points through the body's sagittal plane: y → −y in
                # body coordinates, R D Rᵀ in the recording frame (D = diag(1, −1, 1)).
                r = np.broadcast_to(np.eye(3), (t.n_frames, 3, 3)) if frame is None else frame
                reflect = r @ _MIRROR_Y @ np.swapaxes(r, 1, 2)
                markers = np.einsum("tij,tmj->tmi", reflect, markers)
                joints = None if joints is None else np.einsum("tij,tmj->tmi", reflect, joints)
            out.append(
                replace(
                    t,
                    markers=markers,
                    joints=joints,
                    name=f"{t.name}_{side}",
                    meta={**t.meta, "arm": side},
                    arms=("right",),
                    truth=None,
                )
            )
    return out
