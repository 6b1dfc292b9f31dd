"""Playback of arm trajectories: tracking metrics, the via-point sequencer, input checks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from visprim.sim.model import build_adonis
from visprim.sim.playback import joint_errors, play
from visprim.sim.sequencer import build_reference
from visprim.sim.trajectories import minimum_jerk

REACH = np.array([[0.0, 0.3, 0.0, 0.3], [0.4, 1.5, 0.5, 1.3], [1.2, 1.0, -0.3, 0.6]])


@pytest.fixture(scope="module")
def reach_playback():
    times, angles = minimum_jerk(REACH, [0.8, 0.7])
    return play(times, angles)


def test_reach_is_tracked_within_targets(reach_playback) -> None:
    pb = reach_playback
    assert np.all(np.isfinite(pb.q_actual))
    assert pb.rms_error_deg <= 5.0
    assert pb.max_error_deg < 10.0
    assert pb.reached_all and pb.n_reached == pb.n_via
    assert pb.movement_duration == pytest.approx(1.5)
    assert pb.completion_time <= 1.5 * pb.movement_duration
    assert pb.rest_max_error_deg < 3.0  # the other joints stay near rest


def test_playback_arrays_are_consistent(reach_playback) -> None:
    pb = reach_playback
    n = pb.times.shape[0]
    assert pb.q_actual.shape == pb.q_target.shape == (n, 20)
    assert pb.joint_errors_deg.shape == (n, len(pb.joint_names))
    assert np.allclose(np.diff(pb.times), 0.001)
    assert pb.times[-1] == pytest.approx(pb.completion_time)
    assert len(pb.dof_names) == 20 and len(pb.body_names) == pb.frames.shape[1] == 9
    # Frames every 1/25 s, plus the final state.
    assert np.allclose(np.diff(pb.frame_times[:-1]), 0.04)
    assert pb.frame_times[-1] == pytest.approx(pb.times[-1])
    assert pb.hand_path.shape == (pb.frames.shape[0], 3)
    assert pb.hand_via.shape == (pb.n_via, 3)
    # The target path ends where the last via point is, and the hand got there.
    assert np.allclose(pb.hand_reference[-1], pb.hand_via[-1])
    assert np.linalg.norm(pb.hand_path[-1] - pb.hand_via[-1]) < 0.03
    # Via points reached in order, never before their nominal time.
    reach = pb.via_reach_times
    assert np.all(np.diff(reach) > 0) and np.all(reach >= pb.via_times - 1e-9)
    # The reported RMS is the RMS of the stored shoulder and elbow errors.
    arm = [pb.joint_names.index("r_shoulder"), pb.joint_names.index("r_elbow")]
    assert pb.rms_error_deg == pytest.approx(np.sqrt(np.mean(pb.joint_errors_deg[:, arm] ** 2)))


def test_target_is_the_given_trajectory(reach_playback) -> None:
    """The set point equals the input angles at the same times (no waits happened)."""
    pb = reach_playback
    _, skel = build_adonis()
    times, angles = minimum_jerk(REACH, [0.8, 0.7])
    from visprim.sim.sequencer import angles_to_positions

    idx = np.searchsorted(pb.times, times[:-1] - 1e-9)
    expected = angles_to_positions(skel, angles[:-1])
    err = joint_errors(skel, expected, pb.q_target[idx])
    assert np.degrees(err).max() < 1e-6


def test_generated_strokes_are_tracked() -> None:
    datasets = pytest.importorskip("visprim.datasets")
    trials = datasets.imitation_experiment(n_subjects=1, n_stimuli=3, seed=1)
    model = build_adonis()
    for trial in trials:
        pb = play(trial.times, trial.truth.angles, model=model)
        assert np.all(np.isfinite(pb.q_actual)), trial.name
        assert pb.rms_error_deg <= 5.0, (trial.name, pb.summary())
        assert pb.completion_time <= 1.5 * trial.duration, (trial.name, pb.summary())
        assert pb.reached_all, trial.name


def test_tight_vicinity_makes_the_set_point_wait() -> None:
    """A fast stroke and a vicinity smaller than the lag of PD without the inverse-dynamics
    feedforward: the sequencer waits at via points (completion later than the trajectory),
    still reaching each one."""
    times, angles = minimum_jerk(REACH[:2], [0.35])
    loose = play(times, angles, vicinity=math.radians(10.0), feedforward=False)
    tight = play(times, angles, vicinity=math.radians(1.5), timeout=1.0, feedforward=False)
    assert loose.completion_time == pytest.approx(loose.movement_duration, abs=0.002)
    assert tight.reached_all
    assert tight.completion_time > loose.completion_time + 0.01
    assert np.any(tight.via_reach_times > tight.via_times + 0.005)
    # While waiting, the set point sits on a via point: some set points repeat.
    assert np.any(np.all(np.diff(tight.q_target, axis=0) == 0, axis=1))


def test_inverse_dynamics_feedforward_removes_the_lag() -> None:
    times, angles = minimum_jerk(REACH[:2], [0.35])
    plain = play(times, angles, feedforward=False)
    fed = play(times, angles)
    assert fed.rms_error_deg < 0.25 * plain.rms_error_deg
    assert fed.max_error_deg < 1.0 < plain.max_error_deg
    assert fed.reached_all and fed.completion_time == pytest.approx(fed.movement_duration, abs=2e-3)


def test_unreachable_vicinity_times_out() -> None:
    times, angles = minimum_jerk(REACH[:2], [0.5])
    timeout = 0.05
    pb = play(times, angles, vicinity=1e-7, timeout=timeout, via_spacing=0.1)
    assert not pb.reached_all
    assert pb.n_reached < pb.n_via
    missed = pb.n_via - pb.n_reached
    # Each missed via point costs one timeout (to within a couple of steps).
    assert pb.completion_time == pytest.approx(0.5 + missed * timeout, abs=missed * 0.002 + 0.002)


def test_deterministic() -> None:
    times, angles = minimum_jerk(REACH[:2], [0.4])
    a = play(times, angles)
    b = play(times, angles)
    assert np.array_equal(a.q_actual, b.q_actual)
    assert np.array_equal(a.frames, b.frames)


def test_via_points_sampled_every_spacing() -> None:
    _, skel = build_adonis()
    times, angles = minimum_jerk(REACH[:2], [1.0])
    ref = build_reference(skel, times, angles, 0.001, via_spacing=0.25)
    assert ref.via_steps.tolist() == [250, 500, 750, 1000]
    assert ref.positions.shape == (1001, 20)
    # Velocity of the shoulder: central differences of the rotation (child frame).
    sh = slice(6, 9)
    r = Rotation.from_rotvec(ref.positions[:, sh])
    fd = (r[400].inv() * r[402]).as_rotvec() / 0.002
    assert np.allclose(ref.velocities[401, sh], fd, atol=1e-6)


def test_joint_errors_geodesic() -> None:
    _, skel = build_adonis()
    qt = np.zeros((1, 20))
    qa = np.zeros((1, 20))
    qa[0, 6:9] = Rotation.from_euler("xyz", [0.0, 0.0, 10.0], degrees=True).as_rotvec()
    qa[0, 9] = math.radians(-4.0)
    err = np.degrees(joint_errors(skel, qt, qa)[0])
    assert err[2] == pytest.approx(10.0) and err[3] == pytest.approx(4.0)
    assert np.all(np.delete(err, [2, 3]) == 0)


@pytest.mark.parametrize(
    "times, angles, match",
    [
        (np.linspace(0, 1, 10), np.zeros((10, 3)), "angles must have shape"),
        (np.linspace(0, 1, 10), np.zeros((9, 4)), "angles must have shape"),
        (np.array([0.0, 0.5, 0.5, 1.0]), np.zeros((4, 4)), "strictly increasing"),
        (np.array([0.0]), np.zeros((1, 4)), "at least 2"),
        (np.linspace(0, 1, 5), np.array([[0, 0, 0, 0]] * 4 + [[0, np.nan, 0, 0]]), "NaN"),
    ],
)
def test_bad_trajectories_are_rejected(times, angles, match) -> None:
    with pytest.raises(ValueError, match=match):
        play(times, angles)


def test_bad_parameters_are_rejected() -> None:
    times, angles = minimum_jerk(REACH[:2], [0.3])
    with pytest.raises(ValueError, match="vicinity"):
        play(times, angles, vicinity=0.0)
    with pytest.raises(ValueError, match="timeout"):
        play(times, angles, timeout=-1.0)
    with pytest.raises(ValueError, match="render_fps"):
        play(times, angles, render_fps=0.0)
    with pytest.raises(ValueError, match="time step"):
        play(times, angles, dt=0.002, model=build_adonis(0.001))
    with pytest.raises(ValueError, match="durations"):
        minimum_jerk(REACH, [0.5])
