"""Two-arm trajectories on Adonis: the left arm is the mirror image of the right."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.sim import build_adonis, play
from visprim.sim.model import HAND_POINT
from visprim.sim.sequencer import angles_to_positions, build_reference, positions_to_angles
from visprim.sim.trajectories import minimum_jerk


@pytest.fixture(scope="module")
def skel():
    return build_adonis()[1]


def _hand(skel, side: str, q: np.ndarray) -> np.ndarray:
    skel.setPositions(q)
    tf = skel.getBodyNode(f"{side}_hand").getWorldTransform()
    return tf.rotation() @ np.asarray(HAND_POINT) + tf.translation()


def test_same_angles_put_the_left_hand_at_the_mirror_image(skel) -> None:
    rng = np.random.default_rng(5)
    for _ in range(5):
        a = np.array(
            [rng.uniform(-2, 2), rng.uniform(0.2, 2.8), rng.uniform(-2, 2), rng.uniform(0, 2)]
        )
        q = angles_to_positions(skel, np.concatenate([a, a])[None])[0]
        right, left = _hand(skel, "r", q), _hand(skel, "l", q)
        np.testing.assert_allclose(left, right * np.array([1.0, -1.0, 1.0]), atol=1e-12)
        back = positions_to_angles(skel, q[None], n_arms=2)[0]
        np.testing.assert_allclose(back, np.concatenate([a, a]), atol=1e-9)


def test_left_velocities_are_the_derivative_of_the_positions(skel) -> None:
    t, a = minimum_jerk(np.array([[0.0, 0.4, 0.1, 0.3, 0.2, 0.5, -0.2, 0.4],
                                  [0.6, 1.5, 0.4, 1.3, -0.3, 1.2, 0.5, 1.0]]), [0.5])  # fmt: skip
    ref = build_reference(skel, t, a, 0.001)
    k = 250
    # Finite difference of the left shoulder rotation vs its body angular velocity.
    from scipy.spatial.transform import Rotation

    sh = slice(skel.getJoint("l_shoulder").getIndexInSkeleton(0), None)
    r0 = Rotation.from_rotvec(ref.positions[k - 1, sh][:3])
    r1 = Rotation.from_rotvec(ref.positions[k + 1, sh][:3])
    omega_fd = (r0.inv() * r1).as_rotvec() / 0.002
    np.testing.assert_allclose(ref.velocities[k, sh][:3], omega_fd, atol=1e-3)


def test_two_arm_playback_tracks_both_arms() -> None:
    post = np.array(
        [[0.0, 0.3, 0.0, 0.3, 0.0, 0.3, 0.0, 0.3], [0.5, 1.4, 0.3, 1.2, 0.3, 1.0, -0.2, 0.8]]
    )
    pb = play(*minimum_jerk(post, [0.6]), render_fps=10.0)
    names = list(pb.joint_names)
    assert pb.reached_all and pb.rms_error_deg < 3.0
    assert pb.joint_errors_deg[:, names.index("l_shoulder")].max() < 5.0
    # The left arm did move (it is not simply held at rest), to its own target.
    skel = build_adonis()[1]
    lsh = slice(skel.getJoint("l_shoulder").getIndexInSkeleton(0), None)
    moved = pb.q_actual[-1, lsh][:3] - pb.q_actual[0, lsh][:3]
    assert np.abs(moved).max() > 0.3
    target = angles_to_positions(skel, post[-1:])[0, lsh][:3]
    np.testing.assert_allclose(pb.q_actual[-1, lsh][:3], target, atol=0.06)
