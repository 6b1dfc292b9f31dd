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
    ViaPointSequencer,
    build_reference,
)
from visprim.sim.servo import ExplicitPD, JointGains, StablePD

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
        ``dof_names``).
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
    q_target: NDArray[np.float64]
    q_actual: NDArray[np.float64]
    joint_errors_deg: NDArray[np.float64]
    rms_error_deg: float
    max_error_deg: float
    rest_max_error_deg: float
    completion_time: float
    movement_duration: float
    reached_all: bool
    via_times: NDArray[np.float64]
    via_reach_times: NDArray[np.float64]
    frame_times: NDArray[np.float64]
    frames: NDArray[np.float64]
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
    ref = build_reference(skel, times, angles, dt, via_spacing)
    kinematics = BatchKinematics(skel)
    joint_names, slices = _joint_slices(skel)
    positions, velocities = ref.positions, ref.velocities
    body_names = tuple(b.getName() for b in skel.getBodyNodes())
    hand_index = body_names.index("r_hand")

    # Forward kinematics of the target (numpy; the skeleton is left alone).
    ref_stride = max(1, int(round(0.01 / dt)))
    ref_steps = np.unique(np.append(np.arange(0, ref.times.shape[0], ref_stride), ref.via_steps))
    hand_reference = hand_points(kinematics.transforms(positions[ref_steps]), hand_index)
    hand_via = hand_points(kinematics.transforms(positions[ref.via_steps]), hand_index)

    world.reset()
    skel.resetCommands()
    skel.clearExternalForces()
    skel.setPositions(positions[0])
    skel.setVelocities(velocities[0])

    frame_stride = max(1, int(round(1.0 / (render_fps * dt))))
    run: Any = _run_paper
    wall0 = time.perf_counter()
    if servo == "stable":
        run = partial(_run_stable, feedforward=feedforward)
    rec, seq_state = run(
        world, skel, ref, slices, float(vicinity), float(timeout), gains, frame_stride
    )
    wall_time = time.perf_counter() - wall0
    rec_q, rec_k, n_rec, completion, frame_steps = rec
    reached, reach_times = seq_state
    if not np.all(np.isfinite(rec_q[:n_rec])):
        raise SimulationDiverged("play: the simulation produced NaN joint positions")
    if frame_steps[-1] != n_rec - 1:
        frame_steps.append(n_rec - 1)
    # Body transforms at the frames, from the recorded joint positions (the same forward
    # kinematics as DART's, vectorised after the run rather than queried in the loop).
    frames_arr = kinematics.transforms(rec_q[frame_steps])

    q_actual = rec_q[:n_rec].copy()
    q_target = positions[rec_k[:n_rec]]
    errors = joint_errors(skel, q_target, q_actual)
    driven = [SHOULDER_JOINT, ELBOW_JOINT]
    if np.shape(angles)[1] == 8:
        driven += [LEFT_SHOULDER_JOINT, LEFT_ELBOW_JOINT]
    arm = [joint_names.index(j) for j in driven]
    rest = [i for i in range(len(joint_names)) if i not in arm]
    return Playback(
        times=np.arange(n_rec, dtype=np.float64) * dt,
        q_target=q_target,
        q_actual=q_actual,
        joint_errors_deg=np.degrees(errors),
        rms_error_deg=float(np.degrees(np.sqrt(np.mean(errors[:, arm] ** 2)))),
        max_error_deg=float(np.degrees(errors[:, arm].max())),
        rest_max_error_deg=float(np.degrees(errors[:, rest].max())) if rest else 0.0,
        completion_time=completion,
        movement_duration=ref.duration,
        reached_all=bool(reached.all()),
        via_times=ref.times[ref.via_steps],
        via_reach_times=reach_times.copy(),
        frame_times=np.asarray(frame_steps, dtype=np.float64) * dt,
        frames=frames_arr,
        hand_path=hand_points(frames_arr, hand_index),
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
    skel: dart.dynamics.Skeleton, ref: Reference, slices: list[slice]
) -> list[tuple[slice, dart.dynamics.Joint]]:
    """Ball joints whose target ever leaves rest, with their DOF slices.

    The error ``θd ⊖ θ`` of every other joint is a plain difference: revolute joints
    subtract, and a ball joint aimed at rest has ``log(R(θ)ᵀ) = −θ`` exactly in DART's
    exponential coordinates. Only the driven ball joints need DART's geodesic difference,
    which keeps the per-step cost down.
    """
    names, _ = _joint_slices(skel)
    out = []
    for name, sl in zip(names, slices, strict=True):
        if sl.stop - sl.start == 3 and np.any(ref.positions[:, sl] != 0.0):
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
    """
    saved = (skel.getPositions(), skel.getVelocities())
    n = ref.positions.shape[0]
    coarse = np.unique(np.append(np.arange(0, n, stride), n - 1))
    acc = np.gradient(ref.velocities, ref.dt, axis=0) if n > 1 else np.zeros_like(ref.velocities)
    zero = np.zeros(skel.getNumDofs())
    move = np.empty((coarse.size, zero.size))
    hold = np.empty_like(move)
    for i, k in enumerate(coarse):
        skel.setPositions(ref.positions[k])
        skel.setVelocities(ref.velocities[k])
        skel.setAccelerations(acc[k])
        skel.computeInverseDynamics(False, False, False)
        move[i] = skel.getForces()
        skel.setVelocities(zero)
        skel.setAccelerations(zero)
        skel.computeInverseDynamics(False, False, False)
        hold[i] = skel.getForces()
    skel.setPositions(saved[0])
    skel.setVelocities(saved[1])
    skel.resetCommands()
    grid = np.arange(n)

    def interp(values: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.stack([np.interp(grid, coarse, values[:, j]) for j in range(values.shape[1])], 1)

    return interp(move), interp(hold)


_Record = tuple[NDArray[np.float64], NDArray[np.int64], int, float, list]


class _Recorder:
    """Joint positions and set-point indices at every step (the loops write ``q`` and ``k``
    directly, row ``n``), and the steps of the frames, every ``stride`` steps (:meth:`frame`,
    which also checks for divergence); :func:`play` turns the positions at those steps into
    body transforms afterwards."""

    def __init__(self, skel: dart.dynamics.Skeleton, n_guess: int, stride: int, dt: float) -> None:
        self.skel, self.stride, self.dt = skel, stride, dt
        self.q = np.empty((n_guess + 1000, skel.getNumDofs()))
        self.k = np.empty(n_guess + 1000, dtype=np.int64)
        self.q[0] = skel.getPositions()
        self.k[0] = 0
        self.n = 1
        self.frame_steps = [0]

    def grow(self) -> None:
        self.q = np.concatenate([self.q, np.empty_like(self.q)])
        self.k = np.concatenate([self.k, np.empty_like(self.k)])

    def frame(self, n: int, q: NDArray[np.float64]) -> None:
        v = self.skel.getVelocities()
        if not (np.all(np.isfinite(q)) and np.abs(v).max() < DIVERGENCE_SPEED):
            raise SimulationDiverged(
                f"play: the simulation diverged at t = {n * self.dt:.3f} s "
                f"(max joint speed {np.abs(v).max():.3g} rad/s)"
            )
        self.frame_steps.append(n)

    def result(self, n_rec: int, completion: float) -> _Record:
        return self.q, self.k, n_rec, completion, self.frame_steps


def _run_stable(
    world: dart.simulation.World,
    skel: dart.dynamics.Skeleton,
    ref: Reference,
    slices: list[slice],
    vicinity: float,
    timeout: float,
    gains: dict[str, JointGains] | None,
    stride: int,
    feedforward: bool = True,
) -> tuple[_Record, tuple[NDArray[np.bool_], NDArray[np.float64]]]:
    """Stable PD along the smooth trajectory with the waiting via-point sequencer."""
    dt = ref.dt
    seq = ViaPointSequencer(ref, slices, vicinity, timeout)
    servo = StablePD(skel, dt, gains)
    positions = ref.positions
    n_wait_max = int(math.ceil(timeout / dt)) + 2
    max_steps = ref.times.shape[0] + ref.via_steps.shape[0] * n_wait_max + 1
    rec = _Recorder(skel, ref.times.shape[0], stride, dt)
    # Feedforward on the grid: kd θ̇d (the damping's share) plus the inverse dynamics of the
    # reference while the set point moves; gravity alone while it waits on a via point.
    if feedforward:
        move, hold = inverse_dynamics_feedforward(skel, ref)
    else:
        move, hold = np.zeros_like(ref.velocities), np.zeros_like(ref.velocities)
    ff = ref.velocities * servo.kd + move
    kp, kp_dt = servo.kp, servo.kp * dt
    driven = _driven_ball_joints(skel, ref, slices)
    q = skel.getPositions()
    completion = max_steps * dt
    # The sequencer's state machine (ViaPointSequencer.check / advance) with the set point
    # index kept in a local between via points: the loop runs a thousand times a second.
    k, target_step = 0, seq.target_step
    rec_q, rec_k, cap, n_rec = rec.q, rec.k, rec.k.shape[0], 1
    for n in range(max_steps):
        dq = skel.getVelocities()
        if k == target_step:
            seq.step = k
            seq.check(skel.getPositionDifferences(positions[k], q), n * dt)
            if seq.done:
                completion = n * dt
                break
            target_step = seq.target_step
        moved = k < target_step
        if moved:
            k += 1
        else:
            seq.wait += dt
        target = positions[k]
        error = target - q
        for sl, joint in driven:
            error[sl] = joint.getPositionDifferences(target[sl], q[sl])
        # Stable PD (servo.StablePD.forces, inlined): DART adds the implicit -kd θ̇(n+1).
        tau = kp * error - kp_dt * dq
        tau += ff[k] if moved else hold[k]
        skel.setForces(tau)
        world.step()
        q = skel.getPositions()
        if n + 1 == cap:
            rec.grow()
            rec_q, rec_k, cap = rec.q, rec.k, rec.k.shape[0]
        rec_q[n + 1] = q
        rec_k[n + 1] = k
        if (n + 1) % stride == 0:
            rec.frame(n + 1, q)
        n_rec = n + 2
    seq.step = k
    return rec.result(n_rec, completion), (seq.reached, seq.reach_times)


def _run_paper(
    world: dart.simulation.World,
    skel: dart.dynamics.Skeleton,
    ref: Reference,
    slices: list[slice],
    vicinity: float,
    timeout: float,
    gains: dict[str, JointGains] | None,
    stride: int,
) -> tuple[_Record, tuple[NDArray[np.bool_], NDArray[np.float64]]]:
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
    rec = _Recorder(skel, ref.times.shape[0], stride, dt)
    positions = ref.positions
    current, waited, n_rec = 0, 0, 1
    k = via[0]
    q = skel.getPositions()
    completion = max_steps * dt
    driven = _driven_ball_joints(skel, ref, slices)

    def position_error(target: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
        error = target - q
        for sl, joint in driven:
            error[sl] = joint.getPositionDifferences(target[sl], q[sl])
        return error

    for n in range(max_steps):
        error = position_error(positions[k], q)
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
            error = position_error(positions[k], q)
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
        if n + 1 == rec.k.shape[0]:
            rec.grow()
        rec.q[n + 1] = q
        rec.k[n + 1] = k
        if (n + 1) % stride == 0:
            rec.frame(n + 1, q)
        n_rec = n + 2
    return rec.result(n_rec, completion), (reached, reach_times)


def _shapes_by_name() -> dict[str, tuple[ShapeSpec, ...]]:
    return {link.name: link.shapes for link in LINKS}
