"""One-arm trials of a two-arm trial, the left arm mirrored into a right arm."""

from __future__ import annotations

import numpy as np
import pytest
from _motion_data import PERIOD, _points, _two_arms
from visprim.arm import rot_z
from visprim.ik import arm_angles
from visprim.trial import Trial, split_arms


def _angles(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    s = np.linspace(0.0, 1.0, n)
    a = np.empty((n, 4))
    a[:, 0] = 0.3 + 0.8 * s
    a[:, 1] = 0.6 + 0.7 * np.sin(np.pi * s)
    a[:, 2] = 0.2 * np.cos(2 * np.pi * s)
    a[:, 3] = 0.4 + 0.6 * s
    return a + rng.normal(0, 0.01, a.shape)


def test_the_left_arm_becomes_the_right_arm_of_its_angles() -> None:
    right, left = _angles(60, 0), _angles(60, 1)[::-1].copy()
    trial = _two_arms(right, left, "m")
    r, mirrored = split_arms(trial)
    assert (r.arms, mirrored.arms) == (("right",), ("right",))
    assert (r.name, mirrored.name) == ("m_right", "m_left")
    assert mirrored.meta["arm"] == "left" and mirrored.truth is None
    np.testing.assert_array_equal(r.markers, trial.markers[:, :4])
    # The fixture put the left arm at the mirror image of a right arm with ``left``'s
    # angles, its shoulder 0.4 m to the left: mirrored back, it is that right arm 0.4 m
    # to the right of the right shoulder's frame origin.
    markers, joints = _points(left, left=False)
    np.testing.assert_allclose(mirrored.markers, markers - [0.0, 0.4, 0.0], atol=1e-12)
    assert mirrored.joints is not None
    np.testing.assert_allclose(mirrored.joints, joints - [0.0, 0.4, 0.0], atol=1e-12)
    np.testing.assert_allclose(arm_angles(mirrored), left, atol=1e-6)
    np.testing.assert_allclose(arm_angles(r), right, atol=1e-6)


def test_a_turning_torso_is_mirrored_in_its_own_frame() -> None:
    right, left = _angles(50, 2), _angles(50, 3)
    trial = _two_arms(right, left, "turning")
    turn = rot_z(np.linspace(0.0, 1.5, trial.n_frames))  # the torso turns 86° about z
    assert trial.joints is not None
    turned = Trial(
        times=trial.times,
        markers=np.einsum("tij,tmj->tmi", turn, trial.markers),
        joints=np.einsum("tij,tmj->tmi", turn, trial.joints),
        body_frame=turn,
        arms=("right", "left"),
    )
    _, mirrored = split_arms(turned)
    np.testing.assert_allclose(arm_angles(mirrored), left, atol=1e-6)
    np.testing.assert_allclose(arm_angles(turned)[:, 4:], left, atol=1e-6)


def test_one_arm_trials_pass_through() -> None:
    markers, joints = _points(_angles(20, 4), left=False)
    one = Trial(times=np.arange(20) * PERIOD, markers=markers, joints=joints)
    two = _two_arms(_angles(20, 5), _angles(20, 6), "two")
    out = split_arms([one, two])
    assert len(out) == 3 and out[0] is one
    assert split_arms(one) == [one]


@pytest.mark.parametrize("folder", ["hdm05_cut_amc", "bandai_namco_ds2"])
def test_split_reads_like_a_mirrored_left_arm(shared_data, folder) -> None:
    """On real recordings the mirrored left arm is the one ``read(..., "left",
    mirror=True)`` gives (the reader mirrors points before building the trial)."""
    from visprim.io import read

    path = sorted(p for p in (shared_data / folder).iterdir() if p.suffix in (".amc", ".bvh"))[0]
    both = read(path, "both", resample=PERIOD)
    left = read(path, "left", mirror=True, resample=PERIOD)
    assert isinstance(both, Trial) and isinstance(left, Trial)
    _, mirrored = split_arms(both)
    np.testing.assert_allclose(arm_angles(mirrored), arm_angles(left), atol=1e-9)
    np.testing.assert_allclose(arm_angles(mirrored), arm_angles(both)[:, 4:], atol=1e-9)
