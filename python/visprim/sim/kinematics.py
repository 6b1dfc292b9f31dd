"""Forward kinematics of a DART skeleton in numpy, for many configurations at once.

A body's world transform is ``T_parent · T_parent→joint · J(q) · T_child→joint⁻¹``, where
``J`` is the joint's motion: identity for a weld joint, the rotation of the exponential
coordinates for a ball joint (DART's ``BallJoint`` positions are rotation vectors), the
rotation by ``q`` about the axis for a revolute joint. :class:`BatchKinematics` reads the
fixed parts from the skeleton once; :meth:`BatchKinematics.transforms` then evaluates every
body for (N, n_dofs) joint positions in one vectorised pass. The playback
(:mod:`visprim.sim.playback`) uses it to turn the joint positions recorded at the frame steps
into body transforms after the simulation, instead of asking DART for each body at every
frame inside the control loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import dartpy as dart
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

__all__ = ["BatchKinematics"]


@dataclass(frozen=True)
class _Body:
    parent: int  # index of the parent body, -1 for the root (its parent frame is the world)
    parent_to_joint: NDArray[np.float64]  # (4, 4)
    joint_to_child: NDArray[np.float64]  # (4, 4), the inverse of the child-to-joint transform
    kind: str  # "weld", "ball" or "revolute"
    dof: int  # index of the joint's first DOF in the skeleton (-1 for a weld)
    axis: NDArray[np.float64] | None  # revolute axis (joint frame)


class BatchKinematics:
    """Forward kinematics of ``skeleton`` (weld, ball and revolute joints) in numpy.

    Raises ``ValueError`` for a skeleton with any other joint type.
    """

    def __init__(self, skeleton: dart.dynamics.Skeleton) -> None:
        self.n_dofs = int(skeleton.getNumDofs())
        self.body_names = tuple(b.getName() for b in skeleton.getBodyNodes())
        bodies = []
        for i, body in enumerate(skeleton.getBodyNodes()):
            joint = body.getParentJoint()
            parent = body.getParentBodyNode()
            kind = {"WeldJoint": "weld", "BallJoint": "ball", "RevoluteJoint": "revolute"}.get(
                joint.getType()
            )
            if kind is None:
                raise ValueError(
                    f"BatchKinematics: joint {joint.getName()!r} is a {joint.getType()}; only "
                    "weld, ball and revolute joints are supported"
                )
            p = -1 if parent is None else int(parent.getIndexInSkeleton())
            if p >= i:
                raise ValueError(f"BatchKinematics: body {body.getName()!r} precedes its parent")
            bodies.append(
                _Body(
                    parent=p,
                    parent_to_joint=np.asarray(
                        joint.getTransformFromParentBodyNode().matrix(), dtype=np.float64
                    ),
                    joint_to_child=np.linalg.inv(
                        np.asarray(joint.getTransformFromChildBodyNode().matrix(), dtype=np.float64)
                    ),
                    kind=kind,
                    dof=int(joint.getIndexInSkeleton(0)) if joint.getNumDofs() else -1,
                    axis=np.asarray(joint.getAxis(), dtype=np.float64)
                    if kind == "revolute"
                    else None,
                )
            )
        self._bodies = bodies

    def transforms(self, positions: ArrayLike) -> NDArray[np.float64]:
        """World transforms (N, n_bodies, 4, 4) of every body (skeleton order) for joint
        positions (N, n_dofs) in radians (ball joints: rotation vectors)."""
        q = np.atleast_2d(np.asarray(positions, dtype=np.float64))
        if q.ndim != 2 or q.shape[1] != self.n_dofs:
            raise ValueError(
                f"BatchKinematics.transforms: positions must be (N, {self.n_dofs}), got {q.shape}"
            )
        n = q.shape[0]
        out = np.empty((n, len(self._bodies), 4, 4))
        for i, b in enumerate(self._bodies):
            base = b.parent_to_joint if b.parent < 0 else out[:, b.parent] @ b.parent_to_joint
            if b.kind == "weld":
                out[:, i] = base @ b.joint_to_child
                continue
            if b.kind == "ball":
                rotvec = q[:, b.dof : b.dof + 3]
            else:
                assert b.axis is not None
                rotvec = q[:, b.dof : b.dof + 1] * b.axis
            motion = np.zeros((n, 4, 4))
            motion[:, :3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
            motion[:, 3, 3] = 1.0
            out[:, i] = base @ motion @ b.joint_to_child
        return out
