"""The paper-like preset of the generator (the default): gestures, coarticulation, truth."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.datasets import GESTURES, PRESETS, STROKE_KINDS, imitation_experiment
from visprim.datasets.experiment import stimuli, subjects
from visprim.datasets.gestures import HANG_DEG
from visprim.datasets.imitation import perform, sample_performer
from visprim.ik import arm_angles_corpus

DEG = np.pi / 180
CLEAN = dict(noise=False, skin_offsets=False, drift=False)


@pytest.fixture(scope="module")
def trials():
    return imitation_experiment(3, 20)


def test_default_is_the_paper_preset(trials):
    assert PRESETS[0] == "paper"
    assert [t.meta["preset"] for t in trials] == ["paper"] * len(trials)
    assert len(GESTURES) == 20
    assert {t.meta["stimulus_name"] for t in trials} == {g.name for g in GESTURES}


def test_unknown_preset_is_a_clear_error():
    with pytest.raises(ValueError, match="unknown preset 'easy'; known: paper, strokes"):
        imitation_experiment(1, 1, preset="easy")


def test_truth_is_consistent(trials):
    for t in trials:
        b, labels = t.truth.boundaries, t.truth.labels
        assert labels.size == b.size - 1 >= 2
        assert np.all(np.diff(b) > 0) and b[0] > 0 and b[-1] < t.times[-1]
        assert np.all((labels >= 0) & (labels < len(STROKE_KINDS)))
        assert t.repetitions == t.truth.repetitions >= 1
        assert t.truth.angles.shape == (t.times.size, 4)
    g = GESTURES[[x.name for x in GESTURES].index("wave three times")]
    assert g.repetitions == 3 and len(g.strokes) == 8


def test_gestures_last_three_to_seven_seconds(trials):
    d = np.array([t.duration for t in trials])
    assert 2.5 < np.median(d) < 6.0 and d.max() < 9.0


def test_the_arm_hangs_near_the_singularity(trials):
    beta = np.concatenate([t.truth.angles[:, 1] for t in trials])
    assert 0.15 < np.mean(beta < 20 * DEG) < 0.6  # a good part of the time
    assert beta.min() >= 1 * DEG - 1e-12
    assert beta.max() > 140 * DEG  # and reaches overhead


def test_strokes_blend_without_a_full_stop():
    """At most boundaries between blended strokes the arm still moves, and the four
    angles do not all stop together."""
    moving, staggered, n = 0, 0, 0
    for t in imitation_experiment(2, 20, **CLEAN):
        tt = np.linspace(0, t.duration, 4000)
        from visprim.datasets.experiment import _rng  # the trial's own motion stream

        who = subjects(2)[t.subject]
        motion = perform(stimuli(20)[t.stimulus], who, _rng(0, 1, t.subject, t.stimulus, 0))
        np.testing.assert_allclose(motion.angles(t.times), t.truth.angles)
        v = np.gradient(motion.angles(tt), tt, axis=0)
        speed = np.linalg.norm(v, axis=1)
        for b in t.truth.boundaries[1:-1]:
            i = int(np.searchsorted(tt, b))
            n += 1
            moving += speed[i] > 0.05  # rad/s
            stopped = np.abs(v[i - 20 : i + 20]) < 1e-3
            staggered += not np.any(stopped.all(axis=1))
    assert moving / n > 0.6 and staggered / n > 0.6


def test_subjects_differ():
    subs = subjects(11)
    hang = np.array([s.hang for s in subs])
    assert np.ptp(hang[:, 0]) > 90 * DEG  # direction of the hanging arm
    assert np.all((hang[:, 1] > 7.9 * DEG) & (hang[:, 1] < 15.1 * DEG))
    assert len({round(s.tempo, 3) for s in subs}) == 11
    assert len({round(s.overlap, 3) for s in subs}) == 11


def test_deterministic_and_independent_streams():
    a = imitation_experiment(2, 3, seed=4)
    b = imitation_experiment(2, 3, seed=4)
    c = imitation_experiment(3, 5, seed=4)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x.markers, y.markers)
    by_name = {t.name: t for t in c}
    for x in a:
        np.testing.assert_array_equal(x.markers, by_name[x.name].markers)
    d = imitation_experiment(2, 3, seed=5)
    assert a[0].markers.shape != d[0].markers.shape or not np.allclose(a[0].markers, d[0].markers)


def test_extra_stimuli_are_variants():
    st = stimuli(23)
    assert len(st) == 23 and st[20].name.startswith(GESTURES[0].name)
    hang = [s.target for s in st[20].strokes if s.target == HANG_DEG]
    assert hang == [s.target for s in GESTURES[0].strokes if s.target == HANG_DEG]
    assert len(imitation_experiment(1, 23)) == 23


def test_ik_recovers_the_truth_away_from_the_singularity():
    """Mechanics: without sensor errors, inverse kinematics gives back the true angles
    wherever the arm is away from β ≈ 0 and the elbow is not straight."""
    trials = imitation_experiment(1, 20, **CLEAN)
    est = arm_angles_corpus(trials)
    for t, a in zip(trials, est, strict=True):
        truth = t.truth.angles
        ok = (truth[:, 1] > 10 * DEG) & (truth[:, 1] < 170 * DEG) & (truth[:, 3] > 10 * DEG)
        d = np.angle(np.exp(1j * (a[ok] - truth[ok])))
        assert np.abs(d).max() < 1e-6, t.name


def test_performer_draws_are_fixed_in_number():
    rng = np.random.default_rng(0)
    sample_performer(0, rng)
    after_one = rng.random()
    rng2 = np.random.default_rng(0)
    sample_performer(5, rng2)
    assert rng2.random() == after_one
