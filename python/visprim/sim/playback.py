"""Play an arm trajectory on Adonis: via-point sequencer + servo + metrics.

:func:`play` is the one entry point: it builds (or reuses) the model, maps the trajectory onto
the right arm, or both (:mod:`visprim.sim.sequencer`), runs the servo
(:mod:`visprim.sim.servo`) at the world's time step with gravity and no collision, and returns
a :class:`Playback` with the tracking metrics and the body transforms at a render rate for
:mod:`visprim.sim.render`.

Servos: the stable PD (default) follows the smooth trajectory, with the inverse dynamics of
the trajectory as feedforward (:func:`inverse_dynamics_feedforward`; the PD only corrects
what the model of the body gets wrong, here nothing but the discretisation, so it tracks to
a fraction of a degree) and waits on via points it has not reached; ``servo="paper"`` is the
method's explicit PD towards one via point at a time.

Joint error: for a ball joint the angle of the rotation from target to actual (geodesic,
independent of the Euler-angle parametrisation, so finite at the Z-Y-Z singularity), for a
revolute joint the absolute angle difference. The tracking metrics are taken over the two
joints the angles drive (shoulder and elbow of each driven arm) at every time step, against the set
point the servo was following (the target trajectory including any waits on via points).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from functools import partial
from typing import Any

import dartpy as dart
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from visprim.sim.kinematics import BatchKinematics
from visprim.sim.model import HAND_POINT, LINKS, ShapeSpec, build_adonis
from visprim.sim.sequencer import (
    ELBOW_JOINT,
    LEFT_ELBOW_JOINT,
    LEFT_SHOULDER_JOINT,
    SHOULDER_JOINT,
    Reference,
    ReferenceStream,
    ViaPointSequencer,
)
from visprim.sim.servo import ExplicitPD, JointGains, StablePD
from visprim.sim.trace import Trace, TraceWriter

#: Grid steps of the reference computed at once (positions, velocities, feedforward).
WINDOW_STEPS = 4096
#: Control steps recorded in memory before they are measured and stored.
BLOCK_STEPS = 4096

#: Joint speed (rad/s) beyond which a playback is declared diverged.
DIVERGENCE_SPEED: float = 1.0e3


class SimulationDiverged(RuntimeError):
    """The simulation produced NaN or runaway joint velocities."""


@dataclass(eq=False)
class Playback:
    """Result of :func:`play`. Times in seconds from the start, angles in radians unless the
    name says ``_deg``.

    Attributes
    ----------
    times : (N,) array, s
        Every control step (the simulation time step apart).
    q_target, q_actual : (N, 20) arrays, rad
        Set point and actual joint positions (ball joints: rotation vectors; order
        ``dof_names``). These per-step tables, ``joint_errors_deg`` and ``frames`` are
        numpy arrays, or for a long playback (beyond :data:`visprim.sim.trace.SPILL_BYTES`
        each) a :class:`visprim.sim.trace.Trace` on disk that indexes like one
        (``np.asarray`` loads it): memory stays bounded whatever the length.
    joint_errors_deg : (N, n_joints) array, degrees
        Error of every joint with DOF (order ``joint_names``), see the module docstring.
    rms_error_deg, max_error_deg : float
        RMS and maximum error of the driven shoulders and elbows over all steps.
    rest_max_error_deg : float
        Largest error of any other joint (held at rest).
    completion_time : float, s
        When the last via point was reached (or given up after its timeout).
    movement_duration : float, s
        Duration of the trajectory that was played.
    reached_all : bool
        Whether every via point was reached within the vicinity (none timed out).
    via_times : (n_via,) array, s
        Nominal times of the via points on the trajectory.
    via_reach_times : (n_via,) array, s
        When each via point was reached (NaN if it timed out).
    frame_times : (F,) array, s
        Times of the rendered frames (every ``1 / render_fps`` s and the final state).
    frames : (F, n_bodies, 4, 4) array
        World transforms of every body (order ``body_names``) at ``frame_times``, metres.
    hand_path : (F, 3) array, m
        The right hand's finger point (:data:`visprim.sim.model.HAND_POINT`) at the frames.
    hand_reference : (M, 3) array, m
        The finger point along the target trajectory (forward kinematics, every 10 ms).
    hand_via : (n_via, 3) array, m
        The finger point at the via points.
    body_names : tuple of str; body_shapes : tuple of tuples of ShapeSpec
        The bodies and their shapes, for rendering.
    dof_names, joint_names : tuple of str
    render_fps : float
        Frame rate at which ``frames`` were recorded (Hz).
    wall_time : float, s
        Wall-clock time of the simulation loop (informative; not deterministic).
    """

    times: NDArray[np.float64]
    q_target: NDArray[np.float64] | Trace
    q_actual: NDArray[np.float64] | Trace
    joint_errors_deg: NDArray[np.float64] | Trace
    rms_error_deg: float
    max_error_deg: float
    rest_max_error_deg: float
    completion_time: float
    movement_duration: float
    reached_all: bool
    via_times: NDArray[np.float64]
    via_reach_times: NDArray[np.float64]
    frame_times: NDArray[np.float64]
    frames: NDArray[np.float64] | Trace
    hand_path: NDArray[np.float64]
    hand_reference: NDArray[np.float64]
    hand_via: NDArray[np.float64]
    body_names: tuple[str, ...]
    body_shapes: tuple[tuple[ShapeSpec, ...], ...]
    dof_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    render_fps: float
    wall_time: float

    @property
    def n_via(self) -> int:
        """Number of via points."""
        return int(self.via_times.shape[0])

    @property
    def n_reached(self) -> int:
        """Number of via points reached within the vicinity."""
        return int(np.isfinite(self.via_reach_times).sum())

    @property
    def time_ratio(self) -> float:
        """``completion_time / movement_duration`` (1 = the movement's own pace)."""
        return self.completion_time / self.movement_duration

    def summary(self) -> str:
        """One line: tracking errors, completion time, via points."""
        return (
            f"RMS {self.rms_error_deg:.2f} deg, max {self.max_error_deg:.2f} deg, "
            f"completed in {self.completion_time:.2f} s of {self.movement_duration:.2f} s "
            f"({self.time_ratio:.2f}x), via points {self.n_reached}/{self.n_via}"
        )


def _joint_slices(skeleton: dart.dynamics.Skeleton) -> tuple[list[str], list[slice]]:
    names, slices = [], []
    for j in range(skeleton.getNumJoints()):
        joint = skeleton.getJoint(j)
        n = joint.getNumDofs()
        if n:
            start = joint.getIndexInSkeleton(0)
            names.append(joint.getName())
            slices.append(slice(start, start + n))
    return names, slices


def joint_errors(
    skeleton: dart.dynamics.Skeleton, q_target: ArrayLike, q_actual: ArrayLike
) -> NDArray[np.float64]:
    """Per-joint errors (N, n_joints) in radians between two (N, n_dofs) position arrays.

    Ball joints (3 DOF, rotation vectors): the angle of ``R_targetᵀ R_actual``; 1-DOF joints:
    the absolute difference.
    """
    qt = np.atleast_2d(np.asarray(q_target, dtype=np.float64))
    qa = np.atleast_2d(np.asarray(q_actual, dtype=np.float64))
    if qt.shape != qa.shape or qt.shape[1] != skeleton.getNumDofs():
        raise ValueError(
            f"joint_errors: q_target {qt.shape} and q_actual {qa.shape} must both be "
            f"(N, {skeleton.getNumDofs()})"
        )
    _, slices = _joint_slices(skeleton)
    out = np.empty((qt.shape[0], len(slices)))
    for i, s in enumerate(slices):
        if s.stop - s.start == 3 and not np.any(qt[:, s]):
            # Target at rest: the error is the rotation of the actual pose itself.
            out[:, i] = Rotation.from_rotvec(qa[:, s]).magnitude()
        elif s.stop - s.start == 3:
            rel = Rotation.from_rotvec(qt[:, s]).inv() * Rotation.from_rotvec(qa[:, s])
            out[:, i] = rel.magnitude()
        else:
            out[:, i] = np.abs(qa[:, s] - qt[:, s]).max(axis=1)
    return out


def body_transforms(skeleton: dart.dynamics.Skeleton) -> NDArray[np.float64]:
    """World transforms (n_bodies, 4, 4) of every body node, metres."""
    return np.stack([b.getWorldTransform().matrix() for b in skeleton.getBodyNodes()])


def hand_points(frames: NDArray[np.float64], hand_index: int) -> NDArray[np.float64]:
    """The finger point (:data:`HAND_POINT`) in the world for (F, n_bodies, 4, 4) frames."""
    tf = frames[:, hand_index]
    return tf[:, :3, :3] @ np.asarray(HAND_POINT) + tf[:, :3, 3]


def play(
    times: ArrayLike,
    angles: ArrayLike,
    *,
    vicinity: float = math.radians(3.0),
    timeout: float = 0.5,
    via_spacing: float = 0.1,
    dt: float = 0.001,
    render_fps: float = 25.0,
    gains: dict[str, JointGains] | None = None,
    model: tuple[dart.simulation.World, dart.dynamics.Skeleton] | None = None,
    servo: str = "stable",
    feedforward: bool = True,
) -> Playback:
    """Perform a right-arm (or two-arm) trajectory on Adonis and measure how well it was tracked.

    Parameters
    ----------
    times : (T,) array, seconds
        Strictly increasing sample times (any origin).
    angles : (T, 4) or (T, 8) array, radians
        The method's angles (γ, β, α, elbow) of the right arm (:mod:`visprim.arm`), then for
        (T, 8) those of the left arm (mirror convention, :func:`.sequencer.angles_to_positions`).
    vicinity : float, radians
        A via point counts as reached when every joint is within this of it (default 3°).
    timeout : float, seconds
        Longest wait on one via point before it is given up (default 0.5 s).
    via_spacing : float, seconds
        Via points every this much trajectory time (default 0.1 s), plus the end point.
    dt : float, seconds
        Simulation and control time step (default 1 ms).
    render_fps : float, Hz
        Rate at which body transforms are stored for rendering (default 25).
    gains : dict, optional
        Per-joint PD gains (default :data:`visprim.sim.servo.GAINS`).
    model : (world, skeleton), optional
        Reuse a model from :func:`build_adonis` (its time step must equal ``dt``); its state
        is overwritten. By default a new one is built.
    servo : "stable" or "paper"
        ``"stable"`` (default): stable PD following the smooth trajectory, waiting on via
        points it has not reached (:mod:`visprim.sim.sequencer`). ``"paper"``: the method's
        explicit PD law of eq. (1) towards one via point at a time, the next one taken as soon
        as the arm is within ``vicinity`` of the current one (:mod:`visprim.sim.servo`).

    The body starts at rest except for the right arm, which starts on the trajectory's first
    sample with its velocity; the run ends when the last via point is reached or given up.

    Raises
    ------
    ValueError
        Bad trajectory or parameters (the message names the argument).
    SimulationDiverged
        NaN or joint speeds above :data:`DIVERGENCE_SPEED` rad/s.
    """
    if not (np.isfinite(render_fps) and render_fps > 0):
        raise ValueError(f"render_fps must be > 0 Hz, got {render_fps}")
    if servo not in ("stable", "paper"):
        raise ValueError(f"servo must be 'stable' or 'paper', got {servo!r}")
    if model is None:
        world, skel = build_adonis(dt)
    else:
        world, skel = model
        if not math.isclose(world.getTimeStep(), dt, rel_tol=1e-12):
            raise ValueError(
                f"model: the world's time step {world.getTimeStep()} s differs from dt = {dt} s"
            )
    ref = ReferenceStream(skel, times, angles, dt, via_spacing)
    kinematics = BatchKinematics(skel)
    joint_names, slices = _joint_slices(skel)
    body_names = tuple(b.getName() for b in skel.getBodyNodes())
    hand_index = body_names.index("r_hand")

    # Forward kinematics of the target (numpy; the skeleton is left alone), a window at a
    # time.
    ref_stride = max(1, int(round(0.01 / dt)))
    ref_steps = np.unique(np.append(np.arange(0, ref.n_grid, ref_stride), ref.via_steps))
    hand_reference = np.concatenate(
        [
            hand_points(kinematics.transforms(ref.positions_at(part)), hand_index)
            for part in np.array_split(ref_steps, max(1, ref_steps.size // WINDOW_STEPS))
        ]
    )
    hand_via = hand_points(kinematics.transforms(ref.positions_at(ref.via_steps)), hand_index)

    first_q, first_v = ref.window(0, 1)
    world.reset()
    skel.resetCommands()
    skel.clearExternalForces()
    skel.setPositions(first_q[0])
    skel.setVelocities(first_v[0])

    driven = [SHOULDER_JOINT, ELBOW_JOINT]
    if np.shape(angles)[1] == 8:
        driven += [LEFT_SHOULDER_JOINT, LEFT_ELBOW_JOINT]
    arm = [joint_names.index(j) for j in driven]
    frame_stride = max(1, int(round(1.0 / (render_fps * dt))))
    rec = _Recorder(skel, kinematics, frame_stride, dt, arm, hand_index)
    run: Any = _run_paper
    wall0 = time.perf_counter()
    if servo == "stable":
        run = partial(_run_stable, feedforward=feedforward)
    completion, (reached, reach_times) = run(
        world, skel, ref, slices, float(vicinity), float(timeout), gains, rec, driven
    )
    wall_time = time.perf_counter() - wall0
    out = rec.finish()
    n_rec = out["n"]
    return Playback(
        times=np.arange(n_rec, dtype=np.float64) * dt,
        q_target=out["q_target"],
        q_actual=out["q_actual"],
        joint_errors_deg=out["errors"],
        rms_error_deg=out["rms_deg"],
        max_error_deg=out["max_deg"],
        rest_max_error_deg=out["rest_max_deg"],
        completion_time=completion,
        movement_duration=ref.duration,
        reached_all=bool(reached.all()),
        via_times=ref.via_steps.astype(np.float64) * dt,
        via_reach_times=reach_times.copy(),
        frame_times=out["frame_steps"] * dt,
        frames=out["frames"],
        hand_path=out["hand_path"],
        hand_reference=hand_reference,
        hand_via=hand_via,
        body_names=body_names,
        body_shapes=tuple(_shapes_by_name()[name] for name in body_names),
        dof_names=tuple(skel.getDof(i).getName() for i in range(skel.getNumDofs())),
        joint_names=tuple(joint_names),
        render_fps=float(render_fps),
        wall_time=wall_time,
    )


def _driven_ball_joints(
    skel: dart.dynamics.Skeleton, driven: list[str], slices: list[slice]
) -> list[tuple[slice, dart.dynamics.Joint]]:
    """The ball joints the angles drive (the shoulders), with their DOF slices.

    The error ``θd ⊖ θ`` of every other joint is a plain difference: revolute joints
    subtract, and a ball joint aimed at rest has ``log(R(θ)ᵀ) = −θ`` exactly in DART's
    exponential coordinates. Only the driven ball joints need DART's geodesic difference,
    which keeps the per-step cost down.
    """
    names, _ = _joint_slices(skel)
    out = []
    for name, sl in zip(names, slices, strict=True):
        if sl.stop - sl.start == 3 and name in driven:
            out.append((sl, skel.getJoint(name)))
    return out


def inverse_dynamics_feedforward(
    skel: dart.dynamics.Skeleton, ref: Reference, stride: int = 10
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Joint torques (N·m) that perform the reference exactly, ``M(θd) θ̈d + C(θd, θ̇d) +
    g(θd)``, and those that hold it still, ``g(θd)``, on the control grid (each (K + 1,
    n_dofs)).

    Inverse dynamics of the *reference* (not of the measured state, so the feedforward adds
    no feedback loop), evaluated every ``stride`` grid steps and interpolated linearly in
    between; θ̈d is the finite difference of θ̇d. The skeleton's state is restored.
    :class:`_Window` computes the same a window at a time.
    """
    n = ref.positions.shape[0]
    return _feedforward(skel, ref.positions, ref.velocities, ref.dt, 0, 0, n, n, stride)


def _feedforward(
    skel: dart.dynamics.Skeleton,
    q: NDArray[np.float64],
    v: NDArray[np.float64],
    dt: float,
    offset: int,
    first: int,
    stop: int,
    n: int,
    stride: int = 10,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`inverse_dynamics_feedforward` at grid steps ``first`` to ``stop − 1`` of an
    ``n``-step grid, from positions and velocities ``q``, ``v`` given at grid steps
    ``offset`` to ``offset + len(q) − 1`` (from one step before ``first`` to one step past
    the last coarse step needed, where the grid has them). ``first`` is a multiple of
    ``stride``."""
    saved = (skel.getPositions(), skel.getVelocities())
    last = min(((stop - 1) // stride + 1) * stride, n - 1)
    coarse = np.unique(np.append(np.arange(first, last + 1, stride), last))
    zero = np.zeros(skel.getNumDofs())
    move = np.empty((coarse.size, zero.size))
    hold = np.empty_like(move)
    for i, k in enumerate(coarse):
        r = k - offset
        # np.gradient's differences: central inside the grid, one-sided at its two ends.
        if n < 2:
            acc = zero
        elif k == 0:
            acc = (v[r + 1] - v[r]) / dt
        elif k == n - 1:
            acc = (v[r] - v[r - 1]) / dt
        else:
            acc = (v[r + 1] - v[r - 1]) / (2.0 * dt)
        skel.setPositions(q[r])
        skel.setVelocities(v[r])
        skel.setAccelerations(acc)
        skel.computeInverseDynamics(False, False, False)
        move[i] = skel.getForces()
        skel.setVelocities(zero)
        skel.setAccelerations(zero)
        skel.computeInverseDynamics(False, False, False)
        hold[i] = skel.getForces()
    skel.setPositions(saved[0])
    skel.setVelocities(saved[1])
    skel.resetCommands()
    grid = np.arange(first, stop)

    def interp(values: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.stack([np.interp(grid, coarse, values[:, j]) for j in range(values.shape[1])], 1)

    return interp(move), interp(hold)


class _Window:
    """The reference (positions; with ``feedforward``, the stable PD's feedforward while
    moving, ``kd θ̇d`` plus the inverse dynamics, and while holding) on grid steps
    ``[start, stop)``, computed :data:`WINDOW_STEPS` at a time as the set point advances."""

    def __init__(
        self,
        skel: dart.dynamics.Skeleton,
        ref: ReferenceStream,
        kd: NDArray[np.float64] | None,
        feedforward: bool,
    ) -> None:
        self.skel, self.ref, self.kd, self.feedforward = skel, ref, kd, feedforward
        self.start = self.stop = 0
        self.positions = np.empty((0, skel.getNumDofs()))
        self.move = self.hold = self.positions

    def load(self, k: int) -> None:
        """Make the window the one holding grid step ``k``."""
        n = self.ref.n_grid
        start = (k // WINDOW_STEPS) * WINDOW_STEPS  # a multiple of the feedforward's stride
        stop = min(n, start + WINDOW_STEPS)
        if self.kd is None:  # positions only
            self.positions, _ = self.ref.window(start, stop)
        else:
            last = min(((stop - 1) // 10 + 1) * 10, n - 1)
            lo = max(0, start - 1)
            q, v = self.ref.window(lo, min(n, last + 2))
            self.positions = q[start - lo : start - lo + stop - start]
            vel = v[start - lo : start - lo + stop - start]
            if self.feedforward:
                move, hold = _feedforward(self.skel, q, v, self.ref.dt, lo, start, stop, n)
            else:
                move, hold = np.zeros_like(vel), np.zeros_like(vel)
            self.move = vel * self.kd + move
            self.hold = hold
        self.start, self.stop = start, stop


class _Recorder:
    """The control steps, :data:`BLOCK_STEPS` at a time: joint positions and set points as
    the loops write them (:meth:`row`), measured and stored when a block is full
    (:meth:`flush`: joint errors, the running RMS and maxima, the body transforms at the
    frames, every ``stride`` steps, written by :class:`~visprim.sim.trace.TraceWriter`, so a
    long playback goes to disk)."""

    def __init__(
        self,
        skel: dart.dynamics.Skeleton,
        kinematics: BatchKinematics,
        stride: int,
        dt: float,
        arm: list[int],
        hand_index: int,
    ) -> None:
        self.skel, self.kinematics, self.stride, self.dt = skel, kinematics, stride, dt
        self.arm = arm
        n_dofs = skel.getNumDofs()
        n_joints = len(_joint_slices(skel)[0])
        self.rest = [i for i in range(n_joints) if i not in arm]
        self.hand_index = hand_index
        self.q = np.empty((BLOCK_STEPS, n_dofs))
        self.target = np.empty((BLOCK_STEPS, n_dofs))
        self.j = 0  # rows filled in the block
        self.base = 0  # control step of the block's first row
        self.frame_steps = [0]
        self._frames_done = 0  # frame steps already turned into body transforms
        self.out = {
            "q_actual": TraceWriter((n_dofs,)),
            "q_target": TraceWriter((n_dofs,)),
            "errors": TraceWriter((n_joints,)),
            "frames": TraceWriter((len(kinematics.body_names), 4, 4)),
        }
        self.hand_path: list[NDArray[np.float64]] = []
        self.sum_sq = 0.0
        self.count = 0
        self.max_arm = 0.0
        self.max_rest = 0.0

    def row(self, q: NDArray[np.float64], target: NDArray[np.float64]) -> None:
        """Record one control step (the positions reached and the set point followed)."""
        if self.j == BLOCK_STEPS:
            self.flush()
        self.q[self.j] = q
        self.target[self.j] = target
        self.j += 1

    def frame(self, n: int) -> None:
        """Control step ``n`` is a frame; checks for divergence."""
        v = self.skel.getVelocities()
        q = self.skel.getPositions()
        if not (np.all(np.isfinite(q)) and np.abs(v).max() < DIVERGENCE_SPEED):
            raise SimulationDiverged(
                f"play: the simulation diverged at t = {n * self.dt:.3f} s "
                f"(max joint speed {np.abs(v).max():.3g} rad/s)"
            )
        self.frame_steps.append(n)

    def flush(self) -> None:
        qa, qt = self.q[: self.j], self.target[: self.j]
        if not np.all(np.isfinite(qa)):
            raise SimulationDiverged("play: the simulation produced NaN joint positions")
        errors = joint_errors(self.skel, qt, qa)
        arm = errors[:, self.arm]
        self.sum_sq += float(np.sum(arm * arm))
        self.count += arm.size
        self.max_arm = max(self.max_arm, float(arm.max()))
        if self.rest:
            self.max_rest = max(self.max_rest, float(errors[:, self.rest].max()))
        self.out["q_actual"].append(qa)
        self.out["q_target"].append(qt)
        self.out["errors"].append(np.degrees(errors))
        end = self.base + self.j
        steps = np.asarray(self.frame_steps[self._frames_done :], dtype=np.int64)
        steps = steps[steps < end]
        if steps.size:
            tfs = self.kinematics.transforms(qa[steps - self.base])
            self.out["frames"].append(tfs)
            self.hand_path.append(hand_points(tfs, self.hand_index))
            self._frames_done += steps.size
        self.base, self.j = end, 0

    def finish(self) -> dict[str, Any]:
        """Everything recorded (tables as arrays, or :class:`Trace` on disk when long)."""
        n_rec = self.base + self.j
        if self.frame_steps[-1] != n_rec - 1:
            self.frame_steps.append(n_rec - 1)
        self.flush()
        out: dict[str, Any] = {k: w.finish() for k, w in self.out.items()}
        out["n"] = n_rec
        out["frame_steps"] = np.asarray(self.frame_steps, dtype=np.float64)
        out["hand_path"] = np.concatenate(self.hand_path)
        out["rms_deg"] = float(np.degrees(np.sqrt(self.sum_sq / max(1, self.count))))
        out["max_deg"] = float(np.degrees(self.max_arm))
        out["rest_max_deg"] = float(np.degrees(self.max_rest)) if self.rest else 0.0
        return out


def _run_stable(
    world: dart.simulation.World,
    skel: dart.dynamics.Skeleton,
    ref: ReferenceStream,
    slices: list[slice],
    vicinity: float,
    timeout: float,
    gains: dict[str, JointGains] | None,
    rec: _Recorder,
    driven_joints: list[str],
    feedforward: bool = True,
) -> tuple[float, tuple[NDArray[np.bool_], NDArray[np.float64]]]:
    """Stable PD along the smooth trajectory with the waiting via-point sequencer."""
    dt = ref.dt
    seq = ViaPointSequencer(ref, slices, vicinity, timeout)
    servo = StablePD(skel, dt, gains)
    n_wait_max = int(math.ceil(timeout / dt)) + 2
    max_steps = ref.n_grid + ref.via_steps.shape[0] * n_wait_max + 1
    # Feedforward on the grid: kd θ̇d (the damping's share) plus the inverse dynamics of the
    # reference while the set point moves; gravity alone while it waits on a via point.
    win = _Window(skel, ref, servo.kd, feedforward)
    win.load(0)
    positions, ff, hold, w0, w1 = win.positions, win.move, win.hold, win.start, win.stop
    kp, kp_dt = servo.kp, servo.kp * dt
    driven = _driven_ball_joints(skel, driven_joints, slices)
    q = skel.getPositions()
    rec.row(q, positions[0])
    completion = max_steps * dt
    stride = rec.stride
    # The sequencer's state machine (ViaPointSequencer.check / advance) with the set point
    # index kept in a local between via points: the loop runs a thousand times a second.
    k, target_step = 0, seq.target_step
    for n in range(max_steps):
        dq = skel.getVelocities()
        if k == target_step:
            seq.step = k
            seq.check(skel.getPositionDifferences(positions[k - w0], q), n * dt)
            if seq.done:
                completion = n * dt
                break
            target_step = seq.target_step
        moved = k < target_step
        if moved:
            k += 1
            if k >= w1:
                win.load(k)
                positions, ff, hold, w0, w1 = win.positions, win.move, win.hold, win.start, win.stop
        else:
            seq.wait += dt
        i = k - w0
        target = positions[i]
        error = target - q
        for sl, joint in driven:
            error[sl] = joint.getPositionDifferences(target[sl], q[sl])
        # Stable PD (servo.StablePD.forces, inlined): DART adds the implicit -kd θ̇(n+1).
        tau = kp * error - kp_dt * dq
        tau += ff[i] if moved else hold[i]
        skel.setForces(tau)
        world.step()
        q = skel.getPositions()
        rec.row(q, target)
        if (n + 1) % stride == 0:
            rec.frame(n + 1)
    seq.step = k
    return completion, (seq.reached, seq.reach_times)


def _run_paper(
    world: dart.simulation.World,
    skel: dart.dynamics.Skeleton,
    ref: ReferenceStream,
    slices: list[slice],
    vicinity: float,
    timeout: float,
    gains: dict[str, JointGains] | None,
    rec: _Recorder,
    driven_joints: list[str],
) -> tuple[float, tuple[NDArray[np.bool_], NDArray[np.float64]]]:
    """The paper's servo: explicit PD (eq. (1)) towards the current via point, held still
    (θ̇d = 0); the next via point is taken when every joint is within ``vicinity`` of it (or
    after ``timeout``, then it counts as missed)."""
    dt = ref.dt
    servo = ExplicitPD(skel, gains)
    via = [int(v) for v in ref.via_steps]
    reached = np.zeros(len(via), dtype=bool)
    reach_times = np.full(len(via), np.nan)
    starts = np.array([s.start for s in slices], dtype=np.intp)
    vicinity2 = vicinity * vicinity
    n_wait = int(math.ceil(timeout / dt))
    max_steps = len(via) * (n_wait + 2) + 1
    win = _Window(skel, ref, None, False)

    def position(k: int) -> NDArray[np.float64]:
        if not win.start <= k < win.stop:
            win.load(k)
        return win.positions[k - win.start]

    current, waited = 0, 0
    k = via[0]
    q = skel.getPositions()
    rec.row(q, position(0))
    completion = max_steps * dt
    driven = _driven_ball_joints(skel, driven_joints, slices)
    stride = rec.stride

    def position_error(target: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
        error = target - q
        for sl, joint in driven:
            error[sl] = joint.getPositionDifferences(target[sl], q[sl])
        return error

    target = position(k)
    for n in range(max_steps):
        error = position_error(target, q)
        while True:
            near = bool(np.add.reduceat(error * error, starts).max() <= vicinity2)
            if not near and waited < n_wait:
                break
            if near:
                reached[current] = True
                reach_times[current] = n * dt
            current += 1
            waited = 0
            if current == len(via):
                break
            k = via[current]
            target = position(k)
            error = position_error(target, q)
        if current == len(via):
            completion = n * dt
            break
        dq = skel.getVelocities()
        if not np.abs(dq).max() < DIVERGENCE_SPEED:  # explicit PD: check every step
            raise SimulationDiverged(
                f"play: the simulation diverged at t = {n * dt:.4f} s with the paper's explicit "
                f"PD at dt = {dt:g} s (max joint speed {np.abs(dq).max():.3g} rad/s); "
                "try a smaller time step"
            )
        # The set point is the via point itself, held still: θ̇d = 0.
        skel.setForces(servo.forces(error, dq, None))
        world.step()
        waited += 1
        q = skel.getPositions()
        rec.row(q, target)
        if (n + 1) % stride == 0:
            rec.frame(n + 1)
    return completion, (reached, reach_times)


def _shapes_by_name() -> dict[str, tuple[ShapeSpec, ...]]:
    return {link.name: link.shapes for link in LINKS}
