"""Joint-space PD servo, made stable at a 1 ms step by the stable-PD formulation.

The control law is the method's ``τ = k (θd − θ) + kd (θ̇d − θ̇)`` per degree of freedom,
evaluated as *stable PD* (Tan, Liu & Turk, "Stable proportional-derivative controllers",
IEEE CG&A 2011): the proportional term uses the predicted next position and the damping
term acts on the next velocity,

    τ = k (θd − (θ + Δt θ̇)) + kd (θ̇d − θ̇ₙ₊₁),

which with ``θ̇ₙ₊₁ = θ̇ + Δt θ̈`` amounts to solving the forward dynamics with ``M + kd Δt``
instead of ``M``. Here that solve is DART's own: ``−kd θ̇ₙ₊₁`` is set as the joints' damping
coefficient, which DART integrates implicitly inside its articulated-body forward dynamics
(adds ``kd Δt`` to the articulated inertia of each joint, the same linear system as the
stable-PD solve with the full mass matrix), and the explicit remainder
``k (θd − θ − Δt θ̇) + kd θ̇d`` is applied as joint forces. Plain explicit PD with these gains
diverges at Δt = 1 ms on the hands (the wrist's damping ``kd Δt`` exceeds twice the hand's
inertia about its long axis, 3.4e-4 kg·m²); stable PD does not.

:func:`visprim.sim.playback.play` adds the inverse dynamics of the trajectory as feedforward
(the torques that perform it exactly), so the PD only corrects the residual; the law itself
is unchanged.

For a ball joint the position error ``θd − θ`` is the rotation vector of ``R(θ)ᵀ R(θd)``
(DART's ``getPositionDifferences``: the geodesic error in the child frame, the frame of the
joint's angular velocity), not a difference of coordinates.

Gains (:data:`GAINS`, per joint; the same for every axis of a ball joint): ``kp`` in N·m/rad,
``kd`` in N·m·s/rad, chosen near critical damping ``kd ≈ 2 sqrt(kp I)`` with ``I`` the
inertia the joint moves (straight arm, upright body). The natural frequencies ``sqrt(kp/I)``
are 20–80 rad/s, well above the 1–3 Hz content of arm movements, and stiff enough that
gravity on the outstretched arm (≈ 11 N·m) deflects the shoulder by about 1°.

======== ======= ========= ================================ ==============
joint    kp      kd        moved inertia I (kg·m²)          sqrt(kp/I)
======== ======= ========= ================================ ==============
waist    2000    200       ≈ 5 (torso, head, arms)          ≈ 20 rad/s
neck     150     10        ≈ 0.16 (head)                    ≈ 31 rad/s
shoulder 600     35        ≈ 0.51 (straight arm)            ≈ 34 rad/s
elbow    250     10        ≈ 0.095 (forearm and hand)       ≈ 51 rad/s
wrist    40      1.0       ≈ 0.0062 (hand, transverse)      ≈ 80 rad/s
======== ======= ========= ================================ ==============
"""

from __future__ import annotations

from dataclasses import dataclass

import dartpy as dart
import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class JointGains:
    """PD gains of one joint: ``kp`` N·m/rad, ``kd`` N·m·s/rad (all of its axes)."""

    kp: float
    kd: float


#: Default gains by joint type (the joint name without its ``r_``/``l_`` side prefix).
GAINS: dict[str, JointGains] = {
    "waist": JointGains(2000.0, 200.0),
    "neck": JointGains(150.0, 10.0),
    "shoulder": JointGains(600.0, 35.0),
    "elbow": JointGains(250.0, 10.0),
    "wrist": JointGains(40.0, 1.0),
}


def _joint_kind(name: str) -> str:
    return name[2:] if name[:2] in ("r_", "l_") else name


def gains_per_dof(
    skeleton: dart.dynamics.Skeleton, gains: dict[str, JointGains] | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(kp, kd)`` arrays of length ``skeleton.getNumDofs()`` from a per-joint table.

    Keys of ``gains`` are joint names without the side prefix (``"shoulder"`` covers
    ``r_shoulder`` and ``l_shoulder``); a full joint name overrides its kind. Every joint with
    degrees of freedom needs an entry.
    """
    table = GAINS if gains is None else gains
    n = skeleton.getNumDofs()
    kp = np.zeros(n)
    kd = np.zeros(n)
    for j in range(skeleton.getNumJoints()):
        joint = skeleton.getJoint(j)
        if joint.getNumDofs() == 0:
            continue
        name = joint.getName()
        entry = table.get(name, table.get(_joint_kind(name)))
        if entry is None:
            raise ValueError(f"gains: no entry for joint {name!r} (have {sorted(table)})")
        if not (entry.kp >= 0 and entry.kd >= 0 and np.isfinite([entry.kp, entry.kd]).all()):
            raise ValueError(f"gains: joint {name!r} needs finite kp, kd >= 0, got {entry}")
        start = joint.getIndexInSkeleton(0)
        kp[start : start + joint.getNumDofs()] = entry.kp
        kd[start : start + joint.getNumDofs()] = entry.kd
    return kp, kd


class StablePD:
    """Stable-PD servo for every DOF of a skeleton (see the module docstring).

    Construction sets the joints' damping coefficients to ``kd`` (DART integrates them
    implicitly) and removes joint springs; :meth:`forces` returns the explicit part of the
    torque for the current state. Call ``skeleton.setForces(servo.forces(...))`` before each
    ``world.step()``.
    """

    def __init__(
        self,
        skeleton: dart.dynamics.Skeleton,
        dt: float,
        gains: dict[str, JointGains] | None = None,
    ) -> None:
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"StablePD: dt must be a positive number of seconds, got {dt}")
        self.skeleton = skeleton
        self.dt = float(dt)
        self.kp, self.kd = gains_per_dof(skeleton, gains)
        for i in range(skeleton.getNumDofs()):
            dof = skeleton.getDof(i)
            dof.setDampingCoefficient(float(self.kd[i]))
            dof.setSpringStiffness(0.0)
        self._kp_dt = self.kp * self.dt

    def forces(
        self,
        error: NDArray[np.float64],
        velocity: NDArray[np.float64],
        target_velocity: NDArray[np.float64] | None,
    ) -> NDArray[np.float64]:
        """Explicit joint forces (N·m) for one step.

        ``error`` is ``θd ⊖ θ`` (``skeleton.getPositionDifferences(target, positions)``,
        radians), ``velocity`` the current ``θ̇`` and ``target_velocity`` ``θ̇d`` (rad/s; None
        for zero). The implicit damping ``−kd θ̇ₙ₊₁`` is added by DART.
        """
        tau = self.kp * error - self._kp_dt * velocity
        if target_velocity is not None:
            tau += self.kd * target_velocity
        return tau


class ExplicitPD:
    """The method's PD law, eq. (1), evaluated explicitly:
    ``τ = kp (θd ⊖ θ) + kd (θ̇d − θ̇)`` with the current state (N·m).

    Construction removes the joints' damping and springs (the whole law is in the forces).
    Explicit damping is stable only while ``kd Δt`` stays below about twice the smallest
    inertia a joint moves; :mod:`benches.bench_servo` measures the largest step it tolerates.
    """

    def __init__(
        self, skeleton: dart.dynamics.Skeleton, gains: dict[str, JointGains] | None = None
    ) -> None:
        self.skeleton = skeleton
        self.kp, self.kd = gains_per_dof(skeleton, gains)
        for i in range(skeleton.getNumDofs()):
            dof = skeleton.getDof(i)
            dof.setDampingCoefficient(0.0)
            dof.setSpringStiffness(0.0)

    def forces(
        self,
        error: NDArray[np.float64],
        velocity: NDArray[np.float64],
        target_velocity: NDArray[np.float64] | None,
    ) -> NDArray[np.float64]:
        """Joint forces (N·m): ``error`` = ``θd ⊖ θ`` (rad), velocities in rad/s."""
        tau = self.kp * error - self.kd * velocity
        if target_velocity is not None:
            tau += self.kd * target_velocity
        return tau
