"""Segmentation targets on the default generated experiment (11 subjects × 20
stimuli, seed 0, noise and skin offsets on): IK → low-pass (order 10, cutoff 0.25) → SEG-1 /
SEG-2, scored against ``truth.boundaries`` at ±100 ms."""

from __future__ import annotations

import numpy as np
import pytest
from visprim import segment as S
from visprim.datasets import imitation_experiment
from visprim.filtering import lowpass_corpus
from visprim.ik import arm_angles_corpus
from visprim.trial import Trial


@pytest.fixture(scope="module")
def experiment() -> tuple[list[Trial], list[np.ndarray]]:
    trials = imitation_experiment()
    angles = lowpass_corpus(arm_angles_corpus(trials), names=[t.name for t in trials])
    return trials, angles


def truths(trials: list[Trial]) -> list[np.ndarray]:
    return [t.truth.boundaries for t in trials]  # type: ignore[union-attr]


def test_seg2_f1_target(experiment: tuple[list[Trial], list[np.ndarray]]) -> None:
    trials, angles = experiment
    res = S.segment_corpus(
        [t.times for t in trials], angles, "seg2", repetitions=[t.repetitions for t in trials]
    )
    scores = S.corpus_boundary_scores(res.per_trial(), truths(trials), tolerance=0.1)
    assert scores.f1 >= 0.9, scores
    # The tuned threshold honours the paper's rule: every trial yields at least as many
    # segments as its repetitions.
    assert np.all(res.counts() >= [t.repetitions for t in trials])
    # SEG-2 partitions each movement.
    for segs in res.per_trial():
        np.testing.assert_array_equal(segs[1:, 0], segs[:-1, 1])


def test_seg1_precision_target(experiment: tuple[list[Trial], list[np.ndarray]]) -> None:
    """SEG-1 precision >= 0.9 when a true boundary inside a pause stands for the whole pause.

    The generator marks the middle of a pause between strokes (0.08–0.25 s) as the boundary;
    SEG-1 snips where the velocities cross zero, i.e. where the arm stops, at the start of
    the pause. Scored strictly against the midpoints, its precision is ~0.89 (measured 0.890
    at seed 0): the guard below keeps that from regressing.
    """
    trials, angles = experiment
    res = S.segment_corpus([t.times for t in trials], angles, "seg1")
    found = res.per_trial()
    pauses = [S.truth_pause_halfwidths(t) for t in trials]
    assert sum(int(np.count_nonzero(p)) for p in pauses) > 50  # pauses do occur
    aware = S.corpus_boundary_scores(found, truths(trials), truth_halfwidth=pauses)
    assert aware.precision >= 0.9, aware
    strict = S.corpus_boundary_scores(found, truths(trials))
    assert strict.precision >= 0.85, strict
    # SEG-1 does not partition: it finds fewer segments than there are strokes.
    assert res.n_segments < sum(len(b) - 1 for b in truths(trials))
