"""Joint trajectories for other robots' tools: the URDF's joints, CSV and JSON.

A :class:`JointTrajectory` holds, for the joints of ``visprim export-robot``'s URDF in file
order (:func:`visprim.sim.urdf.urdf_joint_names`), the time from the start (s), positions
(rad) and velocities (rad/s) at each point — the fields of a ROS
``trajectory_msgs/JointTrajectory``:

JSON (:meth:`JointTrajectory.to_json`)::

    {"joint_names": ["waist_x", ...],
     "points": [{"positions": [...], "velocities": [...],
                 "time_from_start": {"sec": 0, "nanosec": 34000000}}, ...],
     "units": {"time_from_start": "s", "positions": "rad", "velocities": "rad/s"},
     "robot": "adonis", "description": "..."}

so that ``msg.joint_names = d["joint_names"]`` and one ``JointTrajectoryPoint(**p)`` per
point (with ``Duration(**p["time_from_start"])``) fill the message without guessing.

CSV (:meth:`JointTrajectory.to_csv`): one row per point; columns ``time_from_start_s``,
then ``position:<joint>`` (rad) for every joint in the same order, then ``velocity:<joint>``
(rad/s).

Positions of the ball joints are the URDF's X-Z-Y Euler angles (unwrapped in time);
velocities are their central differences over ±0.1 ms of the source trajectory.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass
from pathlib import Path

import dartpy as dart
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from visprim.atomic import write_text
from visprim.sim.model import LINKS, build_skeleton
from visprim.sim.sequencer import angles_to_positions
from visprim.sim.urdf import BALL_EULER, urdf_joint_names

#: Half-step (s) of the central differences giving the velocities.
VELOCITY_STEP_S = 1e-4


@dataclass(frozen=True)
class JointTrajectory:
    """Joint names (URDF order), times (P,) s, positions and velocities (P, J) rad, rad/s."""

    joint_names: tuple[str, ...]
    times: NDArray[np.float64]
    positions: NDArray[np.float64]
    velocities: NDArray[np.float64]
    description: str = ""

    def to_dict(self) -> dict:
        points = []
        for t, q, v in zip(self.times, self.positions, self.velocities, strict=True):
            ns = int(round(float(t) * 1e9))
            points.append(
                {
                    "positions": [float(x) for x in q],
                    "velocities": [float(x) for x in v],
                    "time_from_start": {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000},
                }
            )
        return {
            "joint_names": list(self.joint_names),
            "points": points,
            "units": {"time_from_start": "s", "positions": "rad", "velocities": "rad/s"},
            "robot": "adonis",
            "description": self.description,
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=1) + "\n"

    def to_csv(self) -> str:
        from visprim.csvfile import writer

        buf = io.StringIO()
        w = writer(buf)
        w.writerow(
            ["time_from_start_s"]
            + [f"position:{n}" for n in self.joint_names]
            + [f"velocity:{n}" for n in self.joint_names]
        )
        for t, q, v in zip(self.times, self.positions, self.velocities, strict=True):
            w.writerow([f"{t:.6f}"] + [f"{x:.9g}" for x in q] + [f"{x:.9g}" for x in v])
        return buf.getvalue()

    def write(self, stem: str | Path) -> tuple[Path, Path]:
        """Write ``stem.json`` and ``stem.csv`` atomically; returns both paths."""
        base = Path(stem)
        base.parent.mkdir(parents=True, exist_ok=True)
        js, cs = base.with_suffix(".json"), base.with_suffix(".csv")
        write_text(js, self.to_json())
        write_text(cs, self.to_csv())
        return js, cs


_SKELETON: dart.dynamics.Skeleton | None = None


def _skeleton() -> dart.dynamics.Skeleton:
    global _SKELETON
    if _SKELETON is None:
        _SKELETON = build_skeleton(LINKS)
    return _SKELETON


def urdf_positions(
    q: ArrayLike, skeleton: dart.dynamics.Skeleton | None = None
) -> NDArray[np.float64]:
    """URDF joint positions (T, J) rad from DART joint positions (T, n_dofs) of the same
    link table (ball joints: rotation vectors → X-Z-Y Euler angles, unwrapped in time)."""
    skel = skeleton or _skeleton()
    qa = np.atleast_2d(np.asarray(q, dtype=np.float64))
    cols: list[NDArray[np.float64]] = []
    for link in LINKS:
        if link.joint not in ("ball", "revolute"):
            continue
        joint = skel.getJoint(link.joint_name)
        start = joint.getIndexInSkeleton(0)
        if link.joint == "revolute":
            cols.append(qa[:, start : start + 1])
        else:
            euler = Rotation.from_rotvec(qa[:, start : start + 3]).as_euler(BALL_EULER)
            cols.append(np.unwrap(euler, axis=0))
    return np.concatenate(cols, axis=1)


def arm_trajectory(
    times: ArrayLike,
    angles: ArrayLike,
    velocities: ArrayLike,
    description: str = "",
) -> JointTrajectory:
    """The URDF joint trajectory of arm angles (T, 4) rad (right arm; (T, 8): both, see
    :func:`visprim.sim.sequencer.angles_to_positions`) with their rates (rad/s) at ``times``
    (s; the first becomes time 0). Every other joint stays at rest."""
    t = np.asarray(times, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    v = np.asarray(velocities, dtype=np.float64)
    if t.ndim != 1 or a.shape not in ((t.shape[0], 4), (t.shape[0], 8)) or v.shape != a.shape:
        raise ValueError(
            f"arm_trajectory: need times (T,), angles and velocities (T, 4 or 8); got {t.shape}, "
            f"{a.shape}, {v.shape}"
        )
    skel = _skeleton()
    h = VELOCITY_STEP_S
    pos = urdf_positions(angles_to_positions(skel, a), skel)
    plus = urdf_positions(angles_to_positions(skel, a + h * v), skel)
    minus = urdf_positions(angles_to_positions(skel, a - h * v), skel)
    # Keep the ±h samples on the branch of the centre sample.
    plus += 2 * np.pi * np.round((pos - plus) / (2 * np.pi))
    minus += 2 * np.pi * np.round((pos - minus) / (2 * np.pi))
    return JointTrajectory(
        tuple(urdf_joint_names()), t - t[0], pos, (plus - minus) / (2 * h), description
    )


def primitive_trajectory(model: object, k: int, n_points: int | None = None) -> JointTrajectory:
    """Primitive ``k`` of a model as a URDF joint trajectory over its mean duration."""
    from scipy.interpolate import CubicSpline

    from visprim.sim.showcase import primitive_trajectory as angles_of

    t, a = angles_of(model, k)  # type: ignore[arg-type]
    spline = CubicSpline(t, a, axis=0)
    grid = t if n_points is None else np.linspace(t[0], t[-1], int(n_points))
    return arm_trajectory(grid, spline(grid), spline(grid, 1), f"primitive {k}")
