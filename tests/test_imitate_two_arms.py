"""Imitation with a two-arm model: both arms rebuilt and played; the left arm mirrored."""

from __future__ import annotations

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.features import from_angles
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


@pytest.fixture(scope="module")
def one_arm_both():
    """A one-arm model learned from both arms of movements whose arms differ (the left arm of
    one trial is the right arm of another, mirrored), imitating a two-arm movement."""
    from visprim.trial import split_arms

    ones = imitation_experiment(2, 4, seed=6)
    both = [
        Trial(
            a.times[: min(a.n_frames, b.n_frames)],
            np.concatenate(
                [a.markers[: min(a.n_frames, b.n_frames)], b.markers[: a.n_frames] * FLIP], axis=1
            )[: min(a.n_frames, b.n_frames)],
            name=f"{a.name}+{b.name}",
            arms=("right", "left"),
        )
        for a, b in zip(ones, ones[1:] + ones[:1], strict=True)
    ]
    model = PrimitiveModel(n_clusters=5, n_init=2).fit(split_arms(both[:-1]))
    assert model.arms_ == ("right",)
    return model, both[-1]


def test_a_one_arm_model_imitates_each_arm_on_its_own(one_arm_both) -> None:
    """Played together, each arm is what imitating that arm alone gives: the right arm, and
    the left arm mirrored into a right arm (the left's angles are in the mirror convention)."""
    from visprim.trial import split_arms

    model, trial = one_arm_both
    res = imitate(model, trial)
    assert res.human.shape[1] == res.rebuild_angles.shape[1] == 8
    assert res.segment_arm is not None and set(res.segment_arm.tolist()) == {0, 1}
    assert res.metrics["arms_imitated"] == "one by one"
    assert {s["arm"] for s in res.metrics["segments"]} == {"right", "left"}
    assert "right arm" in res.summary() and "left arm" in res.summary()
    for side, arm in enumerate(split_arms(trial)):
        alone = imitate(model, arm, play=False)
        cols = slice(4 * side, 4 * side + 4)
        np.testing.assert_allclose(res.human[:, cols], alone.human, atol=1e-12)
        np.testing.assert_array_equal(res.primitives[res.segment_arm == side], alone.primitives)
        # The same bones, up to 0.3°: inverse kinematics interpolates γ and α across the
        # singular cone along the evaluation grid, which differs (one grid for both arms).
        own = np.isfinite(alone.rebuild_angles[:, 0])
        np.testing.assert_allclose(
            from_angles(res.rebuild_angles[own, cols], "directions"),
            from_angles(alone.rebuild_angles[own], "directions"),
            atol=5e-3,
        )
    # Adonis follows both arms.
    a = res.metrics["adonis"]
    assert a["vs_rebuild_joint_rms_deg"]["overall"] < 2.0
    played = np.isfinite(res.adonis_angles[:, 0])
    assert played.sum() > 0.9 * np.isfinite(res.rebuild_angles[:, 0]).sum()
