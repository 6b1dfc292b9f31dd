"""Imitation with a two-arm model: both arms rebuilt and played; the left arm mirrored."""

from __future__ import annotations

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.imitate import human_arm_points, imitate
from visprim.trial import Trial

FLIP = np.array([1.0, -1.0, 1.0])


def _both_arms(t: Trial) -> Trial:
    """The right arm and its mirror image (y -> -y) as the left arm."""
    joints = None
    if t.joints is not None:
        joints = np.concatenate([t.joints, t.joints * FLIP], axis=1)
    return Trial(
        t.times,
        np.concatenate([t.markers, t.markers * FLIP], axis=1),
        joints=joints,
        name=t.name,
        repetitions=t.repetitions,
        arms=("right", "left"),
    )


@pytest.fixture(scope="module")
def result():
    trials = [_both_arms(t) for t in imitation_experiment(2, 4, seed=5)]
    model = PrimitiveModel(n_clusters=5, n_init=2).fit(trials[:-1])
    assert model.arms_ == ("right", "left")
    return imitate(model, trials[-1])


def test_both_arms_are_rebuilt_alike_and_played(result) -> None:
    assert result.human.shape[1] == result.rebuild_angles.shape[1] == 8
    inside = np.isfinite(result.rebuild_angles[:, 0])
    right, left = result.rebuild_angles[inside, :4], result.rebuild_angles[inside, 4:]
    # Mirror-image arms have the same angles; the rebuild keeps that.
    np.testing.assert_allclose(left, right, atol=1e-6)
    per = result.metrics["rebuild_vs_human_rms_deg"]
    assert {"right_gamma", "left_elbow", "overall"} <= set(per)
    a = result.metrics["adonis"]
    joint = result.metrics["rebuild_vs_human_joint_rms_deg"]["overall"]
    assert a["vs_human_joint_rms_deg"]["overall"] <= joint + 2.0
    adonis = result.adonis_angles[result.covered]
    np.testing.assert_allclose(adonis[:, 7], adonis[:, 3], atol=np.radians(1.0))
    names = list(result.playback.joint_names)
    left_err = result.playback.joint_errors_deg[:, names.index("l_elbow")]
    assert left_err.max() < 5.0


def test_human_points_of_both_arms(result) -> None:
    pts = human_arm_points(result.trial)
    assert pts.shape[1:] == (8, 3)
    np.testing.assert_allclose(pts[:, 4:], pts[:, :4] * FLIP, atol=1e-9)


def test_files_and_video_frame_for_two_arms(result, tmp_path) -> None:
    from visprim.imitate import write_imitation

    paths = write_imitation(result, tmp_path, video="v.gif", size=(96, 96))
    header = paths["csv"].read_text().splitlines()[0].split(",")
    assert "human_left_elbow_rad" in header and "adonis_right_gamma_rad" in header
    assert paths["video"].stat().st_size > 0
