"""The paper's servo: explicit PD towards one via point at a time, switching in the vicinity."""

from __future__ import annotations

import math

import numpy as np
import pytest
from visprim.sim.playback import SimulationDiverged, play
from visprim.sim.trajectories import minimum_jerk

POSTURES = np.array([[0.0, 0.3, 0.0, 0.3], [0.5, 1.2, 0.3, 1.2]])


@pytest.fixture(scope="module")
def reach():
    return minimum_jerk(POSTURES, [0.8])


def test_paper_servo_reaches_every_via_point_at_a_small_step(reach) -> None:
    pb = play(*reach, servo="paper", dt=1e-4, render_fps=10.0)
    assert pb.reached_all and pb.n_via == 8
    # It switches as soon as it is near, so it need not keep the movement's timing, but it
    # ends within the vicinity of the final posture.
    final = pb.joint_errors_deg[-1]
    assert final.max() <= 3.0 + 1e-9
    np.testing.assert_allclose(pb.q_actual[-1], pb.q_target[-1], atol=math.radians(3.0))
    # Reach times increase, and the set point is always a via point.
    assert np.all(np.diff(pb.via_reach_times) > 0)
    via_positions = {tuple(np.round(q, 12)) for q in pb.q_target}
    assert len(via_positions) <= pb.n_via + 1


def test_paper_servo_diverges_at_1ms_with_the_default_gains(reach) -> None:
    # Explicit damping kd dt above twice the upper arm's axial inertia is unstable; the
    # stable PD is not (same gains, same step).
    with pytest.raises(SimulationDiverged, match="smaller time step"):
        play(*reach, servo="paper", dt=1e-3)
    assert play(*reach, servo="stable", dt=1e-3).reached_all


def test_unknown_servo_is_refused(reach) -> None:
    with pytest.raises(ValueError, match="servo"):
        play(*reach, servo="pid")
