"""The trunk's pose (torso_pose) and MotionClassifier's torso term."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from _motion_data import movements as _data
from visprim.classify import MotionClassifier, torso_pose
from visprim.trial import Trial

SMALL_MODEL = {"n_samples": 20, "n_components": 5, "n_clusters": 4, "n_init": 1}


def _carried(trial: Trial, path: np.ndarray, name: str) -> Trial:
    """The same arm movement with the whole body moved along ``path`` (T, 3) metres."""
    assert trial.joints is not None
    return replace(
        trial,
        markers=trial.markers + path[:, None, :],
        joints=trial.joints + path[:, None, :],
        name=name,
    )


def _hop(trial: Trial) -> Trial:
    """Carried 0.6 m forward while bobbing up twice by 0.15 m."""
    s = np.linspace(0.0, 1.0, trial.n_frames)
    path = np.stack([0.6 * s, np.zeros_like(s), 0.15 * np.sin(2 * np.pi * s) ** 2], axis=1)
    return _carried(trial, path, f"{trial.name}_hop")


def test_pose_follows_the_shoulders_and_the_trunk() -> None:
    (trial, *_), _ = _data(1, seed=3)
    assert trial.joints is not None
    still = torso_pose(trial)
    assert still.shape == (trial.n_frames, 6)
    np.testing.assert_allclose(still[:, :3], 0.0, atol=1e-12)  # the shoulders stay put
    np.testing.assert_allclose(still[:, 3:], np.tile([0.0, 0.0, 1.0], (trial.n_frames, 1)))
    # Wherever the movement starts, the pose is where the shoulders went since then.
    rise = np.zeros((trial.n_frames, 3))
    rise[:, 2] = np.linspace(0.0, 0.2, trial.n_frames)
    lifted = _carried(trial, rise + np.array([5.0, -2.0, 1.0]), "lifted")
    np.testing.assert_allclose(torso_pose(lifted)[:, :3], rise, atol=1e-12)
    # A trunk leaning forward by 0.3 rad about its y axis tips the up axis toward +x.
    c, s = np.cos(0.3), np.sin(0.3)
    lean = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    leaning = replace(trial, body_frame=np.tile(lean, (trial.n_frames, 1, 1)))
    np.testing.assert_allclose(
        torso_pose(leaning)[:, 3:], np.tile([s, 0.0, c], (trial.n_frames, 1))
    )
    # A one-arm trial: its one shoulder.
    right = replace(
        trial, markers=trial.markers[:, :4], joints=trial.joints[:, :3], arms=("right",)
    )
    lifted_right = _carried(right, rise, "lifted_right")
    np.testing.assert_allclose(torso_pose(lifted_right)[:, :3], rise, atol=1e-12)


def test_the_torso_tells_apart_what_the_arms_do_alike() -> None:
    """Two classes with the same arm movements: made standing, or carried by a hop. The arm
    costs cannot tell a movement from its hopped copy; the torso term can, and the inner
    leave-one-group-out gives it a weight."""
    base, _ = _data(3, seed=0)
    train = base + [_hop(t) for t in base]
    y = ["stand"] * len(base) + ["hop"] * len(base)
    groups = [i // 3 for i in range(len(base))] * 2
    new, _ = _data(1, seed=5)
    test = new + [_hop(t) for t in new]
    truth = ["stand"] * len(new) + ["hop"] * len(new)

    arms = MotionClassifier(model_params=SMALL_MODEL, torso=False).fit(train, y, groups=groups)
    assert "torso" not in arms.term_weights_
    d = arms.distances(test)
    n = len(base)
    np.testing.assert_allclose(d[:, :n], d[:, n:], rtol=1e-6, atol=1e-9)

    clf = MotionClassifier(model_params=SMALL_MODEL).fit(train, y, groups=groups)
    assert clf.term_weights_["torso"] > 0
    assert clf.score(test, truth) == 1.0


def test_torso_must_be_a_bool() -> None:
    train, y = _data(2, seed=0)
    with pytest.raises(ValueError, match="torso"):
        MotionClassifier(model_params=SMALL_MODEL, torso="yes").fit(train, y)  # type: ignore[arg-type]
