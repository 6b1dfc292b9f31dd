"""Whole-movement classifiers (MotionClassifier, DTWClassifier) on synthetic arm movements."""

from __future__ import annotations

import numpy as np
import pytest
from _motion_data import movements as _data
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from visprim.classify import (
    DTWClassifier,
    MotionClassifier,
    arm_directions,
    primitive_coordinates,
    reconstructed_directions,
    segment_descriptions,
)
from visprim.model import PrimitiveModel
from visprim.trial import Trial

SMALL_MODEL = {"n_samples": 20, "n_components": 5, "n_clusters": 4, "n_init": 1}


def test_motion_classifier_separates_distinct_movements() -> None:
    train, y = _data(4, seed=0)
    test, truth = _data(2, seed=1)
    clf = MotionClassifier(model_params=SMALL_MODEL).fit(train, y)
    assert list(clf.classes_) == ["raise", "sweep", "wave"]
    assert clf.window_seconds_ > 0
    assert clf.score(test, truth) == 1.0
    proba = clf.predict_proba(test)
    assert proba.shape == (6, 3)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0)
    # Deterministic, and clone gives an unfitted copy with the same parameters.
    again = clone(clf)
    assert again.get_params() == clf.get_params()
    assert not hasattr(again, "model_")
    np.testing.assert_array_equal(again.fit(train, y).predict(test), clf.predict(test))


@pytest.mark.parametrize("method", ["coordinates", "segments", "histogram"])
def test_other_methods_run_and_beat_chance(method: str) -> None:
    train, y = _data(4, seed=0)
    test, truth = _data(2, seed=1)
    clf = MotionClassifier(model_params=SMALL_MODEL, method=method).fit(train, y)
    assert clf.predict(test).shape == (6,)
    assert clf.score(test, truth) > 1 / 3


def test_dtw_baseline_and_feature_shapes() -> None:
    train, y = _data(3, seed=0)
    test, truth = _data(2, seed=2)
    base = DTWClassifier(band=0.2).fit(train, y)
    assert base.score(test, truth) == 1.0
    d = base.distances(test)
    assert d.shape == (6, 9) and np.all(d >= 0)
    trial = train[0]
    dirs = arm_directions(trial)
    assert dirs.shape == (trial.n_frames, 12)
    np.testing.assert_allclose(np.linalg.norm(dirs.reshape(-1, 4, 3), axis=2), 1.0)
    clf = MotionClassifier(model_params=SMALL_MODEL).fit(train, y)
    coords = primitive_coordinates(clf.model_, [trial], clf.window_seconds_)[0]
    # f = 5 projections and the window's mean posture (12 channels, two arms).
    assert coords.shape == (trial.n_frames, 5 + 12)
    paper = MotionClassifier(model_params={**SMALL_MODEL, "offsets": "turns"}).fit(train, y)
    coords = primitive_coordinates(paper.model_, [trial], paper.window_seconds_)[0]
    assert coords.shape == (trial.n_frames, 5)
    rec = reconstructed_directions(clf.model_, [trial], clf.window_seconds_)[0]
    assert rec.shape == dirs.shape
    np.testing.assert_allclose(np.linalg.norm(rec.reshape(-1, 4, 3), axis=2), 1.0)
    # The basis rebuilds this training movement's right upper arm closely (same axes as
    # arm_directions up to the shoulder frame's sign flip of y and z).
    flip = np.array([1.0, -1.0, -1.0])
    err = np.linalg.norm(rec[:, :3] * flip - dirs[:, :3], axis=1)
    assert np.median(err) < 0.1


def test_frame_step_keeps_every_step_th_frame_of_the_descriptions() -> None:
    train, y = _data(2, seed=0)
    clf = MotionClassifier(model_params=SMALL_MODEL).fit(train, y)
    window = clf.window_seconds_
    for describe in (primitive_coordinates, reconstructed_directions):
        every = describe(clf.model_, train[:3], window)
        third = describe(clf.model_, train[:3], window, 3)
        for a, b in zip(every, third, strict=True):
            np.testing.assert_allclose(b, a[::3], atol=1e-12)
    with pytest.raises(ValueError, match="step"):
        MotionClassifier(step=0).fit(train, y)


def test_segment_descriptions_keep_the_distance_of_absolute_vectors() -> None:
    """[p, √n o] of a shape-and-posture model: with every eigenvector kept, the distance
    between two segments' descriptions is the distance between their absolute vectors."""
    train, _ = _data(3, seed=0)
    params = {"n_samples": 10, "n_clusters": 3, "n_init": 1}
    model = PrimitiveModel(n_components=60, **params).fit(train)
    corpus = model.prepare(train[:2], tune_seg2=False)
    sv = model.vectorize(corpus)
    desc = segment_descriptions(model, sv)
    absolute = PrimitiveModel(offsets="turns", n_components=5, **params)
    raw = absolute.vectorize(corpus).vectors  # directions have no whole turns: raw curves
    assert desc.shape == (len(sv), 60 + 12)
    for i, j in ((0, 1), (0, len(sv) - 1)):
        np.testing.assert_allclose(
            np.linalg.norm(desc[i] - desc[j]), np.linalg.norm(raw[i] - raw[j]), rtol=1e-9
        )


def test_errors() -> None:
    train, y = _data(2, seed=0)
    with pytest.raises(NotFittedError):
        MotionClassifier().predict(train)
    with pytest.raises(NotFittedError):
        DTWClassifier().predict(train)
    with pytest.raises(ValueError, match="method"):
        MotionClassifier(method="svm").fit(train, y)
    with pytest.raises(ValueError, match="labels"):
        DTWClassifier().fit(train, y[:-1])
    with pytest.raises(ValueError, match="two different labels"):
        DTWClassifier().fit(train[:2], ["a", "a"])
    with pytest.raises(ValueError, match="band"):
        DTWClassifier(band=2.0).fit(train, y)
    fitted = DTWClassifier().fit(train, y)
    right_only = Trial(times=train[0].times, markers=train[0].markers[:, :4])
    with pytest.raises(ValueError, match="arms"):
        fitted.predict([right_only])
    with pytest.raises(ValueError, match="different arms"):
        DTWClassifier().fit([train[0], right_only], ["a", "b"])
    with pytest.raises(TypeError, match="expected visprim.Trial"):
        fitted.predict([1, 2])  # type: ignore[list-item]
