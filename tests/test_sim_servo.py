"""The stable-PD servo: stability where explicit PD fails, posture holding under gravity."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.sim.model import build_adonis
from visprim.sim.playback import play
from visprim.sim.servo import GAINS, JointGains, StablePD, gains_per_dof


def _regulate(explicit: bool, steps: int = 1000) -> tuple[bool, float]:
    """Servo every joint to rest from a perturbed wrist; (stayed finite and slow, final err)."""
    world, skel = build_adonis(0.001)
    if explicit:
        kp, kd = gains_per_dof(skel)
    else:
        servo = StablePD(skel, 0.001)
    q0 = np.zeros(20)
    q0[skel.getJoint("r_wrist").getIndexInSkeleton(0) + np.arange(3)] = [0.3, 0.2, 0.5]
    skel.setPositions(q0)
    rest = np.zeros(20)
    for _ in range(steps):
        q, dq = skel.getPositions(), skel.getVelocities()
        err = skel.getPositionDifferences(rest, q)
        tau = kp * err - kd * dq if explicit else servo.forces(err, dq, None)
        skel.setForces(tau)
        world.step()
        v = skel.getVelocities()
        if not np.all(np.isfinite(v)) or np.abs(v).max() > 1e3:
            return False, np.inf
    return True, float(np.abs(skel.getPositions()).max())


def test_explicit_pd_diverges_where_stable_pd_converges() -> None:
    """The reason for stable PD (servo.py docstring): with the same gains at 1 ms, explicit
    PD blows up on the light hand while stable PD settles."""
    stable_ok, stable_err = _regulate(explicit=False)
    explicit_ok, _ = _regulate(explicit=True)
    assert stable_ok and stable_err < 1e-3
    assert not explicit_ok


def test_holds_rest_posture_under_gravity() -> None:
    times = np.array([0.0, 2.0])
    rest = np.zeros((2, 4))  # arm hanging, elbow straight
    pb = play(times, rest)
    assert pb.max_error_deg < 0.05
    assert pb.rest_max_error_deg < 0.05
    assert np.all(np.isfinite(pb.q_actual))


def test_holds_outstretched_arm_with_small_gravity_sag() -> None:
    """Arm forward and horizontal, elbow straight: gravity ~11 N·m on a 600 N·m/rad shoulder.
    PD alone sags; the inverse-dynamics feedforward compensates gravity."""
    angles = np.tile([0.0, np.pi / 2, 0.0, 0.05], (2, 1))
    pb = play(np.array([0.0, 2.0]), angles, feedforward=False)
    shoulder = pb.joint_names.index("r_shoulder")
    sag = pb.joint_errors_deg[-1, shoulder]
    assert 0.3 < sag < 2.0  # present (gravity acts) and small
    # Settled: the last 0.5 s barely moves.
    tail = pb.q_actual[pb.times > 1.5]
    assert np.ptp(tail, axis=0).max() < np.radians(0.05)
    compensated = play(np.array([0.0, 2.0]), angles)
    assert compensated.joint_errors_deg[-1, shoulder] < 0.1 * sag


def test_gains_table_documented_values_and_coverage() -> None:
    _, skel = build_adonis()
    kp, kd = gains_per_dof(skel)
    assert kp.shape == kd.shape == (20,)
    assert np.all(kp > 0) and np.all(kd > 0)
    sh = skel.getJoint("l_shoulder").getIndexInSkeleton(0)
    assert kp[sh] == GAINS["shoulder"].kp and kd[sh + 2] == GAINS["shoulder"].kd
    override = dict(GAINS, r_elbow=JointGains(1.0, 2.0))
    kp2, kd2 = gains_per_dof(skel, override)
    el = skel.getJoint("r_elbow").getIndexInSkeleton(0)
    assert (kp2[el], kd2[el]) == (1.0, 2.0)
    assert kp2[skel.getJoint("l_elbow").getIndexInSkeleton(0)] == GAINS["elbow"].kp


def test_missing_or_bad_gains_are_reported() -> None:
    _, skel = build_adonis()
    partial = {k: v for k, v in GAINS.items() if k != "neck"}
    with pytest.raises(ValueError, match="neck"):
        gains_per_dof(skel, partial)
    with pytest.raises(ValueError, match="wrist"):
        gains_per_dof(skel, dict(GAINS, wrist=JointGains(-1.0, 1.0)))
    with pytest.raises(ValueError, match="dt"):
        StablePD(skel, 0.0)
