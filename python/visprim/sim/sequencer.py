"""From the method's 4 arm angles to joint targets on the control grid, and via points.

Mapping (see :mod:`visprim.arm`): the right shoulder's rotation in body axes is
``arm.shoulder_rotation_body(angles)`` (Euler Z-Y-Z in the shoulder frame → rotation), and the
shoulder ball joint's coordinates are its rotation vector (DART's ``BallJoint`` positions are
exponential coordinates: ``convertToPositions(R)``); the elbow's revolute coordinate is the
elbow angle (its axis is ``arm.ELBOW_AXIS_BODY``). Every other joint is held at rest (zero).
The angles are interpolated with a cubic spline onto the control grid (one sample per time
step) before the mapping, so the rotation, not the Euler angles, is what the servo sees.

Via points (:class:`Reference.via_steps`) are samples of that smooth trajectory every
``via_spacing`` seconds, the last one at its end. The sequencer (:class:`ViaPointSequencer`)
holds one *current target* via point at a time. The servo's set point runs along the smooth
trajectory towards the current target and arrives there at the target's nominal time; there
the next target is taken as soon as the configuration is within ``vicinity`` of the current
one (every joint's error, a ball joint's geodesic angle, at most ``vicinity`` radians) or the
set point has waited ``timeout`` seconds on it (then the via point counts as missed). While it
waits, the set point stays on the via point with zero target velocity. A servo that keeps up
never waits, so the movement keeps the timing of the trajectory; one that falls behind is
made to reach each via point before moving on.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import dartpy as dart
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from visprim.arm import shoulder_rotation_body

#: Joints driven by the method's 4 angles: (ball joint, revolute joint).
SHOULDER_JOINT = "r_shoulder"
ELBOW_JOINT = "r_elbow"
#: The left arm's joints, driven by columns 4-7 of a two-arm (T, 8) angle array.
LEFT_SHOULDER_JOINT = "l_shoulder"
LEFT_ELBOW_JOINT = "l_elbow"
#: Reflection through the sagittal plane (y → −y): maps the right arm onto the left.
MIRROR = np.diag([1.0, -1.0, 1.0])


def validate_trajectory(
    times: ArrayLike, angles: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Checked float copies of ``times`` (T,) seconds and ``angles`` (T, 4) radians."""
    t = np.asarray(times, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    if t.ndim != 1 or t.shape[0] < 2:
        raise ValueError(f"times must be a 1-D array of at least 2 seconds values, got {t.shape}")
    if a.ndim != 2 or a.shape[0] != t.shape[0] or a.shape[1] not in (4, 8):
        raise ValueError(
            f"angles must have shape (T, 4) = ({t.shape[0]}, 4) radians (gamma, beta, alpha, "
            f"elbow of the right arm) or (T, 8) (then the left arm's), got {a.shape}"
        )
    if not np.all(np.isfinite(t)):
        raise ValueError("times contain NaN or infinity")
    if not np.all(np.isfinite(a)):
        bad = int(np.flatnonzero(~np.isfinite(a).all(axis=1))[0])
        raise ValueError(f"angles contain NaN or infinity (first at sample {bad})")
    if np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0))
        raise ValueError(f"times must be strictly increasing; sample {i + 1} does not follow {i}")
    return t, a


def arm_dof_indices(skeleton: dart.dynamics.Skeleton, side: str = "right") -> tuple[slice, int]:
    """Skeleton DOF indices of one arm's shoulder (a slice of 3) and elbow."""
    names = (
        (SHOULDER_JOINT, ELBOW_JOINT)
        if side == "right"
        else (LEFT_SHOULDER_JOINT, LEFT_ELBOW_JOINT)
    )
    shoulder = skeleton.getJoint(names[0])
    elbow = skeleton.getJoint(names[1])
    if shoulder is None or elbow is None:
        raise ValueError(
            f"skeleton {skeleton.getName()!r} has no joints {names[0]!r} and {names[1]!r}"
        )
    start = shoulder.getIndexInSkeleton(0)
    return slice(start, start + 3), elbow.getIndexInSkeleton(0)


def _arms(a: NDArray[np.float64]) -> list[tuple[str, NDArray[np.float64]]]:
    """(side, (T, 4) angles) of each arm in a (T, 4) or (T, 8) array."""
    if a.shape[1] == 4:
        return [("right", a)]
    if a.shape[1] == 8:
        return [("right", a[:, :4]), ("left", a[:, 4:])]
    raise ValueError(f"angles must have 4 (right arm) or 8 (both arms) columns, got {a.shape}")


def angles_to_positions(skeleton: dart.dynamics.Skeleton, angles: ArrayLike) -> NDArray[np.float64]:
    """Full joint positions (T, n_dofs) for arm angles in radians; rest elsewhere.

    ``angles`` is (T, 4) for the right arm or (T, 8) for right then left. The left arm's
    angles mean the mirror image (through the sagittal plane) of the same right-arm angles:
    its shoulder rotation is ``P R P`` with ``P = diag(1, −1, 1)``, its elbow the same flexion.
    """
    a = np.atleast_2d(np.asarray(angles, dtype=np.float64))
    q = np.zeros((a.shape[0], skeleton.getNumDofs()))
    for side, arm in _arms(a):
        sh, el = arm_dof_indices(skeleton, side)
        rot = shoulder_rotation_body(arm)
        if side == "left":
            rot = MIRROR @ rot @ MIRROR
        q[:, sh] = Rotation.from_matrix(rot).as_rotvec()
        q[:, el] = arm[:, 3]
    return q


def positions_to_angles(
    skeleton: dart.dynamics.Skeleton, positions: ArrayLike, n_arms: int = 1
) -> NDArray[np.float64]:
    """The method's angles (T, 4 n_arms) radians from joint positions (T, n_dofs).

    Inverse of :func:`angles_to_positions` for β in (0, π); at β = 0 (Z-Y-Z singularity) the
    split between γ and α is arbitrary (α = 0 is returned).
    """
    q = np.atleast_2d(np.asarray(positions, dtype=np.float64))
    out = []
    for side in ("right", "left")[:n_arms]:
        sh, el = arm_dof_indices(skeleton, side)
        rot = Rotation.from_rotvec(q[:, sh]).as_matrix()
        if side == "left":
            rot = MIRROR @ rot @ MIRROR
        m = np.diag([1.0, -1.0, -1.0])
        r = m @ rot @ m  # shoulder frame S
        beta = np.arccos(np.clip(r[:, 2, 2], -1.0, 1.0))
        gamma = np.arctan2(r[:, 1, 2], r[:, 0, 2])
        alpha = np.arctan2(r[:, 2, 1], -r[:, 2, 0])
        flat = np.sin(beta) < 1e-9
        gamma[flat] = np.arctan2(r[flat, 1, 0], r[flat, 0, 0])
        alpha[flat] = 0.0
        out.append(np.stack([gamma, beta, alpha, q[:, el]], axis=1))
    return np.concatenate(out, axis=1)


def shoulder_angular_velocity(angles: ArrayLike, rates: ArrayLike) -> NDArray[np.float64]:
    """Angular velocity (T, 3) rad/s of the upper arm relative to the torso, in the upper
    arm's frame (the convention of DART's ball-joint velocities), from the Euler angles
    (T, ≥3) rad and their time derivatives (T, ≥3) rad/s.

    For ``R_S = Rz(γ) Ry(β) Rz(α)`` the body angular velocity in S is
    ``γ̇ (−sin β cos α, sin β sin α, cos β) + β̇ (sin α, cos α, 0) + α̇ (0, 0, 1)``; the body
    axes are S rotated by π about x (``BODY_TO_SHOULDER``), which flips y and z.
    """
    a = np.asarray(angles, dtype=np.float64)
    r = np.asarray(rates, dtype=np.float64)
    sb, cb = np.sin(a[:, 1]), np.cos(a[:, 1])
    sa, ca = np.sin(a[:, 2]), np.cos(a[:, 2])
    g, b, al = r[:, 0], r[:, 1], r[:, 2]
    omega_s = np.stack([-g * sb * ca + b * sa, g * sb * sa + b * ca, g * cb + al], axis=1)
    return omega_s * np.array([1.0, -1.0, -1.0])


@dataclass(frozen=True)
class Reference:
    """The target trajectory sampled on the control grid.

    Attributes
    ----------
    dt : float
        Grid spacing = the simulation time step, seconds.
    times : (K + 1,) array, seconds
        ``k * dt`` from the start of the trajectory.
    positions : (K + 1, n_dofs) array, radians
        Joint positions (ball joints: rotation vectors).
    velocities : (K + 1, n_dofs) array, rad/s
        Joint velocities (ball joints: angular velocity in the child frame, the convention of
        DART's ball-joint velocities; :func:`shoulder_angular_velocity`).
    via_steps : (n_via,) int array
        Grid indices of the via points, increasing; the last is K.
    duration : float
        Duration of the input trajectory, seconds.
    """

    dt: float
    times: NDArray[np.float64]
    positions: NDArray[np.float64]
    velocities: NDArray[np.float64]
    via_steps: NDArray[np.int64]
    duration: float


class ReferenceStream:
    """The target trajectory of :func:`build_reference`, computed a window of grid steps at a
    time (:meth:`window`) instead of all at once: the same values, in memory bounded by the
    window whatever the length. Attributes as :class:`Reference` (``via_steps``, ``dt``,
    ``duration``), ``n_grid`` = K + 1 grid points."""

    def __init__(
        self,
        skeleton: dart.dynamics.Skeleton,
        times: ArrayLike,
        angles: ArrayLike,
        dt: float,
        via_spacing: float = 0.1,
    ) -> None:
        t, a = validate_trajectory(times, angles)
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number of seconds, got {dt}")
        if not (np.isfinite(via_spacing) and via_spacing >= dt):
            raise ValueError(
                f"via_spacing must be at least the time step {dt} s, got {via_spacing} s"
            )
        self.skeleton = skeleton
        self.dt = float(dt)
        self.duration = float(t[-1] - t[0])
        n_steps = max(1, int(round(self.duration / dt)))
        self.n_grid = n_steps + 1
        self.n_arms = a.shape[1] // 4
        self._spline = CubicSpline(t - t[0], a, axis=0)
        stride = max(1, int(round(via_spacing / dt)))
        via = np.arange(stride, n_steps, stride, dtype=np.int64)
        if via.size and n_steps - via[-1] < stride // 2:
            via = via[:-1]  # avoid a via point crowding the end point
        self.via_steps = np.append(via, np.int64(n_steps))

    def _grid(self, steps: NDArray[np.int64]) -> NDArray[np.float64]:
        return np.minimum(steps * self.dt, self.duration)

    def positions_at(self, steps: ArrayLike) -> NDArray[np.float64]:
        """Joint positions (k, n_dofs) at grid indices ``steps``."""
        grid = self._grid(np.asarray(steps, dtype=np.int64))
        return angles_to_positions(self.skeleton, self._spline(grid))

    def window(self, start: int, stop: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Joint positions and velocities (each (stop − start, n_dofs)) at grid indices
        ``start`` to ``stop − 1`` (clipped to the grid)."""
        steps = np.arange(max(0, start), min(self.n_grid, stop), dtype=np.int64)
        grid = self._grid(steps)
        a_grid = self._spline(grid)
        q = angles_to_positions(self.skeleton, a_grid)
        v = np.zeros_like(q)
        rates = self._spline(grid, 1)
        for (side, arm), (_, rate) in zip(_arms(a_grid), _arms(rates), strict=True):
            sh, el = arm_dof_indices(self.skeleton, side)
            omega = shoulder_angular_velocity(arm, rate)
            # A reflection turns an angular velocity (a pseudo-vector) w into -P w.
            v[:, sh] = -omega @ MIRROR if side == "left" else omega
            v[:, el] = rate[:, 3]
        return q, v

    def reference(self) -> Reference:
        """The whole :class:`Reference` (every grid step in memory)."""
        q, v = self.window(0, self.n_grid)
        times = np.arange(self.n_grid, dtype=np.float64) * self.dt
        return Reference(self.dt, times, q, v, self.via_steps, self.duration)


def build_reference(
    skeleton: dart.dynamics.Skeleton,
    times: ArrayLike,
    angles: ArrayLike,
    dt: float,
    via_spacing: float = 0.1,
) -> Reference:
    """Sample a (T, 4) or two-arm (T, 8) angle trajectory (``times`` seconds, any origin) on
    the control grid.

    Via points every ``via_spacing`` seconds (at least one: the end point).
    """
    return ReferenceStream(skeleton, times, angles, dt, via_spacing).reference()


@dataclass
class ViaPointSequencer:
    """The via-point state machine (see the module docstring).

    ``vicinity`` in radians (every joint's error at most this), ``timeout`` in seconds of
    waiting on one via point. Each control step: if ``step == target_step`` call
    :meth:`check` with the error to the via point, then :meth:`advance`.

    Attributes: ``step`` grid index of the set point; ``current`` index of the target via
    point; ``target_step`` its grid index (-1 once done); ``wait`` seconds waited on it;
    ``reached`` / ``reach_times`` (s, NaN if missed) per via point.
    """

    reference: Reference | ReferenceStream
    joint_slices: list[slice]
    vicinity: float
    timeout: float
    step: int = field(init=False, default=0)
    current: int = field(init=False, default=0)
    target_step: int = field(init=False, default=-1)
    wait: float = field(init=False, default=0.0)
    reached: NDArray[np.bool_] = field(init=False)
    reach_times: NDArray[np.float64] = field(init=False)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.vicinity) and self.vicinity > 0):
            raise ValueError(f"vicinity must be > 0 radians, got {self.vicinity}")
        if not (np.isfinite(self.timeout) and self.timeout >= 0):
            raise ValueError(f"timeout must be >= 0 seconds, got {self.timeout}")
        self._via = [int(v) for v in self.reference.via_steps]
        self.reached = np.zeros(len(self._via), dtype=bool)
        self.reach_times = np.full(len(self._via), np.nan)
        self.target_step = self._via[0]

    @property
    def done(self) -> bool:
        """Whether every via point has been reached or given up."""
        return self.current >= len(self._via)

    def joint_errors(self, error: NDArray[np.float64]) -> NDArray[np.float64]:
        """Per-joint error magnitudes (radians) of a DOF error vector."""
        return np.array([np.sqrt(np.dot(error[s], error[s])) for s in self.joint_slices])

    def check(self, error: NDArray[np.float64], time: float) -> None:
        """At the target via point: take the next target if ``error`` (θ_via ⊖ θ, radians)
        is within the vicinity or the wait has timed out. ``time`` (s) is recorded when
        reached."""
        if self.joint_errors(error).max() <= self.vicinity:
            self.reached[self.current] = True
            self.reach_times[self.current] = time
        elif self.wait < self.timeout:
            return
        self.current += 1
        self.wait = 0.0
        self.target_step = self._via[self.current] if self.current < len(self._via) else -1

    def advance(self) -> bool:
        """Move the set point one grid step towards the target via point, or wait on it.

        Returns True if the set point moved (the target velocity applies), False if it waits.
        """
        if self.step < self.target_step:
            self.step += 1
            return True
        self.wait += self.reference.dt
        return False
