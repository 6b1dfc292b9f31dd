"""The costs MotionClassifier sums (velocity, duration) and how it weighs them."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from _motion_data import movements as _data
from visprim import params
from visprim.classify import (
    COMBINED_TERMS,
    MotionClassifier,
    arm_directions,
    arm_velocities,
    duration_costs,
)
from visprim.trial import Trial

SMALL_MODEL = {"n_samples": 20, "n_components": 5, "n_clusters": 4, "n_init": 1}


def _slowed(trial: Trial, factor: float) -> Trial:
    """The same path, ``factor`` times slower, sampled at the same frame period."""
    n = int(round((trial.n_frames - 1) * factor)) + 1
    src = np.linspace(0.0, trial.n_frames - 1, n)
    grid = np.arange(trial.n_frames)

    def interp(a: np.ndarray) -> np.ndarray:
        flat = a.reshape(a.shape[0], -1)
        out = np.stack([np.interp(src, grid, flat[:, j]) for j in range(flat.shape[1])], 1)
        return out.reshape((n, *a.shape[1:]))

    assert trial.joints is not None
    return replace(
        trial,
        times=trial.times[0] + np.arange(n) * trial.frame_period,
        markers=interp(trial.markers),
        joints=interp(trial.joints),
        name=f"{trial.name}_slow",
    )


def test_velocity_and_duration_scale_with_the_tempo() -> None:
    (trial, *_), _ = _data(1, seed=3)
    slow = replace(trial, times=trial.times * 2.0)  # the same frames, twice as long
    v, v_slow = arm_velocities(trial), arm_velocities(slow)
    assert v.shape == (trial.n_frames - 1, 12)
    np.testing.assert_allclose(v_slow, v / 2.0, rtol=1e-12, atol=1e-12)
    # Summed back, the velocities rebuild the directions.
    d = arm_directions(trial)
    rebuilt = d[0] + np.cumsum(v * np.diff(trial.times)[:, None], axis=0)
    np.testing.assert_allclose(rebuilt, d[1:], atol=1e-9)
    c = duration_costs([trial, slow])
    np.testing.assert_allclose(c, [[0.0, np.log(2.0)], [np.log(2.0), 0.0]], atol=1e-9)


def test_defaults_are_the_declared_ones() -> None:
    clf = MotionClassifier()
    for p in params.CLASSIFIER_PARAMETERS:
        assert getattr(clf, p.name) == p.default
    with pytest.raises(ValueError, match="term_weights"):
        train, y = _data(2, seed=0)
        MotionClassifier(model_params=SMALL_MODEL, term_weights=(-1.0,)).fit(train, y)


def test_zero_weights_leave_the_primitive_path_alone() -> None:
    train, y = _data(3, seed=0)
    test, _ = _data(1, seed=1)
    only = MotionClassifier(model_params=SMALL_MODEL, term_weights=(0.0,)).fit(train, y)
    terms = (*COMBINED_TERMS, "torso")
    assert only.term_weights_ == dict.fromkeys(terms, 0.0) | {"coordinates": 1.0}
    path = MotionClassifier(model_params=SMALL_MODEL, method="coordinates").fit(train, y)
    np.testing.assert_allclose(
        only.distances(test) * only.scales_["coordinates"], path.distances(test), rtol=1e-12
    )


def test_weights_are_chosen_on_the_training_groups() -> None:
    """Two classes that differ only in tempo: the same raises, waves and sweeps, played at
    their own speed ("brisk") or 1.8 times slower ("slow"). Only the velocity and duration
    costs can tell them apart, and the inner leave-one-group-out must find that."""
    base, _ = _data(3, seed=0)
    train = base + [_slowed(t, 1.8) for t in base]
    y = ["brisk"] * len(base) + ["slow"] * len(base)
    groups = [i // 3 for i in range(len(base))] * 2  # three groups, each with every kind
    clf = MotionClassifier(model_params=SMALL_MODEL).fit(train, y, groups=groups)
    assert len(clf.inner_accuracy_) == len(params.TERM_WEIGHTS) ** 4
    chosen = tuple(clf.term_weights_[t] for t in (*COMBINED_TERMS[1:], "torso"))
    assert clf.inner_accuracy_[chosen] == max(clf.inner_accuracy_.values()) == 1.0
    assert clf.term_weights_["velocity"] + clf.term_weights_["duration"] > 0
    new, _ = _data(1, seed=5)
    test = new + [_slowed(t, 1.8) for t in new]
    assert clf.score(test, ["brisk"] * 3 + ["slow"] * 3) == 1.0
